#!/usr/bin/env python3
"""Writes scans of the tests' scan CSV (tools/export_scans_csv.py) as a CARMEN log whose time
counts from 0, as in the GMapping-corrected classic logs: one ODOM and one FLASER line per scan,
the sensor standing at the origin, readings without a return written as 81.91 (beyond 80 m).

  /usr/bin/python3 tools/carmen_from_scan_csv.py data/leg_tracker/scans_250_to_650.csv \
      data/carmen/leg_tracker_from0.log --count 100
"""
import argparse
import math


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("csv")
    p.add_argument("log")
    p.add_argument("--count", type=int, default=100)
    a = p.parse_args()
    rows = []
    with open(a.csv) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            rows.append(line.strip().split(","))
            if len(rows) == a.count:
                break
    t0 = float(rows[0][0])
    with open(a.log, "w") as out:
        out.write("# CARMEN log, time from 0 s: scans %d.. of %s (tools/carmen_from_scan_csv.py)\n"
                  % (0, a.csv.split("/")[-1]))
        out.write("# FLASER num_readings [range_readings] x y theta odom_x odom_y odom_theta "
                  "ipc_timestamp ipc_hostname logger_timestamp\n")
        for r in rows:
            t = float(r[0]) - t0
            n = int(r[5])
            ranges = []
            for v in r[6:6 + n]:
                x = float(v)
                ranges.append("81.91" if not math.isfinite(x) else "%.3f" % x)
            out.write("ODOM 0 0 0 0 0 0 %.6f nohost %.6f\n" % (t, t))
            out.write("FLASER %d %s 0 0 0 0 0 0 %.6f nohost %.6f\n" % (n, " ".join(ranges), t, t))


if __name__ == "__main__":
    main()
