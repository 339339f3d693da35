#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test: first the Release build (with the ROS 1
# nodes and their live tests), then the unit tests again under AddressSanitizer and
# UndefinedBehaviorSanitizer (without the command line and the ROS 1 nodes), then each fuzz
# target of the readers for 30 s (scripts/fuzz.sh, build-fuzz/; docs/fuzzing.md).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
jobs=$(nproc)
# A test without a TIMEOUT of its own is stopped, and fails, after 20 minutes (ctest's default is
# none): a hang fails the run with the test's name instead of holding CI until its own limit.
# The slowest test takes about 2 minutes under the sanitizers.
timeout_s=1200

bash scripts/build.sh
ctest --test-dir build --output-on-failure -j"$jobs" --timeout "$timeout_s"

# -O1 -g1: the sanitizers' own advice (-O1), and line tables (-g1) for their stack traces, which
# is all they print; it halves the build of the Eigen-heavy files against -O2 -g (the UKF's:
# 137 s to 71 s), the longest stage of this script.
BUILD_DIR=build-sanitize BUILD_TYPE=RelWithDebInfo bash scripts/build.sh -DDISPEL_SANITIZE=ON \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DDISPEL_BUILD_APPS=OFF \
  -DDISPEL_BUILD_BENCHMARKS=OFF -DDISPEL_WITH_ROS1=OFF
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
  ctest --test-dir build-sanitize --output-on-failure -j"$jobs" --timeout "$timeout_s" \
  -E package_

bash scripts/fuzz.sh 30
