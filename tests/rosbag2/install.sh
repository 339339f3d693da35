#!/bin/sh
# Installs the pinned Node.js packages of tests/rosbag2 (npm ci) when node_modules is
# missing or older than package-lock.json. Prints one line.
cd "$(dirname "$0")" || exit 1
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  echo "tests/rosbag2/install.sh: node and npm are required (e.g. apt-get install nodejs npm, Node >= 18)" >&2
  exit 1
fi
if [ -d node_modules ] && [ -f node_modules/.package-lock.json ] && \
   [ ! package-lock.json -nt node_modules/.package-lock.json ]; then
  echo "tests/rosbag2: node modules up to date ($(node --version))"
  exit 0
fi
if ! log=$(npm ci --no-audit --no-fund 2>&1); then
  echo "$log" >&2
  echo "tests/rosbag2/install.sh: npm ci failed" >&2
  exit 1
fi
echo "tests/rosbag2: installed node modules with npm ci ($(node --version), npm $(npm --version))"
