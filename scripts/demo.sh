#!/usr/bin/env bash
# The main job: installs what is missing, builds, then
#  1. simulates the thesis's scenario (config/scenarios/thesis_hall.yaml), filters it with the
#     thesis's parameters and evaluates the result against the ground truth;
#  2. filters the real recording that ships with the project (people walking past a stationary
#     2D LiDAR);
# and prints a table of both.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
dispel=./build/apps/dispel
out=build/demo
mkdir -p "$out"

echo "== simulated: the thesis's hall (range cut to 5.5 m, masked sectors, people walking), seed 1"
$dispel sim config/scenarios/thesis_hall.yaml -o "$out/thesis_hall.bag" --seed 1
$dispel filter "$out/thesis_hall.bag" -o "$out/thesis_hall_filtered.bag" \
  --config config/thesis_sensor.yaml --stats "$out/thesis_hall_stats.json"
echo "-- the thesis's parameters (config/thesis_sensor.yaml):"
$dispel eval --truth "$out/thesis_hall.bag" --result "$out/thesis_hall_filtered.bag"
$dispel filter "$out/thesis_hall.bag" -o "$out/thesis_hall_tuned.bag" \
  --config config/thesis_sensor_tuned.yaml > /dev/null
echo "-- tuned (config/thesis_sensor_tuned.yaml):"
$dispel eval --truth "$out/thesis_hall.bag" --result "$out/thesis_hall_tuned.bag"

echo
echo "== recorded: leg_tracker demo bag (stationary Hokuyo, people walking), no ground truth"
$dispel filter data/leg_tracker/demo_stationary_simple_environment.bag -o "$out/filtered.bag" \
  --static-sensor --scale-to-scanner --stats "$out/stats.json" "$@"
echo "outputs in $out/: bags to replay (/scan_filtered), statistics as JSON"
