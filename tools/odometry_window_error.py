#!/usr/bin/env python3
"""Wheel odometry's error against ground truth over short windows: how far the odometry's motion
over one scan (0.15 s) or one second is from the true motion, on a simulated recording or on the
optiodom data set (a real differential-drive robot with motion-capture truth).

usage: /usr/bin/python3 tools/odometry_window_error.py SOURCE [--windows 0.05,0.15,1.0] [--json]

SOURCE is either a bag written by `dispel sim` (its /odom against its /ground_truth, paired by
stamp) or a folder of optiodom sessions (any depth of *_metadata.csv with their *_run-NN.csv:
rows time_s, x_gt_m, y_gt_m, theta_gt_rad, ticks_right, ticks_left at 20 Hz; the odometry is
dead reckoning from the ticks with the metadata's wheel diameters Di and base Li).

For each window length, the recording is cut into consecutive windows of that length; a window is
counted when the true motion over it is at least 0.08 m/s times its length (the robot drives).
In each, both motions are taken in the frame of the window's first pose; the translation error is
the distance between the two end points (in mm and as a share of the true distance), the rotation
error the difference of the two turns (mrad). Prints medians and 90th percentiles per window
length. Motion capture has noise of its own (optiodom: about 0.7 mm over 0.05 s with the robot
nearly still), so on optiodom the short windows are an upper bound of the odometry's error."""
import csv, glob, json, math, os, statistics, sys


def relative(a, b):
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return (c * dx + s * dy, -s * dx + c * dy, math.atan2(math.sin(b[2] - a[2]), math.cos(b[2] - a[2])))


def fail(message):
    sys.stderr.write(f'odometry_window_error.py: {message}\n')
    sys.exit(2)


def optiodom_runs(folder):
    """Yields (period_s, truth poses, odometry poses) per run."""
    metas = sorted(glob.glob(os.path.join(folder, '**', '*_metadata.csv'), recursive=True))
    if not metas:
        fail(f'{folder}: no *_metadata.csv below it')
    for meta_path in metas:
        meta = {r[0]: [c for c in r[1:] if c != ''] for r in csv.reader(open(meta_path)) if r and r[0]}
        try:
            ticks_per_rev = float(meta['ngear'][0]) * float(meta['encRes'][0])
            d_right, d_left = float(meta['Di'][0]), float(meta['Di'][1])
            base = float(meta['Li'][0])
        except (KeyError, IndexError, ValueError):
            fail(f'{meta_path}: needs ngear, encRes, Di (two values) and Li')
        for run in sorted(glob.glob(meta_path.replace('_metadata.csv', '_run-*.csv'))):
            rows = [[float(c) for c in r] for r in csv.reader(open(run)) if r]
            if len(rows) < 2:
                continue
            x = y = yaw = 0.0
            odometry = [(x, y, yaw)]
            for r in rows[1:]:
                right = r[4] / ticks_per_rev * math.pi * d_right
                left = r[5] / ticks_per_rev * math.pi * d_left
                step, turn = 0.5 * (right + left), (right - left) / base
                x += step * math.cos(yaw + 0.5 * turn)
                y += step * math.sin(yaw + 0.5 * turn)
                yaw += turn
                odometry.append((x, y, yaw))
            period = (rows[-1][0] - rows[0][0]) / (len(rows) - 1)
            yield period, [(r[1], r[2], r[3]) for r in rows], odometry


def bag_run(path):
    import rosbag
    odometry, truth = {}, {}
    try:
        bag = rosbag.Bag(path)
    except Exception as e:  # rosbag raises several types for a bad file.
        fail(f'{path}: cannot read the bag ({e})')
    for topic, m, _ in bag.read_messages(topics=['/odom', '/ground_truth']):
        p, q = m.pose.pose.position, m.pose.pose.orientation
        yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
        (odometry if topic == '/odom' else truth)[m.header.stamp.to_nsec()] = (p.x, p.y, yaw)
    stamps = sorted(set(odometry) & set(truth))
    if len(stamps) < 2:
        fail(f'{path}: needs /odom and /ground_truth with the same stamps (dispel sim writes both)')
    yield ((stamps[-1] - stamps[0]) * 1e-9 / (len(stamps) - 1), [truth[s] for s in stamps],
           [odometry[s] for s in stamps])


def percentile(values, p):
    values = sorted(values)
    return values[min(len(values) - 1, int(p * len(values)))]


def main():
    args = sys.argv[1:]
    if not args or args[0].startswith('-'):
        fail('usage: odometry_window_error.py SIM.bag|OPTIODOM_DIR [--windows S,S,...] [--json]')
    source, windows, as_json = args[0], [0.05, 0.15, 1.0], False
    i = 1
    while i < len(args):
        if args[i] == '--windows' and i + 1 < len(args):
            try:
                windows = [float(w) for w in args[i + 1].split(',')]
            except ValueError:
                fail(f'--windows: not a list of seconds: {args[i + 1][:80]}')
            if not all(w > 0.0 and math.isfinite(w) for w in windows):
                fail('--windows: each window must be a positive number of seconds')
            i += 2
        elif args[i] == '--json':
            as_json, i = True, i + 1
        else:
            fail(f'unknown argument: {args[i][:80]}')
    if not os.path.exists(source):
        fail(f'{source}: no such file or folder')
    runs = list(optiodom_runs(source) if os.path.isdir(source) else bag_run(source))
    result = []
    for window in windows:
        speed, translation, share, rotation = [], [], [], []
        for period, truth, odometry in runs:
            k = max(1, round(window / period))
            for j in range(0, len(truth) - k, k):
                t = relative(truth[j], truth[j + k])
                o = relative(odometry[j], odometry[j + k])
                distance = math.hypot(t[0], t[1])
                if distance < 0.08 * k * period:
                    continue
                error = math.hypot(t[0] - o[0], t[1] - o[1])
                speed.append(distance / (k * period))
                translation.append(1000.0 * error)
                share.append(100.0 * error / distance)
                rotation.append(1000.0 * abs(math.atan2(math.sin(t[2] - o[2]), math.cos(t[2] - o[2]))))
        if not translation:
            fail(f'no window of {window} s in which the robot drives')
        result.append({'window_s': window, 'windows': len(translation),
                       'speed_mps': statistics.median(speed),
                       'translation_mm': [statistics.median(translation), percentile(translation, 0.9)],
                       'translation_percent': [statistics.median(share), percentile(share, 0.9)],
                       'rotation_mrad': [statistics.median(rotation), percentile(rotation, 0.9)]})
    if as_json:
        print(json.dumps(result, indent=1))
        return
    for r in result:
        print('%.2f s: %d windows at %.2f m/s; translation %.2f mm (p90 %.2f), %.1f %% of the motion '
              '(p90 %.1f); rotation %.2f mrad (p90 %.2f)' % (
                  r['window_s'], r['windows'], r['speed_mps'], *r['translation_mm'],
                  *r['translation_percent'], *r['rotation_mrad']))


if __name__ == '__main__':
    main()
