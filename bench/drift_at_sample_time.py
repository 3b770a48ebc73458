"""How far the compensated rate is from the true drift, with a build that advances the
model's smoothed prediction to the sample's time (--thermodrift) against one that does not
(--before: a build of a commit before 2026-11-29). Held out: `fit --model linear --features
auto` (or --fit OPTIONS) on one simulated cycle of a unit, `compensate` of another programme of it (a new
run: other noise, programme seed 303; the default unit: only other noise).

Per axis, over the rows from 1800 s on, centered MSE over the noise floor (the variance of
the gyro noise after the 100 s trailing mean) of
  raw:      the compensator's drift minus the true drift, sample by sample;
  smoothed: the same, both averaged over 100 s (what a user smoothing the compensated
            column sees, less the noise);
  evaluate: the smoothed true drift minus the model's smoothed prediction (what
            `evaluate` judges, less the noise).
Law 0 is the simulator's default unit. docs/export.md, "The drift at the sample's time".

    PYTHONPATH=build/python /usr/bin/python3 bench/drift_at_sample_time.py \\
        --before OLD/build/bin/thermodrift --laws 0-8
"""
import argparse
import os
import subprocess
import tempfile

import numpy as np
import pandas as pd

from impulse_response import parse_laws


def run(command):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise SystemExit(' '.join(command) + '\n' + result.stderr[-2000:])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--thermodrift', default='build/bin/thermodrift')
    parser.add_argument('--before', required=True, help='a build without the advance')
    parser.add_argument('--laws', default='0-8', help='law seeds (0: the default unit), e.g. 0-8,9001-9012')
    parser.add_argument('--fit', default='--model linear --features auto', help="fit's model options")
    parser.add_argument('--json', help='write the table here')
    args = parser.parse_args()
    temps = ['--temp', 'temp_x,temp_y,temp_z']
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for law in parse_laws(args.laws):
            unit = ['--law', str(law)] if law else []
            training, test, model = (os.path.join(work, f'{name}{law}') for name in ('training.csv', 'test.csv', 'model.json'))
            run([args.thermodrift, 'simulate', *unit, '--cycles', '1', '--seed', '101', '--out', training])
            run([args.thermodrift, 'simulate', *unit, '--cycles', '1', '--seed', '202',
                 *(['--profile-seed', '303'] if law else []), '--out', test])
            run([args.thermodrift, 'fit', '--data', training, *temps, *args.fit.split(), '--out', model])
            compensated = {}
            for name, binary in (('before', args.before), ('now', args.thermodrift)):
                out = os.path.join(work, f'{name}{law}.csv')
                run([binary, 'compensate', '--model', model, '--data', test, *temps, '--out', out])
                compensated[name] = pd.read_csv(out)
            log = compensated['before']
            judged = slice(1800, None)
            smooth = lambda values: pd.Series(values).rolling(100).mean().to_numpy()
            for axis in 'xyz':
                gyro, drift = log[f'gyro_{axis}'].to_numpy(), log[f'drift_{axis}'].to_numpy()
                floor = np.var(smooth(gyro - drift)[judged])
                def ratio(error):
                    error = error[judged]
                    error = error[np.isfinite(error)]
                    return np.mean((error - error.mean()) ** 2) / floor
                before = gyro - compensated['before'][f'gyro_{axis}_comp_dph'].to_numpy()  # the smoothed prediction
                now = gyro - compensated['now'][f'gyro_{axis}_comp_dph'].to_numpy()
                rows.append({'law': law, 'axis': axis,
                             'raw_before': ratio(before - drift), 'raw_now': ratio(now - drift),
                             'smoothed_before': ratio(smooth(drift - before)), 'smoothed_now': ratio(smooth(drift - now)),
                             'evaluate': ratio(smooth(drift) - before)})
    table = pd.DataFrame(rows)
    pd.set_option('display.width', 200)
    print(table.round(3).to_string(index=False))
    columns = ['raw_before', 'raw_now', 'smoothed_before', 'smoothed_now', 'evaluate']
    print('median ' + '  '.join(f'{c} {table[c].median():.3g}' for c in columns))
    print(f"smoothed: now closer to the true drift on {(table.smoothed_now < table.smoothed_before).sum()} "
          f"of {len(table)} axes")
    if args.json:
        table.to_json(args.json, orient='records', indent=1)


if __name__ == '__main__':
    main()
