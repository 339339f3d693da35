#!/usr/bin/env bash
# Reading and writing recordings, ROS 1 bag against rosbag2 MCAP, on the same messages: `dispel
# convert` of a recording into its own format (every message read, then written byte for byte),
# for each format and compression, the runs alternating, and `dispel filter` on both (reading
# decodes every scan). Prints, per case, the median and spread of the runs' wall and CPU (user +
# system) seconds, and the ratio MCAP / ROS 1 of the medians.
#   bash tools/recording_io_bench.sh [DISPEL] [RUNS]      (defaults ./build/bin/dispel, 5)
# The recording: 120 s of config/scenarios/thesis_hall.yaml simulated (seed 1; 1617-beam scans
# with their ground truth, odometry, wheels, IMU: about 100 MB), as a ROS 1 bag and converted to
# MCAP. Each time includes the program's start (`dispel --version`, printed first). Run it on an
# idle machine.
set -euo pipefail
cd "$(dirname "$0")/.."
dispel=${1:-./build/bin/dispel}
runs=${2:-5}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
src=$work/sim.bag  # lz4, as dispel sim writes
"$dispel" sim config/scenarios/thesis_hall.yaml --duration 120 --seed 1 -o "$src" > /dev/null
"$dispel" convert "$src" -o "$work/in.bag" > /dev/null
"$dispel" convert "$src" -o "$work/in.mcap" > /dev/null
"$dispel" convert "$src" -o "$work/in_lz4.bag" --compression lz4 > /dev/null
"$dispel" convert "$src" -o "$work/in_lz4.mcap" --compression lz4 > /dev/null
"$dispel" convert "$src" -o "$work/in_zstd.mcap" --compression zstd > /dev/null

# name|command: each run's output is removed first (a bag folder is never replaced).
cases=(
  "copy ROS 1 bag (none)|convert $work/in.bag -o $work/out.bag"
  "copy MCAP (none)|convert $work/in.mcap -o $work/out.mcap"
  "copy ROS 1 bag (lz4)|convert $work/in_lz4.bag -o $work/out.bag --compression lz4"
  "copy MCAP (lz4)|convert $work/in_lz4.mcap -o $work/out.mcap --compression lz4"
  "copy MCAP (zstd)|convert $work/in_zstd.mcap -o $work/out.mcap --compression zstd"
  "filter, ROS 1 bag|filter $work/in.bag -o $work/out.bag"
  "filter, MCAP|filter $work/in.mcap -o $work/out.mcap"
  "program start|--version"
)
declare -A wall cpu
for ((r = 0; r < runs; r++)); do
  for c in "${cases[@]}"; do
    name=${c%%|*}
    rm -rf "$work/out.bag" "$work/out.mcap"
    # shellcheck disable=SC2086
    /usr/bin/time -o "$work/time" -f "%e %U %S" "$dispel" ${c#*|} > /dev/null 2> /dev/null
    read -r e u s < "$work/time"
    wall[$name]+="$e "
    cpu[$name]+="$(awk -v u="$u" -v s="$s" 'BEGIN {printf "%.2f", u + s}') "
  done
done

median() { tr ' ' '\n' | grep -v '^$' | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
range() { tr ' ' '\n' | grep -v '^$' | sort -g | awk 'NR==1{lo=$1} {hi=$1} END {print lo "-" hi}'; }
printf '%-32s %18s %18s\n' case "wall s med (range)" "cpu s med (range)"
declare -A med_cpu
for c in "${cases[@]}"; do
  name=${c%%|*}
  mw=$(echo "${wall[$name]}" | median)
  mc=$(echo "${cpu[$name]}" | median)
  med_cpu[$name]=$mc
  printf '%-32s %6s (%9s) %6s (%9s)\n' "$name" "$mw" "$(echo "${wall[$name]}" | range)" "$mc" \
    "$(echo "${cpu[$name]}" | range)"
done
ratio() { awk -v a="${med_cpu[$1]}" -v b="${med_cpu[$2]}" 'BEGIN {printf "%.2f", a / b}'; }
echo "CPU ratio MCAP / ROS 1: copy none $(ratio "copy MCAP (none)" "copy ROS 1 bag (none)"), copy lz4 $(ratio "copy MCAP (lz4)" "copy ROS 1 bag (lz4)"), filter $(ratio "filter, MCAP" "filter, ROS 1 bag")"
ls -la "$work"/in*.bag "$work"/in*.mcap | awk '{print "  " $5 " bytes  " $NF}' 
