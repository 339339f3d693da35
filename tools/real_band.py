#!/usr/bin/env python3
"""The filter on the real recordings over a band of neighbouring configurations: a figure of one
configuration can be one draw of the tracks' associations (docs/results.md, "the person_following
figures sit on a knife edge" and "Free space marked something else"), so a change is judged by
the band's mean as well as by the default's own figure.

usage: /usr/bin/python3 tools/real_band.py DISPEL [CONFIG.yaml] [--set section.key=value ...]
                                           [--people-bag person_following_outdoor_1.bag]

The band: CONFIG (default config/default.yaml) with the --set keys, and the same with one of
tracking.match_distance_m: 0.26, tracking.max_gate_m: 1.99, 1.9 or 2.1. For each, `dispel filter`
on data/leg_tracker/negative_2.bag's three lasers (no people: every removed beam is a false
removal; the issue's target is 0.2 % of the valid beams per laser), and with --people-bag on
angusleigh/leg_tracker_benchmarks' person_following_outdoor_1 (fetched for development, never
committed): the followed person's beams removed (all, and those of the person walking) and the
background kept (tools/recording_eval.py).
Prints one row per configuration and the band's mean."""
import json, os, re, statistics, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from filter_sim_eval import set_keys  # noqa: E402

NEGATIVE_2 = 'data/leg_tracker/negative_2.bag'
LASERS = ('/left_scan', '/right_scan', '/rear_scan')
REMOVED, INVALID = (1, 2), 4  # dispel filter's labels (docs/filter_command.md)
NEIGHBOURS = (None, 'tracking.match_distance_m=0.26', 'tracking.max_gate_m=1.99',
              'tracking.max_gate_m=1.9', 'tracking.max_gate_m=2.1')

def removed_beams(dispel, bag, topic, config, tmp):
    """Beams removed (labelled dynamic or unknown) and valid beams (not labelled invalid)."""
    import rosbag
    out = os.path.join(tmp, 'out.bag')
    subprocess.run([dispel, 'filter', bag, '-o', out, '--scan-topic', topic, '--config', config],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    removed = valid = 0
    with rosbag.Bag(out) as b:
        for _, m, _ in b.read_messages([topic + '_labels']):
            labels = m.intensities if m.intensities else m.ranges
            removed += sum(1 for v in labels if int(v) in REMOVED)
            valid += sum(1 for v in labels if int(v) != INVALID)
    os.remove(out)
    return removed, valid

def people(dispel, bag, config, tmp):
    """person_following_outdoor_1: the person's beams removed (all, and while walking: see
    tools/recording_eval.py), the background kept."""
    out = os.path.join(tmp, 'people.bag')
    subprocess.run([dispel, 'filter', bag, '-o', out, '--scan-topic', '/scan_base2', '--config',
                    config], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    here = os.path.dirname(os.path.abspath(__file__))
    r = json.loads(subprocess.run(
        [sys.executable, os.path.join(here, 'recording_eval.py'), out, '--scan-topic',
         '/scan_base2', '--people', '/ground_truth_people_tracks', '--json'],
        check=True, capture_output=True, text=True).stdout)
    os.remove(out)
    return r['person_beams_removed'], r['walking_person_beams_removed'], r['background_kept']

def main():
    args = sys.argv[1:]
    if not args or args[0].startswith('-'):
        sys.exit(__doc__)
    dispel = args[0]
    config = args[1] if len(args) > 1 and not args[1].startswith('-') else 'config/default.yaml'
    settings = [args[i + 1] for i, a in enumerate(args) if a == '--set']
    people_bag = args[args.index('--people-bag') + 1] if '--people-bag' in args else None
    for s in settings:
        if not re.match(r'^\w+\.\w+=.+$', s):
            sys.exit('--set %s: expected section.key=value' % s)
    base = open(config).read()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for neighbour in NEIGHBOURS:
            name = neighbour or os.path.basename(config)
            cfg = os.path.join(tmp, 'config.yaml')
            open(cfg, 'w').write(set_keys(base, settings + ([neighbour] if neighbour else [])))
            counts = [removed_beams(dispel, NEGATIVE_2, t, cfg, tmp) for t in LASERS]
            row = {'config': name, 'negative_2_removed': [c[0] for c in counts],
                   'negative_2_valid': [c[1] for c in counts]}
            if people_bag:
                row['person_removed'], row['walking_removed'], row['background_kept'] = people(
                    dispel, people_bag, cfg, tmp)
            rows.append(row)
            print('%-34s negative_2 removed %s (%s %%)%s' % (
                name, ' / '.join('%d' % c[0] for c in counts),
                ' / '.join('%.2f' % (100.0 * c[0] / c[1]) for c in counts),
                '  person_following: person %.3f (walking %.3f), background %.4f' % (
                    row['person_removed'], row['walking_removed'], row['background_kept'])
                if people_bag else ''),
                flush=True)
    mean = [statistics.mean(r['negative_2_removed'][k] for r in rows) for k in range(3)]
    valid = rows[0]['negative_2_valid']
    print('%-34s negative_2 removed %s (%s %%)%s' % (
        'mean of the band', ' / '.join('%.0f' % m for m in mean),
        ' / '.join('%.2f' % (100.0 * m / v) for m, v in zip(mean, valid)),
        '  person_following: person %.3f (walking %.3f), background %.4f' % (
            statistics.mean(r['person_removed'] for r in rows),
            statistics.mean(r['walking_removed'] for r in rows),
            statistics.mean(r['background_kept'] for r in rows)) if people_bag else ''))

if __name__ == '__main__':
    main()
