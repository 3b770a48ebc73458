"""The next cycle cut from a running recording: what its start costs, and what `evaluate --log-start` repairs.

A log cut from a longer recording (the second cycle of a two-cycle run, evaluated on its
own) starts with the unit's thermal states wherever the first cycle left them, while the
model's lags start in equilibrium at its first row. This tool judges the same rows three
ways, per axis of each development law (`thermodrift simulate --law N --cycles 2`; `fit
--model linear --features auto` on the first cycle, which is the one-cycle run; `evaluate
--json`, MSE after over the true noise floor of the judged rows, the second cycle from
1800 s after its start on):

- `cut`: the second cycle as a log of its own, `--settle 1800 --log-start power-on`;
- `carried`: the whole recording, `--settle` up to the same rows, so the lags run through
  the first cycle (what the tool advises when the recording is at hand);
- `running`: the cut log with `--log-start running` (each thermometer's initial line, held
  within its range over the log, for 6 h before it), `--settle 1800`;
- `estimated`: the cut log with `--log-start estimated` (evaluate's default: power-on's
  prediction plus the weight in [0, 1] of running's difference from it that fits the
  first 1800 s, which are not judged), `--settle 1800`.

    PYTHONPATH=build/python /usr/bin/python3 bench/cut_log_start.py --laws 1-40 --jobs 2

About 20 s per law on one core.
"""

import json
import os
import subprocess
import tempfile

import numpy as np
import pandas as pd

from impulse_response import law_parser, map_laws, moving_mean, parse_laws
from missing_physics import SETTLE_S

TEMPERATURES = "temp_x,temp_y,temp_z"
WAYS = ("cut", "carried", "running", "estimated")


def study_law(task):
    law, binary = task
    with tempfile.TemporaryDirectory() as folder:
        path = {name: os.path.join(folder, name + ".csv") for name in ("first", "whole", "cut")}
        for cycles, name in ((1, "first"), (2, "whole")):
            subprocess.run([binary, "simulate", "--law", str(law), "--cycles", str(cycles), "--out", path[name]],
                           check=True, capture_output=True)
        whole = pd.read_csv(path["whole"])
        first_cycle = len(pd.read_csv(path["first"]))  # the one-cycle run is the two-cycle run's first cycle
        whole.iloc[first_cycle:].to_csv(path["cut"], index=False)
        model = os.path.join(folder, "model.json")
        subprocess.run([binary, "fit", "--data", path["first"], "--temp", TEMPERATURES, "--model", "linear",
                        "--features", "auto", "--out", model], check=True, capture_output=True)
        start_s = float(whole["time_s"].iloc[first_cycle])
        options = {"cut": [path["cut"], "--settle", str(SETTLE_S), "--log-start", "power-on"],
                   "carried": [path["whole"], "--settle", str(start_s + SETTLE_S), "--log-start", "power-on"],
                   "running": [path["cut"], "--settle", str(SETTLE_S), "--log-start", "running"],
                   "estimated": [path["cut"], "--settle", str(SETTLE_S), "--log-start", "estimated"]}
        mse = {}
        for way, (data, *rest) in options.items():
            run = subprocess.run([binary, "evaluate", "--model", model, "--data", data, "--temp", TEMPERATURES,
                                  "--json"] + rest, capture_output=True, text=True, check=True)
            mse[way] = [axis["mse_after"] for axis in json.loads(run.stdout)["axes"]]
    judged = whole["time_s"].to_numpy() >= start_s + SETTLE_S
    out = []
    for i, axis in enumerate("xyz"):
        noise = moving_mean(whole["gyro_" + axis]) - moving_mean(whole["drift_" + axis])
        floor = float(np.mean(noise[judged] ** 2))
        row = {"law": law, "axis": axis, **{way: mse[way][i] / floor for way in WAYS}}
        print(f"law {law} {axis}: " + ", ".join(f"{way} {row[way]:.2f}" for way in WAYS), flush=True)
        out.append(row)
    return out


def main():
    args = law_parser(__doc__).parse_args()
    rows = map_laws(study_law, [(law, os.path.abspath(args.thermodrift)) for law in parse_laws(args.laws)], args.jobs)
    print(f"\n{len(rows)} axes: MSE after over the true floor, the second cycle from {SETTLE_S} s on")
    for way in WAYS:
        r = np.array([row[way] for row in rows])
        print(f"{way:8s} geometric mean {np.exp(np.mean(np.log(r))):.2f}  median {np.median(r):.2f}  "
              f"p90 {np.percentile(r, 90):.1f}  above 10 {np.sum(r > 10)}  worst {r.max():.0f}")
    cut, carried = np.array([row["cut"] for row in rows]), np.array([row["carried"] for row in rows])
    for way in ("running", "estimated"):
        r = np.array([row[way] for row in rows])
        closer = np.sum(np.abs(np.log(r / carried)) < np.abs(np.log(cut / carried)))
        print(f"{way} against cut: {np.sum(r < cut / 1.5)} axes better by more than 1.5x, {np.sum(r > 1.5 * cut)} "
              f"worse; closer to carried on {closer}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f)


if __name__ == "__main__":
    main()
