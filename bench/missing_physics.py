"""Which physics does a term set miss? One axis of a drawn law, studied against its true states.

The unit of `thermodrift simulate --law LAW` is run through one chamber cycle (training)
and through five other programmes of the same unit (slow, staircase, fast, partial,
wander). For each term set below, a linear model is fitted on the training cycle and
judged on every log by its distance from the true drift: the MSE of its prediction
against the true drift (smoothed as the gyro is, 100 s), from 1800 s on, over the noise
floor of that log. The sets:

- `--features auto` as fitted (all of its averaged members);
- the given --terms (default: the first member of the auto set);
- those terms plus each true regressor of the law in turn (`--internal-states`): where one
  regressor brings the distance down, the terms miss that physics;
- those terms plus every true dynamic regressor (--dynamics) but the one named, in turn.

A true regressor enters the fit as a made-up temperature channel read by `grad:A-Z`, Z a
channel of zeros, so it goes through the same smoothing as the model's own terms.
--quiet fits on the noise-free drift instead of the gyro (the thermometers keep their
noise): what the terms can hold, apart from what the noise lets a fit find.

    PYTHONPATH=build/python /usr/bin/python3 bench/missing_physics.py --law 13 --axis y --quiet

One law and axis takes 10-60 s (one core).
"""

import argparse
import os
import subprocess
import sys
import tempfile
import warnings

import numpy as np
import pandas as pd

import thermodrift as td

PROGRAMMES = ["slow", "staircase", "fast", "partial", "wander"]
REGRESSORS = ["dTc", "dTc^2", "dTc^3", "step", "coil_rate", "axial_gradient", "axial_gradient_rate",
              "radial_gradient_rate", "memory", "play", "turn_on"]
SMOOTH_S, SETTLE_S = 100, 1800


def simulate(binary, law, profile, folder):
    path = os.path.join(folder, f"{profile}.csv")
    subprocess.run([binary, "simulate", "--law", str(law), "--profile", profile, "--cycles", "1",
                    "--internal-states", "--out", path], check=True, capture_output=True)
    return pd.read_csv(path)


class Study:
    def __init__(self, logs, axis, quiet):
        self.logs, self.axis, self.quiet = logs, axis, quiet
        self.scale = {}  # each regressor divided by its largest magnitude in training: a plausible temperature

    def frame(self, log, regressors):
        axis = self.axis
        temps = ["temp_" + axis] + ["temp_" + a for a in "xyz" if a != axis]
        out = log[["time_s"] + temps].copy()
        out["gyro"] = log["drift_" + axis] if self.quiet else log["gyro_" + axis]
        out["temp_zero"] = 0.0
        names = temps + ["temp_zero"]
        for k in regressors:
            column = log[f"law_{axis}_{k}"]
            scale = self.scale.setdefault(k, max(1e-9, float(self.logs["cycle"][f"law_{axis}_{k}"].abs().max())))
            out["temp_" + k] = column / scale
            names.append("temp_" + k)
        return out, names

    def distance(self, model, log, frame):
        predicted = np.asarray(model.drift(frame)).reshape(len(log), -1)[:, 0]
        axis = self.axis
        window = max(1, round(SMOOTH_S / float(np.median(np.diff(log["time_s"])))))  # rows in SMOOTH_S
        true = log["drift_" + axis].rolling(window, min_periods=1).mean().to_numpy()
        noise = (log["gyro_" + axis] - log["drift_" + axis]).rolling(window, min_periods=1).mean().to_numpy()
        judged = log["time_s"].to_numpy() >= SETTLE_S
        return float(np.mean((predicted - true)[judged] ** 2) / np.mean(noise[judged] ** 2))

    def judge(self, terms, regressors=()):
        regressors = list(regressors)
        frame, names = self.frame(self.logs["cycle"], regressors)
        if terms != "auto":
            terms = list(terms) + [f"grad:{5 + i}-4" for i in range(len(regressors))]
            temps = names
        else:
            temps = names[:3]
        model = td.fit(frame, model="linear", features=terms, gyro=["gyro"], temp=temps, progress=False)
        row = [self.distance(model, self.logs["cycle"], frame)]
        for programme in PROGRAMMES:
            other, _ = self.frame(self.logs[programme], regressors)
            row.append(self.distance(model, self.logs[programme], other))
        return model, row


def first_member(terms):
    """The auto set's first member: up to the second node's level term."""
    for i, term in enumerate(terms):
        if i > 0 and term.split(":")[0] in ("lag", "lag2") and "*" not in term and term != terms[0] and \
                any(t.startswith(("hinge:", "nodehinge:")) for t in terms[i + 1:i + 3]):
            return terms[:i]
    return terms


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--law", type=int, required=True)
    parser.add_argument("--axis", choices=list("xyz"), required=True)
    parser.add_argument("--terms", help="comma-separated terms (default: the auto set's first member)")
    parser.add_argument("--dynamics", default="axial_gradient_rate,radial_gradient_rate,memory,play,turn_on",
                        help="the true regressors of the leave-one-out rows")
    parser.add_argument("--quiet", action="store_true", help="fit on the noise-free drift")
    parser.add_argument("--thermodrift", default="build/bin/thermodrift")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as folder:
        logs = {p: simulate(args.thermodrift, args.law, p, folder) for p in ["cycle"] + PROGRAMMES}
    study = Study(logs, args.axis, args.quiet)
    print(f"law {args.law} {args.axis}: distance from the true drift / noise floor, from {SETTLE_S} s on"
          f"{' (fitted on the noise-free drift)' if args.quiet else ''}")
    print(f"{'set':44s} {'train':>8s}" + "".join(f" {p:>9s}" for p in PROGRAMMES))

    def show(name, row):
        print(f"{name:44s} {row[0]:8.2f}" + "".join(f" {v:9.2f}" for v in row[1:]), flush=True)

    auto, row = study.judge("auto")
    auto_terms = auto.terms["gyro"]
    show("auto", row)
    terms = args.terms.split(",") if args.terms else first_member(auto_terms)
    print("terms:", " ".join(t for t in terms if "hinge" not in t), file=sys.stderr)
    show("terms", study.judge(terms)[1])
    present = [k for k in REGRESSORS if float(logs["cycle"][f"law_{args.axis}_{k}"].abs().max()) > 0]
    for k in present:
        show("terms + " + k, study.judge(terms, [k])[1])
    dynamics = [k for k in args.dynamics.split(",") if k in present]
    show("terms + true dynamics", study.judge(terms, dynamics)[1])
    for k in dynamics:
        show(f"terms + true dynamics - {k}", study.judge(terms, [d for d in dynamics if d != k])[1])


if __name__ == "__main__":
    main()
