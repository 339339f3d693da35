#!/usr/bin/env bash
# dispel and the MCAP reference libraries, each reading what the other wrote (ctest
# rosbag2_interop):
#   1. files written by @mcap/core with ROS 2 messages serialised by @foxglove/rosmsg2-serialization
#      (every chunk compression, many small chunks, big-endian scans) are read by dispel and copied
#      unchanged: @mcap/core validates the copy (records, CRCs, indexes, summary) and its messages
#      decode to the same field values;
#   2. ROS 2 -> ROS 1 -> ROS 2 keeps the scans and transforms field for field;
#   3. `dispel filter` on the shipped ROS 1 recording and on its MCAP conversion gives the same
#      filtered scans and labels, and the MCAP output is valid; its messages, and the simulator's
#      (step 4), serialised again by rosmsg2-serialization from their decoded values are the same
#      bytes: dispel's CDR encoder, which dispel-ros2 publishes with, writes what it writes;
#   4. every command that reads or writes a recording does so in MCAP: sim (a bag folder), filter,
#      eval, render, odom, slam;
#   5. sqlite3 storage: an MCAP recording through a .db3 (checked with Python's sqlite3 module)
#      and back is the same, and filtering a .db3 gives the same labels.
# Usage: interop_test.sh DISPEL WORK_DIR SOURCE_DIR
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
dispel=$1
work=$2
source_dir=$3
rm -rf "$work"
mkdir -p "$work"
cd "$work"
bash "$here/install.sh"

check() { node "$here/check_mcap.mjs" "$@"; }
same() { node "$here/compare_jsonl.mjs" "$@"; }
step() { printf '\n== %s\n' "$*"; }

step "1. @mcap/core's files read and copied by dispel"
for c in none zstd lz4; do
  node "$here/write_mcap.mjs" "in_$c.mcap" --compression "$c" --chunk-size 4096
  "$dispel" convert "in_$c.mcap" -o "copy_$c.mcap" --compression "$c"
  check "copy_$c.mcap" --jsonl "copy_$c.jsonl"
  same "in_$c.mcap.expected.jsonl" "copy_$c.jsonl"
done
node "$here/write_mcap.mjs" be.mcap --big-endian-scan --qos-style humble
"$dispel" convert be.mcap -o be_folder
check be_folder/be_folder_0.mcap --jsonl be_folder.jsonl
same be.mcap.expected.jsonl be_folder.jsonl
grep -q "storage_identifier: mcap" be_folder/metadata.yaml

step "2. ROS 2 -> ROS 1 -> ROS 2"
"$dispel" convert be.mcap -o be.bag 2>convert.err
grep -q "4 messages left out on '/chatter'" convert.err
"$dispel" convert be.bag -o be_back.mcap --compression zstd
check be_back.mcap --jsonl be_back.jsonl
same be.mcap.expected.jsonl be_back.jsonl --topics /scan,/tf,/tf_static

step "3. dispel filter: the same labels from a ROS 1 bag and from its MCAP conversion"
bag=$source_dir/data/leg_tracker/demo_stationary_simple_environment.bag
"$dispel" convert "$bag" -o demo.mcap --compression lz4
"$dispel" filter "$bag" -o filtered.bag --static-sensor
"$dispel" filter demo.mcap -o filtered.mcap --static-sensor --compression zstd
"$dispel" convert filtered.bag -o filtered_from_bag.mcap
check filtered.mcap --jsonl filtered.jsonl --reencode
check filtered_from_bag.mcap --jsonl filtered_from_bag.jsonl
# One topic at a time: messages of equal time on different topics may come in either order.
for topic in /scan /scan_filtered /scan_labels; do
  same filtered_from_bag.jsonl filtered.jsonl --topics "$topic"
done

step "4. sim, filter, eval, render, odom and slam on MCAP"
"$dispel" sim "$source_dir/config/scenarios/thesis_hall.yaml" --duration 6 --seed 3 -o sim
check sim/sim_0.mcap --reencode
"$dispel" filter sim -o sim_filtered.mcap
"$dispel" eval --truth sim --result sim_filtered.mcap --json > eval.json
# The truth topics were read from the folder: moving beams are counted, and most were removed.
node -e 'const e = JSON.parse(require("fs").readFileSync("eval.json", "utf8"));
  const m = e.per_class.moving;
  if (!(m.beams > 1000 && m.removed > 0.5 * m.beams && e.preservation_rate > 0.9)) {
    console.error("eval on MCAP:", JSON.stringify(e.per_class)); process.exit(1);
  }' 
"$dispel" render sim_filtered.mcap -o sim.png
test -s sim.png
"$dispel" odom sim -o odom.csv
test "$(wc -l < odom.csv)" -gt 10
if "$dispel" slam --help > /dev/null 2>&1; then  # Built with MRPT's SLAM (dispel-slam).
  "$dispel" slam sim_filtered.mcap -o slam.csv
  test "$(wc -l < slam.csv)" -gt 100
fi
step "5. sqlite3 storage: MCAP -> .db3 (checked with Python's sqlite3) -> MCAP, and filtered"
"$dispel" convert in_zstd.mcap -o in.db3
/usr/bin/python3 - in.db3 <<'PY'
import sqlite3, sys
db = sqlite3.connect(sys.argv[1])
counts = dict(db.execute("SELECT t.name, COUNT(m.id) FROM topics t JOIN messages m ON m.topic_id = t.id GROUP BY t.name"))
want = {"/tf_static": 1, "/tf": 100, "/odom": 100, "/scan": 40, "/imu": 200, "/joint_states": 40, "/chatter": 4}
assert counts == want, counts
assert db.execute("SELECT schema_version FROM schema").fetchone()[0] == 4
assert all(q for (q,) in db.execute("SELECT offered_qos_profiles FROM topics"))
PY
"$dispel" convert in.db3 -o from_db3.mcap
check from_db3.mcap --jsonl from_db3.jsonl
same in_zstd.mcap.expected.jsonl from_db3.jsonl
"$dispel" convert demo.mcap -o demo.db3
"$dispel" filter demo.db3 -o filtered_db3 --static-sensor --format sqlite3
"$dispel" convert filtered_db3 -o filtered_db3.mcap
check filtered_db3.mcap --jsonl filtered_db3.jsonl
for topic in /scan_filtered /scan_labels; do
  same filtered_from_bag.jsonl filtered_db3.jsonl --topics "$topic"
done
echo "rosbag2_interop: all passed"
