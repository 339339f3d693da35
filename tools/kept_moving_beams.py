#!/usr/bin/env python3
"""Where the moving beams a filter kept are: a simulated bag's ground truth against the filter's
labels, the moving beams (truth code 1) counted by actor, by range (whole metres), by the beams
the actor returned in that scan, and the labels of those kept. The figures of docs/results.md,
"Where the kept moving beams are".

usage: /usr/bin/python3 tools/kept_moving_beams.py SIM.bag FILTERED.bag [--scan-topic /scan]

SIM.bag from `dispel sim` (its <scan>_truth and <scan>_truth_actor), FILTERED.bag from
`dispel filter` (its <scan>_labels: 0 static, 1 dynamic, 2 unknown, 3 no object, 4 invalid)."""
import collections, math, sys

import rosbag

def values(msg):
    return msg.intensities if msg.intensities else msg.ranges

def main():
    args = sys.argv[1:]
    if len(args) < 2 or args[0].startswith('-') or args[1].startswith('-'):
        sys.exit(__doc__)
    topic = args[args.index('--scan-topic') + 1] if '--scan-topic' in args else '/scan'
    truth, actor, ranges, labels = {}, {}, {}, {}
    for t, m, _ in rosbag.Bag(args[0]).read_messages([topic, topic + '_truth', topic + '_truth_actor']):
        into = {topic: ranges, topic + '_truth': truth, topic + '_truth_actor': actor}[t]
        into[m.header.stamp.to_nsec()] = m.ranges if t == topic else values(m)
    for _, m, _ in rosbag.Bag(args[1]).read_messages([topic + '_labels']):
        labels[m.header.stamp.to_nsec()] = values(m)
    if not truth or not labels:
        sys.exit('%s: no %s_truth in %s or no %s_labels in %s' % (topic, topic, args[0], topic, args[1]))
    by_actor, by_range, by_count = (collections.defaultdict(lambda: [0, 0]) for _ in range(3))
    kept_labels = collections.Counter()
    for stamp in sorted(truth):
        if stamp not in labels or stamp not in actor or stamp not in ranges:
            continue
        tr, ac, lb, rg = truth[stamp], actor[stamp], labels[stamp], ranges[stamp]
        moving = [i for i in range(len(tr)) if int(tr[i]) == 1]
        per_actor = collections.Counter(int(ac[i]) for i in moving)
        for i in moving:
            removed = int(lb[i]) == 1 or int(lb[i]) == 2
            a = int(ac[i])
            metre = int(rg[i]) if math.isfinite(rg[i]) else -1
            for table, key in ((by_actor, a), (by_range, metre), (by_count, min(per_actor[a], 40))):
                table[key][0] += 1
                table[key][1] += removed
            if not removed:
                kept_labels[int(lb[i])] += 1
    for name, table in (('actor', by_actor), ('range_m', by_range), ('actor_beams_in_scan', by_count)):
        print('%-20s %s' % (name, ' '.join('%s:%d/%d' % (k, v[1], v[0]) for k, v in sorted(table.items()))))
    print('%-20s %s' % ('labels_of_kept', ' '.join('%d:%d' % kv for kv in sorted(kept_labels.items()))))

if __name__ == '__main__':
    main()
