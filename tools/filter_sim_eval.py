#!/usr/bin/env python3
"""The filter on simulated scenarios against their ground truth, means over seeds: the figures of
README's "Results on the simulated thesis hall" and docs/simulator.md.

usage: filter_sim_eval.py DISPEL SCENARIO.yaml CONFIG.yaml [--seeds N] [--set section.key=value ...]
                          [--scenario-set section.key=value ...] [--scale-to-scanner]
                          [--laser-only]

For each seed 1..N (default 5): dispel sim -> dispel filter --config -> dispel eval --json. --set
changes one key of the configuration, e.g. --set classification.presumption=guilt
--set tracking.matching=nearest_neighbour; --scenario-set changes one of the scenario, e.g.
--scenario-set robot.speed_mps=1.5; --scale-to-scanner is passed to dispel filter; --laser-only
passes --odom-topic none (the registration alone, seeded by a constant-velocity guess). Prints mean preservation and rejection and the median
over seeds of each run's median detection latency."""
import json, os, re, statistics, subprocess, sys, tempfile

def set_keys(text, settings):
    """YAML text with each section.key=value of settings set: a key the file already sets in that
    section is replaced (YAML keys must be unique), else added to the section."""
    for s in settings:
        key, value = s.split('=', 1)
        section, name = key.split('.', 1)
        block = re.search(r'^%s:\s*(#.*)?\n((?:[ \t]+.*\n|[ \t]*\n)*)' % section, text, re.M)
        if block and re.search(r'^[ \t]+%s:' % re.escape(name), block.group(2), re.M):
            body = re.sub(r'^([ \t]+)%s:.*$' % re.escape(name), r'\g<1>%s: %s' % (name, value),
                          block.group(2), count=1, flags=re.M)
            text = text[:block.start(2)] + body + text[block.end(2):]
        elif re.search(r'^%s:\s*(#.*)?$' % section, text, re.M):
            text = re.sub(r'^(%s:\s*(#.*)?)$' % section, r'\1\n  %s: %s' % (name, value), text,
                          count=1, flags=re.M)
        else:
            text += '\n%s:\n  %s: %s\n' % (section, name, value)
    return text

def main():
    args = sys.argv[1:]
    if len(args) < 3 or any(a.startswith('-') for a in args[:3]):
        sys.exit(__doc__)
    dispel, scenario, config = args[0], args[1], args[2]
    seeds = int(args[args.index('--seeds') + 1]) if '--seeds' in args else 5
    settings = [args[i + 1] for i, a in enumerate(args) if a == '--set']
    scenario_settings = [args[i + 1] for i, a in enumerate(args) if a == '--scenario-set']
    filter_args = ['--scale-to-scanner'] if '--scale-to-scanner' in args else []
    if '--laser-only' in args:  # The recording's odometry is not used: registration alone.
        filter_args += ['--odom-topic', 'none']
    text = set_keys(open(config).read(), settings)
    scenario_text = set_keys(open(scenario).read(), scenario_settings)
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        cfg = os.path.join(tmp, 'config.yaml')
        open(cfg, 'w').write(text)
        scenario = os.path.join(tmp, os.path.basename(scenario))
        open(scenario, 'w').write(scenario_text)
        for seed in range(1, seeds + 1):
            sim, out = os.path.join(tmp, 'sim.bag'), os.path.join(tmp, 'filtered.bag')
            subprocess.run([dispel, 'sim', scenario, '-o', sim, '--seed', str(seed)], check=True,
                           stdout=subprocess.DEVNULL)
            stats = os.path.join(tmp, 'stats.json')
            subprocess.run([dispel, 'filter', sim, '-o', out, '--config', cfg, '--stats', stats] +
                           filter_args,
                           check=True, stdout=subprocess.DEVNULL)
            used = json.load(open(stats))['config']
            for s in settings:  # What the filter reports it used is what was asked for.
                key, value = s.split('=', 1)
                name = key.split('.', 1)[1]
                if name in used and str(used[name]) != value:
                    sys.exit('%s: the filter used %s = %s, not %s' % (config, name, used[name], value))
            runs.append(json.loads(subprocess.run(
                [dispel, 'eval', '--truth', sim, '--result', out, '--json'], check=True,
                capture_output=True, text=True).stdout))
    def mean(key):
        values = [r[key] for r in runs if r[key] is not None]
        return statistics.mean(values) if values else float('nan')
    latencies = [r['detection_latency_s']['median'] for r in runs
                 if r['detection_latency_s']['median'] is not None]
    print('%s, %s%s, seeds 1-%d: preservation %.4f, rejection %.4f, latency %s' % (
        os.path.basename(scenario), os.path.basename(config),
        ''.join(' --set ' + s for s in settings) +
        ''.join(' --scenario-set ' + s for s in scenario_settings) +
        ''.join(' ' + a for a in filter_args), seeds, mean('preservation_rate'),
        mean('rejection_rate'), '%.2f s' % statistics.median(latencies) if latencies else '-'))
    for seed, r in enumerate(runs, 1):
        lat = r['detection_latency_s']['median']
        print('  seed %d: preservation %.4f, rejection %s, latency %s' % (
            seed, r['preservation_rate'],
            '-' if r['rejection_rate'] is None else '%.4f' % r['rejection_rate'],
            '-' if lat is None else '%.2f s' % lat))

if __name__ == '__main__':
    main()
