#!/usr/bin/python3
"""Export LaserScan messages from a ROS 1 bag to the CSV used by dispel's tests.

Uses the real ROS bag library (Debian package python3-rosbag; run with /usr/bin/python3).
One line per scan:
  stamp_s,angle_min_rad,angle_increment_rad,range_min_m,range_max_m,beam_count,r_0,...,r_n-1
Ranges are written to 0.1 mm ("inf" and "nan" kept).

Usage: export_scans_csv.py BAG TOPIC OUT.csv [--every N] [--start K] [--count M]
"""
import argparse
import math
import sys

import rosbag


def fmt(r):
    if math.isnan(r):
        return "nan"
    if math.isinf(r):
        return "inf" if r > 0 else "-inf"
    return "%.4f" % r


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bag")
    ap.add_argument("topic")
    ap.add_argument("out")
    ap.add_argument("--every", type=int, default=1, help="keep every N-th scan")
    ap.add_argument("--start", type=int, default=0, help="skip the first K scans")
    ap.add_argument("--count", type=int, default=0, help="keep at most M scans (0: all)")
    args = ap.parse_args()
    kept = 0
    with rosbag.Bag(args.bag) as bag, open(args.out, "w") as out:
        out.write("# exported from %s topic %s, scans from %d, every %d-th, by "
                  "tools/export_scans_csv.py\n"
                  % (args.bag.split("/")[-1], args.topic, args.start, args.every))
        for i, (_, msg, _) in enumerate(bag.read_messages(topics=[args.topic])):
            if i < args.start or (i - args.start) % args.every:
                continue
            if args.count and kept >= args.count:
                break
            head = [repr(msg.header.stamp.to_sec()), repr(msg.angle_min), repr(msg.angle_increment),
                    repr(msg.range_min), repr(msg.range_max), str(len(msg.ranges))]
            out.write(",".join(head + [fmt(r) for r in msg.ranges]) + "\n")
            kept += 1
    if kept == 0:
        sys.exit("no messages on topic %s" % args.topic)
    print("wrote %d scans to %s" % (kept, args.out))


if __name__ == "__main__":
    main()
