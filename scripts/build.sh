#!/usr/bin/env bash
# Configures and builds dispel into BUILD_DIR (default: build/), Release unless told otherwise,
# with the ROS 1 nodes and ROS 2 over DDS (scripts/setup.sh installs what they need). Extra
# arguments go to the CMake configure step, after the defaults, so they win (-DDISPEL_WITH_ROS1=OFF).
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${BUILD_DIR:-build}
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" -DDISPEL_WITH_ROS1=ON \
  -DDISPEL_WITH_ROS2=ON "$@" >/dev/null
cmake --build "$build_dir" -j"$(nproc)"
