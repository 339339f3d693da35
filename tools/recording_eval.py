#!/usr/bin/env python3
"""The filter on a real recording without the simulator's ground truth: what `dispel filter`
removed, against people annotations or against the recording's persistent background.

usage: /usr/bin/python3 tools/recording_eval.py FILTERED.bag --scan-topic TOPIC
           [--people TOPIC] [--person-radius M] [--json]
           [--cell M] [--min-scans N] [--min-span S]

FILTERED.bag is `dispel filter`'s output (it has TOPIC_labels, and TOPIC_pose when the
registration is on), or `dispel clean`'s with TOPIC its `<scan topic>_clean`. Beams labelled
invalid (4) are not counted.

--people TOPIC: person annotations as in angusleigh/leg_tracker_benchmarks (leg_tracker/Person
  messages without a header, positions in the laser frame, each belonging to the latest scan
  before it in bag time). A person's beams end within --person-radius (default 0.4 m) of the
  annotation; background beams end farther than 1 m from every person of the scan. Prints the
  share of person beams removed and of background beams kept, and the person beams split into
  walking and standing (a person stands where the scanner stands, at least 60 % of the beams
  returning within 3 cm of the scan before, and they stay within 0.15 m over 0.5 s either side;
  while the scanner drives everyone counts as walking: see STILL_SHARE below).
Without --people: background beams end in a 0.1 m cell of the registered frame (TOPIC_pose)
  that beams of at least 20 scans hit, the first and the last at least 10 s apart: structure that
  persisted (--cell, --min-scans, --min-span change 0.1, 20 and 10: a short or fast recording
  sees a place for fewer scans). Prints the share of all valid beams removed and of background
  beams kept."""
import bisect, json, math, sys
import rosbag

# Removed labels: dispel filter's 1 dynamic and 2 unknown; dispel clean's `_clean_labels` adds 5
# (moved at another time), 6 (place seen through) and 8 (a leg at range that walked).
REMOVED = (1, 2, 5, 6, 8)
INVALID = 4

def main():
    args = sys.argv[1:]
    if not args or '--scan-topic' not in args:
        sys.exit(__doc__)
    path = args[0]
    topic = args[args.index('--scan-topic') + 1]
    people_topic = args[args.index('--people') + 1] if '--people' in args else None
    radius = float(args[args.index('--person-radius') + 1]) if '--person-radius' in args else 0.4
    bag = rosbag.Bag(path)
    topics = bag.get_type_and_topic_info().topics
    if topic + '_labels' not in topics:
        sys.exit('%s: no %s_labels (filter the recording with dispel filter first)' % (path, topic))
    result = {'recording': path, 'scan_topic': topic}
    if people_topic:
        result.update(annotated(bag, topic, people_topic, radius))
    else:
        if topic + '_pose' not in topics:
            sys.exit('%s: no %s_pose (the background needs the registered poses)' % (path, topic))
        def option(name, default):
            return float(args[args.index(name) + 1]) if name in args else default
        rule = {'cell': option('--cell', 0.1), 'min_scans': int(option('--min-scans', 20)),
                'min_span_s': option('--min-span', 10.0)}
        result.update(rule)
        result.update(background(bag, topic, **rule))
    if '--json' in args:
        print(json.dumps(result, indent=2))
    else:
        for k, v in result.items():
            print('%-28s %s' % (k, '%.4f' % v if isinstance(v, float) else v))

def beam_points(scan):
    for i, r in enumerate(scan.ranges):
        a = scan.angle_min + i * scan.angle_increment
        yield i, r, r * math.cos(a), r * math.sin(a)

# Walking or standing, without odometry (the annotated recordings have none): the scanner stands
# in a scan when at least STILL_SHARE of the beams that return in it and in the scan before return
# within STILL_TOLERANCE_M of each other (person_following_outdoor_1: a median of 81-94 % per 100
# scans where the robot stands, 8-33 % where it drives); a person stands in a scan where the
# scanner stands and every annotation of theirs (by id) within STANDING_WINDOW_S either side lies
# within STANDING_RADIUS_M of this one. Everyone else walks: while the scanner drives, a person is
# counted as walking (on that recording the one annotated person walks ahead of the robot that
# follows them).
STILL_TOLERANCE_M = 0.03
STILL_SHARE = 0.6
STANDING_WINDOW_S = 0.5
STANDING_RADIUS_M = 0.15

def scanner_stands(scan, previous):
    if previous is None or len(previous.ranges) != len(scan.ranges):
        return False
    def valid(r):
        return math.isfinite(r) and scan.range_min <= r <= scan.range_max
    both = [(a, b) for a, b in zip(previous.ranges, scan.ranges) if valid(a) and valid(b)]
    same = sum(1 for a, b in both if abs(a - b) <= STILL_TOLERANCE_M)
    return bool(both) and same >= STILL_SHARE * len(both)

def annotated(bag, topic, people_topic, radius):
    scans = []  # [labels message, [(x, y, id), ...]]
    for t, m, _ in bag.read_messages(topics=[topic + '_labels', people_topic]):
        if t == topic + '_labels':
            scans.append([m, []])
        elif scans:
            scans[-1][1].append((m.pose.position.x, m.pose.position.y, getattr(m, 'id', None)))
    tracks = {}  # id -> ([stamp, ...], [(x, y), ...]) in time order
    for labels, people in scans:
        for x, y, pid in people:
            stamps, places = tracks.setdefault(pid, ([], []))
            stamps.append(labels.header.stamp.to_sec())
            places.append((x, y))
    def standing(pid, stamp, x, y):
        stamps, places = tracks[pid]
        lo = bisect.bisect_left(stamps, stamp - STANDING_WINDOW_S)
        hi = bisect.bisect_right(stamps, stamp + STANDING_WINDOW_S)
        return all(math.hypot(px - x, py - y) <= STANDING_RADIUS_M for px, py in places[lo:hi])
    count = {k: 0 for k in ('person', 'person_removed', 'walking', 'walking_removed', 'standing',
                            'standing_removed', 'background', 'background_kept')}
    annotated_scans = still_scans = 0
    previous = None
    for labels, people in scans:
        stands = scanner_stands(labels, previous)
        previous = labels
        if not people:
            continue
        annotated_scans += 1
        still_scans += stands
        stamp = labels.header.stamp.to_sec()
        still = [stands and pid is not None and standing(pid, stamp, x, y) for x, y, pid in people]
        for i, r, x, y in beam_points(labels):
            label = int(labels.intensities[i])
            if label == INVALID:
                continue
            d, k = min((math.hypot(x - px, y - py), k) for k, (px, py, _) in enumerate(people))
            removed = label in REMOVED
            if d <= radius:
                kind = 'standing' if still[k] else 'walking'
                count['person'] += 1
                count['person_removed'] += removed
                count[kind] += 1
                count[kind + '_removed'] += removed
            elif d > 1.0:
                count['background'] += 1
                count['background_kept'] += not removed
    def share(part, whole):
        return count[part] / max(1, count[whole])
    return {'scans': len(scans), 'annotated_scans': annotated_scans,
            'annotated_scans_scanner_still': still_scans,
            'person_beams': count['person'],
            'person_beams_removed': share('person_removed', 'person'),
            'walking_person_beams': count['walking'],
            'walking_person_beams_removed': share('walking_removed', 'walking'),
            'standing_person_beams': count['standing'],
            'standing_person_beams_removed': share('standing_removed', 'standing'),
            'background_beams': count['background'],
            'background_kept': share('background_kept', 'background')}

def background(bag, topic, cell=0.1, min_scans=20, min_span_s=10.0):
    poses = {}
    # A pose is written with its scan's labels, at the same bag time.
    for _, m, t in bag.read_messages(topics=[topic + '_pose']):
        q = m.pose.pose.orientation
        yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
        poses[t.to_nsec()] = (m.pose.pose.position.x, m.pose.pose.position.y, yaw)
    cells = {}  # cell -> [scans, first stamp, last stamp, last scan]
    beams = []  # (cell, removed)
    valid = removed = 0
    for n, (_, m, t) in enumerate(bag.read_messages(topics=[topic + '_labels'])):
        pose = poses.get(t.to_nsec())
        stamp = m.header.stamp.to_sec()
        for i, r, x, y in beam_points(m):
            label = int(m.intensities[i])
            if label == INVALID:
                continue
            valid += 1
            removed += label in REMOVED
            if pose is None:
                continue
            c, s = math.cos(pose[2]), math.sin(pose[2])
            key = (math.floor((pose[0] + c * x - s * y) / cell),
                   math.floor((pose[1] + s * x + c * y) / cell))
            e = cells.setdefault(key, [0, stamp, stamp, -1])
            if e[3] != n:
                e[0] += 1
                e[3] = n
            e[2] = stamp
            beams.append((key, label in REMOVED))
    persistent = [rem for key, rem in beams
                  if cells[key][0] >= min_scans and cells[key][2] - cells[key][1] >= min_span_s]
    return {'valid_beams': valid, 'removed_share': removed / max(1, valid),
            'background_beams': len(persistent),
            'background_kept': 1.0 - sum(persistent) / max(1, len(persistent))}

if __name__ == '__main__':
    main()
