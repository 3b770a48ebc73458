"""A regularized impulse response for the linear thermal dynamics, against the search's terms.

System identification's answer to "which lags, which rates" is to estimate the whole
impulse response from the temperature to the drift, with a prior that makes it smooth and
decaying (the TC kernel of Chen, Ohlsson and Ljung, MATLAB's `impulseest`), its scale and
decay chosen by the marginal likelihood. This tool asks whether that carries to other
programmes better than the discrete terms `--features auto` chooses (lags, rates, Shupe
terms, second lags). The response is an FIR on the rate of each thermometer's 100 s mean
(°C/min), one tap every 30 s over an hour; prior covariance c·λ^max(i,j) per thermometer,
λ = exp(−30 s / decay), decay on a grid of 60-8,000 s and c on a grid of 10^−6..10^6; every
other column has a flat prior. The evidence counts each 100 s of the 30 s rows once (the
smoothed noise is correlated over the window).

Two studies on the development laws (`thermodrift simulate --law N --internal-states`,
one chamber cycle for training, five other programmes of the unit as tests; held-out MSE
over the noise floor from 1800 s on, as bench/missing_physics.py judges):

- `--study oracle`: the law's true regressors, its linear dynamic ones (coil rate, axial
  gradient and its rate, radial gradient rate) replaced by the FIR on the axis' own
  thermometer or on all three; the static map, memory, play and turn-on stay the law's
  own. Rows: `oracle` (all true regressors, least squares), `no_linear` (the linear
  dynamic ones dropped, nothing in their place), `fir_own`, `fir_all` (TC prior),
  `ridge_own` (a diagonal prior λ^i instead of TC).
- `--study search`: `--features auto` as fitted (`auto`, its members averaged); least
  squares on the union of its terms (`union`); that union with its linear dynamic terms
  (`rate`, `lagrate`, `lag2rate`, `gradrate`, `grad`, a lag without a static map) replaced
  by the FIR on all three thermometers (`fir`).

    PYTHONPATH=build/python /usr/bin/python3 bench/impulse_response.py --study search --laws 1-20 --jobs 2

About 40 s per law for the search study, 15 s for the oracle's (one core each).
"""

import argparse
import json
import multiprocessing
import os
import sys
import tempfile
import warnings

import numpy as np
import pandas as pd

import thermodrift as td
from missing_physics import PROGRAMMES, REGRESSORS, SETTLE_S, SMOOTH_S, simulate

STEP_S, TAPS = 30, 120  # the FIR's tap spacing and length: an hour
LINEAR_DYNAMICS = ["coil_rate", "axial_gradient", "axial_gradient_rate", "radial_gradient_rate"]
DECAYS_S = [60, 120, 250, 500, 1000, 2000, 4000, 8000]
LOG_SCALES = np.arange(-6, 6.01, 1.0)


def moving_mean(x):
    return pd.Series(np.asarray(x, dtype=float)).rolling(SMOOTH_S, min_periods=1).mean().to_numpy()


def fir_columns(log, channels, rows):
    """Each thermometer's rate of its 100 s mean (°C/min) at the rows and TAPS-1 steps back."""
    blocks = []
    for c in channels:
        level = moving_mean(log["temp_" + c])[rows]
        rate = np.diff(level, prepend=level[0]) / STEP_S * 60.0
        block = np.zeros((len(rows), TAPS))
        for k in range(TAPS):
            block[k:, k] = rate[:len(rows) - k]
        blocks.append(block)
    return np.column_stack(blocks) if blocks else np.zeros((len(rows), 0))


def prior(decay_s, kind):
    i = np.arange(1, TAPS + 1)
    lam = np.exp(-STEP_S / decay_s)
    return lam ** np.maximum(i[:, None], i[None, :]) if kind == "tc" else np.diag(lam ** i)


def fit_with_prior(fixed, fir, y, kind):
    """Posterior mean of [fixed; fir] weights, the FIR's prior scale and decay by the evidence."""
    p = fixed.shape[1]
    spread = fixed.std(0)
    spread[spread == 0] = 1
    a = np.column_stack([fixed / spread, fir])
    per = SMOOTH_S / STEP_S  # rows per independent 100 s mean
    gram, ay, yy, n = a.T @ a / per, a.T @ y / per, y @ y / per, len(y) / per
    blocks = fir.shape[1] // TAPS
    best = None
    for decay in DECAYS_S:
        kernel = np.kron(np.eye(blocks), prior(decay, kind))
        for scale in LOG_SCALES:
            q = np.zeros((a.shape[1],) * 2)
            q[:p, :p] = np.eye(p) * 1e6
            q[p:, p:] = kernel * 10 ** scale
            lq = np.linalg.cholesky(q + 1e-12 * np.eye(len(q)))
            c = np.linalg.cholesky(np.eye(len(q)) + lq.T @ gram @ lq)
            v = np.linalg.solve(c, lq.T @ ay)
            residual = yy - v @ v  # σ² profiled out
            evidence = -0.5 * (n * np.log(residual / n) + 2 * np.sum(np.log(np.diag(c))))
            if best is None or evidence > best[0]:
                best = (evidence, decay, scale, lq @ np.linalg.solve(c.T, v))
    w = best[3].copy()
    w[:p] /= spread
    return w, (best[1], float(best[2]))


def least_squares(x, y):
    return np.linalg.lstsq(x, y, rcond=None)[0]


def judge(predict, logs, axis):
    """Held-out MSE over the noise floor on each programme, from SETTLE_S on (30 s rows)."""
    out = []
    for programme in PROGRAMMES:
        log = logs[programme]
        rows = np.arange(0, len(log), STEP_S)
        gyro = moving_mean(log["gyro_" + axis])[rows]
        drift = moving_mean(log["drift_" + axis])[rows]
        judged = log["time_s"].to_numpy()[rows] >= SETTLE_S
        floor = np.mean((gyro - drift)[judged] ** 2)
        out.append(float(np.mean((predict(log, rows) - gyro)[judged] ** 2) / floor))
    return out


def oracle_study(logs, axis):
    training = logs["cycle"]
    present = [k for k in REGRESSORS if np.abs(training[f"law_{axis}_{k}"]).max() > 0]
    static = [k for k in present if k not in LINEAR_DYNAMICS]
    own, every = [axis], [axis] + [a for a in "xyz" if a != axis]
    variants = {"oracle": (present, [], None), "no_linear": (static, [], None),
                "fir_own": (static, own, "tc"), "fir_all": (static, every, "tc"),
                "ridge_own": (static, own, "diag")}

    def columns(log, names, channels, rows):
        fixed = np.column_stack([np.ones(len(rows))] + [moving_mean(log[f"law_{axis}_{k}"])[rows] for k in names])
        return fixed, fir_columns(log, channels, rows)

    result = {}
    rows = np.arange(0, len(training), STEP_S)
    y = moving_mean(training["gyro_" + axis])[rows]
    for name, (names, channels, kind) in variants.items():
        fixed, fir = columns(training, names, channels, rows)
        if kind:
            w, chosen = fit_with_prior(fixed, fir, y, kind)
        else:
            w, chosen = least_squares(fixed, y), None
        result[name] = {"ratios": judge(lambda log, r: np.column_stack(columns(log, names, channels, r)) @ w,
                                        logs, axis), "prior": chosen}
    return result


def linear_dynamic(term, terms):
    if "*" in term:
        return False
    kind = term.split(":")[0]
    if kind in ("rate", "lagrate", "lag2rate", "gradrate", "grad"):
        return True
    return kind == "lag" and not any(t.startswith(f"hinge:{term.split(':')[1]}:") for t in terms)


def search_study(logs, axis):
    others = [a for a in "xyz" if a != axis]

    def frame(log, channels):
        return log[["time_s", "gyro_" + axis] + ["temp_" + c for c in channels]]

    def fit(channels, features):
        return td.fit(frame(logs["cycle"], channels), model="linear", features=features, gyro=["gyro_" + axis],
                      temp=["temp_" + c for c in channels], progress=False)

    channels = [axis] + others
    auto = fit(channels, "auto")
    node = channels[auto.to_json()["axes"][0]["pipeline"].get("temperature_channel", 1) - 1]
    node_first = [node] + [c for c in channels if c != node]  # terms read the model's first thermometer
    terms = auto.terms["gyro_" + axis]
    kept = [t for t in terms if not linear_dynamic(t, terms)]
    dynamic = [t for t in terms if linear_dynamic(t, terms)]
    # A one-term model's prediction is affine in the term's column: as good as the column in a fit
    # with an intercept.
    single = {t: fit(node_first, [t]) for t in kept + dynamic}

    evaluated = {}  # (log, term) -> the term's column: the union and the FIR fit share the kept terms'

    def column(log, term):
        key = (id(log), term)
        if key not in evaluated:
            evaluated[key] = np.asarray(single[term].drift(frame(log, node_first))).reshape(len(log), -1)[:, 0]
        return evaluated[key]

    def columns(log, names, rows):
        return [np.ones(len(rows))] + [column(log, t)[rows] for t in names]

    training = logs["cycle"]
    rows = np.arange(0, len(training), STEP_S)
    y = moving_mean(training["gyro_" + axis])[rows]
    w_union = least_squares(np.column_stack(columns(training, kept + dynamic, rows)), y)
    w_fir, chosen = fit_with_prior(np.column_stack(columns(training, kept, rows)),
                                   fir_columns(training, channels, rows), y, "tc")
    return {
        "auto": {"ratios": judge(lambda log, r: np.asarray(auto.drift(frame(log, channels))).reshape(len(log), -1)[r, 0],
                                 logs, axis), "terms": terms},
        "union": {"ratios": judge(lambda log, r: np.column_stack(columns(log, kept + dynamic, r)) @ w_union, logs, axis)},
        "fir": {"ratios": judge(lambda log, r: np.column_stack(columns(log, kept, r) + [fir_columns(log, channels, r)])
                                @ w_fir, logs, axis), "prior": chosen, "replaced": dynamic},
    }


def study_law(task):
    law, study, binary = task
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as folder:
        logs = {p: simulate(binary, law, p, folder) for p in ["cycle"] + PROGRAMMES}
    run = oracle_study if study == "oracle" else search_study
    out = []
    for axis in "xyz":
        result = run(logs, axis)
        line = " | ".join(f"{name} {np.median(r['ratios']):.2f}/{max(r['ratios']):.1f}" for name, r in result.items())
        print(f"law {law} {axis}: {line}", flush=True)
        out.append({"law": law, "axis": axis, **result})
    return out


def map_laws(study, tasks, jobs):
    """study(task) for every task, on `jobs` processes; the rows of all in order."""
    if jobs > 1:
        with multiprocessing.Pool(jobs) as pool:
            results = pool.map(study, tasks, chunksize=1)
    else:
        results = [study(t) for t in tasks]
    return [row for law_rows in results for row in law_rows]


def law_parser(doc, laws="1-40"):
    """The options every study over development laws takes: --laws, --jobs, --json, --thermodrift."""
    parser = argparse.ArgumentParser(description=doc.split("\n")[0])
    parser.add_argument("--laws", default=laws, help="development laws, e.g. 1-20 or 3,7,13")
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--json", help="write every axis' figures here")
    parser.add_argument("--thermodrift", default="build/bin/thermodrift")
    return parser


def parse_laws(text):
    laws = []
    for part in text.split(","):
        first, _, last = part.partition("-")
        laws += list(range(int(first), int(last or first) + 1))
    return laws


def summary(rows):
    names = [k for k in rows[0] if k not in ("law", "axis")]
    print(f"\n{len(rows)} axes x {len(PROGRAMMES)} programmes; held-out MSE / noise floor")
    print(f"{'':10s} {'geo mean':>9s} {'median':>7s} {'p90':>7s} {'> 10':>5s} {'> 100':>6s} {'worst':>9s}")
    for name in names:
        r = np.array([v for row in rows for v in row[name]["ratios"]])
        print(f"{name:10s} {np.exp(np.mean(np.log(r))):9.2f} {np.median(r):7.2f} {np.percentile(r, 90):7.1f} "
              f"{np.sum(r > 10):5d} {np.sum(r > 100):6d} {r.max():9.0f}")
    first = names[0]
    per_axis = {n: np.array([np.exp(np.mean(np.log(row[n]["ratios"]))) for row in rows]) for n in names}
    for name in names[1:]:
        better = int(np.sum(per_axis[name] < per_axis[first] / 1.5))
        worse = int(np.sum(per_axis[name] > per_axis[first] * 1.5))
        print(f"{name} against {first}, axes 1.5x better | worse (geometric mean of the five): {better} | {worse}")


def main():
    parser = law_parser(__doc__, laws="1-20")
    parser.add_argument("--study", choices=["oracle", "search"], required=True)
    args = parser.parse_args()
    binary = os.path.abspath(args.thermodrift)
    tasks = [(law, args.study, binary) for law in parse_laws(args.laws)]
    rows = map_laws(study_law, tasks, args.jobs)
    summary(rows)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f)


if __name__ == "__main__":
    sys.exit(main())
