#!/usr/bin/env bash
# Odometry on simulated lawnmower runs: dead reckoning, the CT filter and the omnidirectional
# filter against the true pose, seeds 1..N, means over seeds.
# usage: tools/odometry_sim_eval.sh [SCENARIO.yaml] [SEEDS]   (defaults: odometry_lawnmower, 5)
set -euo pipefail
cd "$(dirname "$0")/.."
scenario=${1:-config/scenarios/odometry_lawnmower.yaml}
seeds=${2:-5}
dispel=./build/bin/dispel
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for seed in $(seq 1 "$seeds"); do
  $dispel sim "$scenario" -o "$work/run.bag" --seed "$seed" > /dev/null
  for model in dead_reckoning ct omni; do
    $dispel odom "$work/run.bag" -o "$work/$model.csv" --model "$model" \
      --truth-csv "$work/truth.csv" --json > "$work/$model.json"
    $dispel eval-trajectory --truth "$work/truth.csv" --estimate "$work/$model.csv" --json |
      /usr/bin/python3 -c "
import json, sys
e = json.load(sys.stdin); s = json.load(open('$work/$model.json'))
print('$seed $model %.4f %.4f %.4f %.4f %d' % (e['rmse_position_m'], e['final_position_error_m'],
      e['rmse_yaw_rad'], e['final_yaw_error_rad'], s['events']['gated']['wheels']))"
  done
done | /usr/bin/python3 -c "
import sys, statistics as st
rows = [l.split() for l in sys.stdin]
print('%-15s %10s %10s %10s %10s %12s' % ('model', 'RMSE m', 'final m', 'RMSE yaw', 'final yaw', 'gated wheels'))
for m in ('dead_reckoning', 'ct', 'omni'):
    r = [x for x in rows if x[1] == m]
    f = lambda i: st.mean(float(x[i]) for x in r)
    print('%-15s %10.3f %10.3f %10.4f %10.4f %12.0f' % (m, f(2), f(3), f(4), f(5), f(6)))
"
