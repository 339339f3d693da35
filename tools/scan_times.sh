#!/usr/bin/env bash
# Per-scan cost of the default filter on the real recordings: runs `dispel filter --stats` on
# each and prints one row per recording: scans, beams, then wall and CPU time per scan (median,
# p99, p99.9, max, in microseconds) and what the costliest scan (by CPU time) was doing.
#   bash tools/scan_times.sh [DISPEL]      (default ./build/bin/dispel)
# Extra recordings: SCAN_TIMES_EXTRA="file.bag:--scan-topic /x ..." (one per line).
# Wall time includes the time the machine kept the filter waiting; CPU time is the filtering
# thread's own work. Run it on an idle machine for the wall figures.
set -euo pipefail
cd "$(dirname "$0")/.."
dispel=${1:-./build/bin/dispel}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
sena="/usr/share/mrpt/datasets/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog"

runs=(
  "data/leg_tracker/demo_stationary_simple_environment.bag|--static-sensor --scale-to-scanner"
  "data/carmen/leg_tracker_from0.log|--static-sensor --scale-to-scanner"
  "data/leg_tracker/negative_2.bag|--scan-topic /left_scan"
  "data/leg_tracker/negative_2.bag|--scan-topic /right_scan"
  "data/leg_tracker/negative_2.bag|--scan-topic /rear_scan"
)
[[ -f "$sena" ]] && runs+=("$sena|")
while IFS= read -r extra; do
  [[ -n "$extra" ]] && runs+=("${extra%%:*}|${extra#*:}")
done <<<"${SCAN_TIMES_EXTRA:-}"

printf '%-58s %6s %5s | %-27s | %-27s | %s\n' recording scans beams \
  "wall med/p99/p99.9/max us" "cpu med/p99/p99.9/max us" "costliest scan"
k=0
for run in "${runs[@]}"; do
  input=${run%%|*}
  read -r -a options <<<"${run#*|}"
  k=$((k + 1))
  "$dispel" filter "$input" -o "$work/out$k.bag" "${options[@]}" --stats "$work/s$k.json" \
    >/dev/null 2>"$work/err$k" || { echo "failed: $input: $(cat "$work/err$k")" >&2; exit 1; }
  rm -f "$work/out$k.bag"
  /usr/bin/python3 - "$work/s$k.json" "$(basename "$input") ${options[*]:-}" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
w, c = s["scan_time_us"], s["scan_cpu_time_us"]
slow = s["slowest_scans"][0] if s["slowest_scans"] else {}
def q(t):
    return "/".join("%.0f" % t[k] for k in ("median", "p99", "p99_9", "max"))
what = ("#%d %s: %d objects, %d tracks, ICP %d points x %d, %d voxels, %d tiles" % (
    slow["index"], slow["event"], slow["objects"], slow["tracks"], slow["registration_points"],
    slow["registration_iterations"], slow["map_voxels"], slow["free_space_tiles_started"])
    ) if slow else ""
print("%-58s %6d %5d | %-27s | %-27s | %s" % (sys.argv[2][:58], s["scans"]["total"],
      slow.get("beams", 0), q(w), q(c), what))
EOF
done
