#!/usr/bin/env bash
# The main job: installs what is missing, builds, and runs `dispel bench` on the scenes that ship
# with the project (segmentation and the reference DBSCAN, 1617 to 1 000 000 beams).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
./build/apps/dispel bench "$@"
