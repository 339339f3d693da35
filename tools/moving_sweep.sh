#!/usr/bin/env bash
# The filter's figures on every simulated moving-robot scenario, the targets of docs/results.md's
# "moving robot" table: the office loop and the warehouse aisles at 0.5, 1.0 and 1.5 m/s, the
# cluttered hall and the office driven 200 s (two laps) with larger low things (office_revisits) at
# 1.0 m/s, and the two halls, 5 seeds each (about 8 minutes on 2 cores). Extra
# arguments go to every tools/filter_sim_eval.py run, e.g. --set segmentation.min_width_m=0.1 to
# measure a change.
# usage: tools/moving_sweep.sh [DISPEL] [-- filter_sim_eval.py arguments]
set -euo pipefail
cd "$(dirname "$0")/.."
dispel=build/bin/dispel
if [[ $# -gt 0 && $1 != -- ]]; then dispel=$1; shift; fi
[[ ${1:-} == -- ]] && shift
evaluate() { /usr/bin/python3 tools/filter_sim_eval.py "$dispel" "$@" | awk 'NR == 1'; }
for scenario in office_corridors warehouse_aisles; do
  for speed in 0.5 1.0 1.5; do
    evaluate "config/scenarios/$scenario.yaml" config/default.yaml --scale-to-scanner \
      --scenario-set robot.speed_mps=$speed "$@"
  done
done
evaluate config/scenarios/cluttered_hall.yaml config/default.yaml --scale-to-scanner "$@"
evaluate config/scenarios/office_revisits.yaml config/default.yaml --scale-to-scanner "$@"
for scenario in thesis_hall empty_hall; do
  evaluate "config/scenarios/$scenario.yaml" config/default_masked.yaml "$@"
done
