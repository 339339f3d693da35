#!/usr/bin/env python3
"""How far the registration's motion between consecutive scans is from the wheel odometry's: the
odometry's noise per scan as the registration sees it, on a recording with odometry.

usage: /usr/bin/python3 tools/odometry_vs_registration.py FILTERED.bag [--scan-topic TOPIC]
           [--odom-topic TOPIC] [--mount X Y YAW_DEG] [--json]

FILTERED.bag is `dispel filter`'s output of a recording with odometry: it has TOPIC_pose (the
laser's registered pose, default topic /scan) and the odometry (default /odom). The mount (the
laser in the odometry's child frame) is read from /tf_static unless --mount gives it. For each
pair of consecutive scans both motions are taken in the laser's frame: the registered one from
TOPIC_pose, the odometry's from the odometry interpolated at the two stamps (linear, yaw along
the shorter arc, as `dispel filter` does) composed with the mount. Prints, over the pairs that
moved more than 5 cm by the odometry, the medians and 90th percentiles of the difference's
translation (in mm and as a share of the odometry's motion) and of its rotation (in mrad)."""
import bisect, json, math, sys
import rosbag


def compose(a, b):
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrap(a[2] + b[2]))


def inverse(a):
    c, s = math.cos(a[2]), math.sin(a[2])
    return (-c * a[0] - s * a[1], s * a[0] - c * a[1], -a[2])


def wrap(angle):
    return math.atan2(math.sin(angle), math.cos(angle))


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def percentile(values, p):
    values = sorted(values)
    return values[min(len(values) - 1, int(p * len(values)))] if values else float('nan')


def fail(message):
    sys.stderr.write(f'odometry_vs_registration.py: {message}\n')
    sys.exit(2)


def main():
    args = sys.argv[1:]
    if not args or args[0].startswith('-'):
        fail('usage: odometry_vs_registration.py FILTERED.bag [--scan-topic T] [--odom-topic T] '
             '[--mount X Y YAW_DEG] [--json]')
    path, scan_topic, odom_topic, mount, as_json = args[0], '/scan', '/odom', None, False
    i = 1
    while i < len(args):
        if args[i] == '--scan-topic' and i + 1 < len(args):
            scan_topic, i = args[i + 1], i + 2
        elif args[i] == '--odom-topic' and i + 1 < len(args):
            odom_topic, i = args[i + 1], i + 2
        elif args[i] == '--mount' and i + 3 < len(args):
            try:
                mount = (float(args[i + 1]), float(args[i + 2]), math.radians(float(args[i + 3])))
            except ValueError:
                fail('--mount needs three numbers: X Y YAW_DEG')
            i += 4
        elif args[i] == '--json':
            as_json, i = True, i + 1
        else:
            fail(f'unknown or incomplete argument: {args[i][:80]}')
    pose_topic = scan_topic + '_pose'
    odometry, registered, statics = [], [], []
    try:
        bag = rosbag.Bag(path)
    except Exception as e:  # rosbag raises several types for an unreadable file.
        fail(f'cannot read {path[:200]}: {str(e)[:200]}')
    with bag:
        for topic, msg, _ in bag.read_messages(topics=[odom_topic, pose_topic, '/tf_static']):
            if topic == '/tf_static':
                statics.extend(msg.transforms)
                continue
            p = msg.pose.pose
            pose = (p.position.x, p.position.y, yaw_of(p.orientation))
            stamp = msg.header.stamp.to_sec()
            if topic == odom_topic:
                odometry.append((stamp, pose))
            else:
                registered.append((stamp, pose, msg.child_frame_id))
    if not registered:
        fail(f'no {pose_topic} in {path[:200]}: filter with the registration on')
    if len(odometry) < 2:
        fail(f'no odometry on {odom_topic} in {path[:200]}')
    if mount is None:
        frame = registered[0][2]
        for t in statics:
            if t.child_frame_id == frame:
                mount = (t.transform.translation.x, t.transform.translation.y,
                         yaw_of(t.transform.rotation))
        if mount is None:
            fail(f'no /tf_static transform to {frame[:80]}: give --mount X Y YAW_DEG')
    odometry.sort(key=lambda o: o[0])
    stamps = [o[0] for o in odometry]

    def odometry_at(t):
        k = bisect.bisect_left(stamps, t)
        if k < len(stamps) and stamps[k] == t:
            return odometry[k][1]
        if k == 0 or k == len(stamps) or stamps[k] - stamps[k - 1] > 0.5:
            return None
        (t0, a), (t1, b) = odometry[k - 1], odometry[k]
        f = (t - t0) / (t1 - t0)
        return (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]),
                wrap(a[2] + f * wrap(b[2] - a[2])))

    translation_m, share, rotation_rad = [], [], []
    for (s0, p0, _), (s1, p1, _) in zip(registered, registered[1:]):
        o0, o1 = odometry_at(s0), odometry_at(s1)
        if o0 is None or o1 is None:
            continue
        by_odometry = compose(inverse(compose(o0, mount)), compose(o1, mount))
        moved = math.hypot(by_odometry[0], by_odometry[1])
        if moved <= 0.05:
            continue
        difference = compose(inverse(by_odometry), compose(inverse(p0), p1))
        translation_m.append(math.hypot(difference[0], difference[1]))
        share.append(translation_m[-1] / moved)
        rotation_rad.append(abs(difference[2]))
    if not translation_m:
        fail('no pair of scans moved more than 5 cm by the odometry')
    result = {
        'pairs': len(translation_m),
        'translation_mm': {'median': 1000 * percentile(translation_m, 0.5),
                           'p90': 1000 * percentile(translation_m, 0.9)},
        'translation_share': {'median': percentile(share, 0.5), 'p90': percentile(share, 0.9)},
        'rotation_mrad': {'median': 1000 * percentile(rotation_rad, 0.5),
                          'p90': 1000 * percentile(rotation_rad, 0.9)},
    }
    if as_json:
        print(json.dumps(result))
        return
    print(f"{result['pairs']} pairs of scans that moved more than 5 cm: registered minus odometry "
          f"per scan, translation median {result['translation_mm']['median']:.1f} mm "
          f"({100 * result['translation_share']['median']:.1f} % of the motion), p90 "
          f"{result['translation_mm']['p90']:.1f} mm "
          f"({100 * result['translation_share']['p90']:.1f} %); rotation median "
          f"{result['rotation_mrad']['median']:.2f} mrad, p90 "
          f"{result['rotation_mrad']['p90']:.2f} mrad")


if __name__ == '__main__':
    main()
