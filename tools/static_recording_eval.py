#!/usr/bin/env python3
"""Walls kept and walkers removed on a recording from a scanner that does not move (the shipped
leg_tracker demo), without annotations, by the rule of the test FilterJobOnRecordedBag: a beam
whose valid ranges over the whole recording spread (10th to 90th percentile) under 5 cm and that
is valid in 90 % of the scans sees a wall, and counts as one in a scan when within 5 cm of its
median; a return more than 30 cm nearer than its beam's 90th percentile is a walker. The first
20 scans are left out. Labels 1, 2, 5, 6 and 8 are removed (dispel filter's and dispel clean's).

  /usr/bin/python3 tools/static_recording_eval.py OUT.bag LABELS_TOPIC [SCAN_TOPIC]
  e.g. OUT.bag from `dispel clean data/leg_tracker/demo_stationary_simple_environment.bag -o
  OUT.bag --static-sensor --scale-to-scanner`, LABELS_TOPIC /scan_clean_labels
"""
import math
import sys

import rosbag


def main():
    path, labels_topic = sys.argv[1], sys.argv[2]
    scan_topic = sys.argv[3] if len(sys.argv) > 3 else "/scan"
    scans, labels = [], []
    for topic, m, _ in rosbag.Bag(path).read_messages([scan_topic, labels_topic]):
        (scans if topic == scan_topic else labels).append(m)
    if not scans or len(scans) != len(labels):
        sys.exit("%s: %d scans on %s, %d on %s" % (path, len(scans), scan_topic, len(labels),
                                                     labels_topic))
    n = len(scans[0].ranges)
    median, p90, wall = [None] * n, [None] * n, [False] * n
    for i in range(n):
        v = sorted(s.ranges[i] for s in scans
                   if math.isfinite(s.ranges[i]) and s.range_min <= s.ranges[i] <= s.range_max)
        if len(v) < len(scans) // 2:
            continue
        median[i], p90[i] = v[len(v) // 2], v[len(v) * 9 // 10]
        wall[i] = len(v) >= len(scans) * 9 // 10 and p90[i] - v[len(v) // 10] < 0.05
    walls = walls_kept = walkers = walkers_removed = 0
    for k in range(20, len(scans)):
        for i in range(n):
            r = scans[k].ranges[i]
            if not math.isfinite(r):
                continue
            removed = labels[k].intensities[i] in (1, 2, 5, 6, 8)
            if wall[i] and abs(r - median[i]) < 0.05:
                walls += 1
                walls_kept += not removed
            elif p90[i] is not None and r < p90[i] - 0.3:
                walkers += 1
                walkers_removed += removed
    print("walls kept %.4f (%d beams), walkers removed %.4f (%d beams)" %
          (walls_kept / walls, walls, walkers_removed / walkers, walkers))


if __name__ == "__main__":
    main()
