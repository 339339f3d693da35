#!/usr/bin/env python3
"""Odometry on the optiodom data set (a differential-drive robot with motion-capture truth):
dead reckoning, the CT filter and the omnidirectional filter, each run through `dispel odom` and
compared with `dispel eval-trajectory`.

usage: optiodom_eval.py DISPEL OPTIODOM_DIR [--json] [--odometry-yaml 'key: value, ...']

OPTIODOM_DIR holds session folders (square/..., circular/...), each with *_metadata.csv and
*_run-NN.csv files: rows time_s, x_gt_m, y_gt_m, theta_gt_rad, ticks_right, ticks_left at 20 Hz.
Wheel speeds come from the encoder ticks of each cycle (ticks per revolution = ngear * encRes,
wheel diameters Di, wheel base Li from the metadata). Prints one line per run type and model:
mean final position error, final yaw error and RMSE over runs."""
import csv, glob, json, math, os, statistics, subprocess, sys, tempfile

def metadata(path):
    m = {}
    for row in csv.reader(open(path)):
        if row and row[0]:
            m[row[0]] = [c for c in row[1:] if c != '']
    return m

def convert(run, meta, wheels_path, truth_path):
    ticks_per_rev = float(meta['ngear'][0]) * float(meta['encRes'][0])
    d_right, d_left = float(meta['Di'][0]), float(meta['Di'][1])
    rows = [[float(c) for c in r] for r in csv.reader(open(run)) if r]
    with open(wheels_path, 'w') as w, open(truth_path, 'w') as t:
        w.write('t,v_left,v_right\n'); t.write('t,x,y,yaw\n')
        for i, r in enumerate(rows):
            t.write('%.4f,%.6f,%.6f,%.6f\n' % (r[0], r[1], r[2], r[3]))
            if i == 0:
                continue
            dt = r[0] - rows[i - 1][0]
            # Ticks counted during the cycle that ends at this row: the mean speed over it,
            # stamped at its middle.
            vr = r[4] / ticks_per_rev * math.pi * d_right / dt
            vl = r[5] / ticks_per_rev * math.pi * d_left / dt
            w.write('%.4f,%.6f,%.6f\n' % (r[0] - 0.5 * dt, vl, vr))
    return float(meta['Li'][0])

def main():
    dispel, root = sys.argv[1], sys.argv[2]
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for kind in sorted(os.listdir(root)):
            for session in sorted(glob.glob(os.path.join(root, kind, '*'))):
                meta_files = glob.glob(os.path.join(session, '*_metadata.csv'))
                if not meta_files:
                    continue
                meta = metadata(meta_files[0])
                for run in sorted(glob.glob(os.path.join(session, '*_run-*.csv'))):
                    wheels, truth = os.path.join(tmp, 'w.csv'), os.path.join(tmp, 't.csv')
                    base = convert(run, meta, wheels, truth)
                    cfg = os.path.join(tmp, 'c.yaml')
                    extra = sys.argv[sys.argv.index('--odometry-yaml') + 1] \
                        if '--odometry-yaml' in sys.argv else ''
                    open(cfg, 'w').write('odometry: {track_width_m: %g%s}\n'
                                         % (base, ', ' + extra if extra else ''))
                    for model in ('dead_reckoning', 'ct', 'omni'):
                        out = os.path.join(tmp, 'e.csv')
                        subprocess.run([dispel, 'odom', '--wheels-csv', wheels, '-o', out,
                                        '--model', model, '--config', cfg], check=True,
                                       stdout=subprocess.DEVNULL)
                        r = json.loads(subprocess.run(
                            [dispel, 'eval-trajectory', '--truth', truth, '--estimate', out,
                             '--json'], check=True, capture_output=True, text=True).stdout)
                        results.setdefault((kind, model), []).append(r)
    summary = {}
    for (kind, model), rs in sorted(results.items()):
        s = {k: statistics.mean(r[k] for r in rs) for k in
             ('final_position_error_m', 'final_yaw_error_rad', 'rmse_position_m', 'rmse_yaw_rad',
              'path_length_m')}
        s['runs'] = len(rs)
        summary['%s/%s' % (kind, model)] = s
        if '--json' not in sys.argv:
            print('%-9s %-15s runs %3d  path %5.1f m  final %.3f m  %.4f rad  RMSE %.3f m  %.4f rad'
                  % (kind, model, len(rs), s['path_length_m'], s['final_position_error_m'],
                     s['final_yaw_error_rad'], s['rmse_position_m'], s['rmse_yaw_rad']))
    if '--json' in sys.argv:
        print(json.dumps(summary, indent=2))

if __name__ == '__main__':
    main()
