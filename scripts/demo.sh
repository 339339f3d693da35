#!/usr/bin/env bash
# The main job: installs what is missing, builds, and runs `dispel filter` on the recording that
# ships with the project (people walking past a stationary 2D LiDAR), then prints a summary.
# Arguments are passed to `dispel filter` (e.g. --stats stats.json, --config config/default.yaml).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
bag=data/leg_tracker/demo_stationary_simple_environment.bag
mkdir -p build/demo
./build/apps/dispel filter "$bag" -o build/demo/filtered.bag --static-sensor --scale-to-scanner \
  --stats build/demo/stats.json "$@"
echo "statistics: build/demo/stats.json; replay build/demo/filtered.bag with /scan_filtered"
