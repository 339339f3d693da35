#!/usr/bin/env bash
# The main job: installs what is missing, builds, then
#  1. simulates the thesis's scenario (config/scenarios/thesis_hall.yaml) with three seeds, filters
#     each with dispel's defaults and with the thesis's filter, evaluates both against the ground
#     truth and prints a table;
#  2. filters the real recording that ships with the project (people walking past a stationary
#     2D LiDAR);
#  3. converts that recording to rosbag2 MCAP (a bag folder, as `ros2 bag record` makes one),
#     filters it, and checks that the beams removed are the same as from the ROS 1 bag;
# and prints a table of both.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
dispel=./build/bin/dispel
out=build/demo
mkdir -p "$out"

echo "== simulated: the thesis's hall (range cut to 5.5 m, masked sectors, people walking), seeds 1-3"
table="$out/thesis_hall_table.txt"
printf "%-36s %5s %12s %10s %15s\n" "configuration" "seed" "preservation" "rejection" "latency median" > "$table"
for seed in 1 2 3; do
  $dispel sim config/scenarios/thesis_hall.yaml -o "$out/thesis_hall_$seed.bag" --seed "$seed"
  for config in default_masked thesis_masked; do
    $dispel filter "$out/thesis_hall_$seed.bag" -o "$out/thesis_hall_${seed}_$config.bag" \
      --config "config/$config.yaml" --stats "$out/thesis_hall_${seed}_$config.json" > /dev/null
    $dispel eval --truth "$out/thesis_hall_$seed.bag" --result "$out/thesis_hall_${seed}_$config.bag" \
      --json > "$out/thesis_hall_${seed}_${config}_eval.json"
    /usr/bin/python3 - "$out/thesis_hall_${seed}_${config}_eval.json" "$config" "$seed" >> "$table" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
name = {"default_masked": "dispel default (default_masked.yaml)",
        "thesis_masked": "thesis (thesis_masked.yaml)"}[sys.argv[2]]
lat = r["detection_latency_s"]["median"]
print("%-36s %5s %12.4f %10.4f %15s" % (name, sys.argv[3], r["preservation_rate"],
      r["rejection_rate"], "-" if lat is None else "%.2f s" % lat))
PY
  done
done
cat "$table"
echo "targets: preservation >= 0.99, rejection >= 0.90, median latency < 1.0 s"
echo
echo "== recorded: leg_tracker demo bag (stationary Hokuyo, people walking), no ground truth"
$dispel filter data/leg_tracker/demo_stationary_simple_environment.bag -o "$out/filtered.bag" \
  --static-sensor --scale-to-scanner --stats "$out/stats.json" "$@"
echo
echo "== the same recording as a ROS 2 user has it: a rosbag2 MCAP bag folder"
rm -rf "$out/demo_ros2" "$out/filtered_ros2"  # A bag folder is never replaced.
$dispel convert data/leg_tracker/demo_stationary_simple_environment.bag -o "$out/demo_ros2" \
  --compression zstd
$dispel filter "$out/demo_ros2" -o "$out/filtered_ros2" --static-sensor --scale-to-scanner \
  --stats "$out/stats_ros2.json" "$@"
/usr/bin/python3 - "$out/stats.json" "$out/stats_ros2.json" <<'PY'
import json, sys
a, b = (json.load(open(p))["beams_removed"] for p in sys.argv[1:3])
print("beams removed: ROS 1 bag %s, rosbag2 MCAP %s: %s" % (a, b, "the same" if a == b else "DIFFERENT"))
sys.exit(0 if a == b else 1)
PY
echo "outputs in $out/: filtered.bag (ROS 1) and filtered_ros2/ (rosbag2 MCAP) to replay (/scan_filtered)"
