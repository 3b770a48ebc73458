"""Does `fit`'s figure say when a model will miss other programmes? Its far-from-the-floor warning, measured.

For each law (`thermodrift simulate --law N`), `fit --json` on one chamber cycle (three
axes, `--model linear --features auto` unless told otherwise) gives each axis' expected
held-out MSE over the noise floor estimated from the log (`expected_held_out.x_floor_estimate`,
what `fit` prints and warns on above 2, apps/thermodrift/output.hpp `kFarFromFloor`). The
model is then judged on five other programmes of the unit (held-out MSE over the true
noise floor from 1800 s on, as bench/impulse_response.py judges). Printed: for each
threshold, how many axes it flags and how many of those, and of the others, miss some
programme by more than 10 and 30 times the floor.

    PYTHONPATH=build/python /usr/bin/python3 bench/far_from_floor.py --laws 1-40 --jobs 2

About 15 s per law on one core.
"""

import json
import os
import subprocess
import sys
import tempfile
import warnings

import numpy as np

import thermodrift as td
from impulse_response import judge, law_parser, map_laws, parse_laws
from missing_physics import PROGRAMMES, simulate


def study_law(task):
    law, binary, fit_options = task
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as folder:
        logs = {p: simulate(binary, law, p, folder) for p in ["cycle"] + PROGRAMMES}
        model_file = os.path.join(folder, "model.json")
        run = subprocess.run([binary, "fit", "--data", os.path.join(folder, "cycle.csv"), "--temp",
                              "temp_x,temp_y,temp_z", "--json", "--out", model_file] + fit_options,
                             capture_output=True, text=True, check=True)
        model = td.load_model(model_file)
    result = json.loads(run.stdout)
    predicted = {id(logs[p]): np.asarray(model.drift(logs[p])).reshape(len(logs[p]), -1) for p in PROGRAMMES}  # all axes
    out = []
    for i, axis in enumerate(result["axes"]):
        a = "xyz"[i]
        ratios = judge(lambda log, rows: predicted[id(log)][rows, i], logs, a)
        row = {"law": law, "axis": a, "expected_x_floor": axis["expected_held_out"]["x_floor_estimate"],
               "in_sample_x_floor": axis["mse_after_x_floor"], "ratios": ratios}
        print(f"law {law} {a}: expected held-out {row['expected_x_floor']:.2f} x the floor estimate; "
              f"other programmes {' '.join(f'{r:.1f}' for r in ratios)}", flush=True)
        out.append(row)
    return out


def main():
    parser = law_parser(__doc__)
    parser.add_argument("--fit", default="--model linear --features auto", help="fit's options (one string)")
    args = parser.parse_args()
    tasks = [(law, os.path.abspath(args.thermodrift), args.fit.split()) for law in parse_laws(args.laws)]
    rows = map_laws(study_law, tasks, args.jobs)
    expected = np.array([r["expected_x_floor"] for r in rows])
    worst = np.array([max(r["ratios"]) for r in rows])
    print(f"\n{len(rows)} axes; {np.sum(worst > 10)} miss some programme by more than 10x the floor, "
          f"{np.sum(worst > 30)} by more than 30x")
    print(f"{'expected held-out':>18s} {'axes':>5s} {'> 10':>5s} {'> 30':>5s} {'< 5':>5s} | {'axes':>5s} {'> 10':>5s} {'> 30':>5s}")
    for threshold in (1.5, 2.0, 3.0, 4.0):
        above = expected > threshold
        print(f"{'above ' + format(threshold, 'g'):>18s} {above.sum():5d} {np.sum(worst[above] > 10):5d} "
              f"{np.sum(worst[above] > 30):5d} {np.sum(worst[above] < 5):5d} | {(~above).sum():5d} "
              f"{np.sum(worst[~above] > 10):5d} {np.sum(worst[~above] > 30):5d}  (right: at or below)")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f)


if __name__ == "__main__":
    sys.exit(main())
