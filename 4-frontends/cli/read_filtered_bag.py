#!/usr/bin/python3
"""Reads a bag written by `dispel filter` with python3-rosbag and checks its promises:
every /scan message has a /scan_filtered and a /scan_labels twin with the same header, the
filtered ranges are the original ones or NaN, and a NaN appears exactly where the label says
removed (1 or 2)."""
import math
import sys

import rosbag


def main(path):
    by_topic = {"/scan": [], "/scan_filtered": [], "/scan_labels": []}
    with rosbag.Bag(path) as bag:
        for topic, msg, _ in bag.read_messages():
            by_topic.setdefault(topic, []).append(msg)
    scans, filtered, labels = by_topic["/scan"], by_topic["/scan_filtered"], by_topic["/scan_labels"]
    if not scans or not (len(scans) == len(filtered) == len(labels)):
        sys.exit("topic counts differ: %d %d %d" % (len(scans), len(filtered), len(labels)))
    removed = 0
    for s, f, l in zip(scans, filtered, labels):
        if s.header.stamp != f.header.stamp or s.header.frame_id != f.header.frame_id:
            sys.exit("headers differ at %s" % s.header.stamp)
        for r, fr, lab in zip(s.ranges, f.ranges, l.intensities):
            if lab in (1.0, 2.0):
                if not math.isnan(fr):
                    sys.exit("removed beam is not NaN")
                removed += 1
            elif not (fr == r or (math.isnan(fr) and math.isnan(r))):
                sys.exit("kept beam changed")
    print("%d scans, %d beams removed" % (len(scans), removed))


if __name__ == "__main__":
    main(sys.argv[1])
