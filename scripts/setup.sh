#!/usr/bin/env bash
# Installs the Debian packages dispel needs that are not installed yet (Debian bookworm).
# Runs apt-get as root (or through sudo); does nothing when everything is present.
set -euo pipefail

packages=(
  cmake make g++                       # build
  libeigen3-dev                        # core
  libcli11-dev nlohmann-json3-dev      # command line, JSON output
  libgtest-dev libbenchmark-dev        # tests, benchmarks
  libyaml-cpp-dev                      # configuration files
  librosbag-storage-dev libsensor-msgs-dev libnav-msgs-dev libgeometry-msgs-dev
  libtf2-msgs-dev                      # ROS 1 bags (the real bag library, no ROS install needed)
  python3-rosbag                       # tests: bags we write must read in Python and rosbag info
  libcairo2-dev libfontconfig-dev      # dispel render, eval --plot: PNG and SVG pictures (Cairo)
  libmrpt-slam-dev libmrpt-maps-dev libmrpt-obs-dev  # dispel::slam: MRPT's ICP-SLAM (tests);
                                       # dispel::io_mrpt_rawlog: MRPT rawlogs
  zlib1g-dev                           # io_mrpt_rawlog: gzip-compressed rawlogs, checked whole
  libzstd-dev liblz4-dev               # io_rosbag2: MCAP chunks compressed with zstd or lz4
  libsqlite3-dev                       # io_rosbag2: sqlite3 storage (.db3)
  mrpt-common                          # tests and docs/results.md: MRPT's datasets, among them
                                       # the SENA wheelchair log (one loop of a building)
  pkg-config libroscpp-dev libtf2-ros-dev libvisualization-msgs-dev libdiagnostic-msgs-dev
                                       # ROS 1 nodes (ros1/, -DDISPEL_WITH_ROS1=ON)
  python3-rosmaster python3-roslaunch python3-rosparam tf2-tools
                                       # their live tests: rosmaster, roslaunch,
                                       # static_transform_publisher
  cyclonedds-dev cyclonedds-tools     # ROS 2 over DDS (ros2/, -DDISPEL_WITH_ROS2=ON): Cyclone DDS, idlc
  libfastrtps-dev fastddsgen default-jre-headless
                                       # its cross-vendor test: Fast DDS, and fastddsgen (Java)
                                       # for the message types
  clang libclang-rt-14-dev             # scripts/fuzz.sh: libFuzzer, ASan, UBSan (build-fuzz/)
  procps gdb                           # scripts/fuzz.sh's watchdog: a hung run's processes
                                       # (pgrep) and their stacks
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: need root to install: ${missing[*]}" >&2; exit 1; }
  sudo=sudo
fi
echo "setup: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
