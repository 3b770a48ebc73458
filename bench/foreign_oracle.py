"""What one cycle and the thermometers hold on the second law family: the law's own terms.

For each law of bench/foreign_laws.py, the logs of bench/foreign_bench.py (cycle 1 of a
two-cycle run to train on; the next cycle and five other programmes to test on), and in
place of an identification the law's own terms (foreign_laws.law_terms), each a column
fitted by least squares on the training cycle's 100 s means, judged like the methods
(held-out MSE of the 100 s mean from 1800 s on, over the true noise floor). The states
the terms are evaluated on are

- `true`: the network's true states (a bound on the coefficients one cycle gives);
- `L0`, `L50`, ...: rebuilt from the log's three thermometers by a Kalman filter on the
  unit's own network (the air, which is not read, a ramp whose rate is a random walk; its
  intensity chosen by the training cycle's likelihood), reading the thermometers up to
  that many seconds after the row (a fixed-lag smoother; `Linf`: the whole run).

Nothing is identified: the structure and every constant are the law's. Where `L50` (what a
100 s mean judged by `evaluate` reads) is far from the floor, no method that reads the
thermometers could be near it (docs/generalization.md, "What the thermometers hold").

    /usr/bin/python3 bench/foreign_oracle.py [--seeds development|acceptance|S,S,...] [--limit N]
        [--states true,0,50,inf] [--jobs 2] [--json FILE]
"""

import argparse
import json
import math
import os
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from scipy.linalg import expm, solve_discrete_are

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import foreign_bench as fb  # noqa: E402
import foreign_laws as fl  # noqa: E402

WINDOW = 100  # rows of the 100 s mean at 1 Hz
INTENSITIES = [1e-12, 1e-11, 1e-10, 1e-9, 1e-8, 1e-7, 1e-6]  # (°C/s)²/s


def trailing_mean(column):
    """The 100 s trailing mean from the first full window on (row WINDOW - 1 is row 0)."""
    return fl.trailing_mean(column, WINDOW)


class Filter:
    """A steady-state Kalman filter on the unit's network, driven by an air whose rate is a
    random walk, measured by the three thermometers. State: air, its rate, the network."""

    def __init__(self, unit, intensity, dt=1.0):
        A, b, c = fl.network(unit)
        n = A.shape[0]
        m = n + 2
        f = np.zeros((m, m))
        f[0, 1] = 1.0
        f[2:, 0] = b
        f[2:, 2:] = A
        drive = np.concatenate([[0.0, 0.0], c])
        big = np.zeros((m + 1, m + 1))
        big[:m, :m] = f * dt
        big[:m, m] = drive * dt
        e = expm(big)
        self.phi, self.offset = e[:m, :m], e[:m, m]
        van_loan = np.zeros((2 * m, 2 * m))
        van_loan[:m, :m] = -f * dt
        van_loan[1, m + 1] = intensity * dt
        van_loan[m:, m:] = f.T * dt
        v = expm(van_loan)
        q = v[m:, m:].T @ v[:m, m:]
        # A little noise on every state (1e-5 °C per √s) keeps the smoother stable: on a state
        # the air alone drives, the backward gain would be the inverse of its decay.
        q = 0.5 * (q + q.T) + 1e-10 * np.eye(m)
        self.h = np.zeros((3, m))
        for a in range(3):
            self.h[a, 2 + 2 + 3 * fl.SHELLS + a] = 1.0
        noise = unit["noise"]
        r = (noise["temperature_noise"] ** 2 + noise["temperature_resolution"] ** 2 / 12) * np.eye(3)
        predicted = solve_discrete_are(self.phi.T, self.h.T, q, r)
        self.s = self.h @ predicted @ self.h.T + r
        self.gain = predicted @ self.h.T @ np.linalg.inv(self.s)
        filtered = (np.eye(m) - self.gain @ self.h) @ predicted
        self.smoother = filtered @ self.phi.T @ np.linalg.pinv(predicted)  # Rauch-Tung-Striebel gain
        self.m = m

    def run(self, thermometers):
        """Filtered states row by row (row k from thermometer rows 0..k) and the log-likelihood."""
        rows = thermometers.shape[0]
        x = np.full(self.m, thermometers[0].mean())
        x[1] = 0.0
        out = np.empty((rows, self.m))
        keep = np.eye(self.m) - self.gain @ self.h
        s_inv = np.linalg.inv(self.s)
        _, logdet = np.linalg.slogdet(self.s)
        loglik = 0.0
        for k in range(rows):
            if k > 0:
                x = self.phi @ x + self.offset
            innovation = thermometers[k] - self.h @ x
            loglik -= 0.5 * (innovation @ s_inv @ innovation + logdet + 3 * math.log(2 * math.pi))
            x = keep @ x + self.gain @ thermometers[k]
            out[k] = x
        return out, loglik

    def ahead(self, filtered, rows_ahead):
        """Row k from thermometer rows up to k + rows_ahead (None: every row)."""
        rows = filtered.shape[0]
        # x(j | later) = g_j + C x(j + 1 | later), g_j = x_f(j) - C (phi x_f(j) + offset)
        g = filtered - (filtered @ self.phi.T + self.offset) @ self.smoother.T
        whole = np.empty_like(filtered)
        whole[-1] = filtered[-1]
        for j in range(rows - 2, -1, -1):
            whole[j] = g[j] + self.smoother @ whole[j + 1]
        if rows_ahead is None or rows_ahead >= rows:
            return whole
        out = whole.copy()  # the last rows read to the end of the run
        valid = rows - rows_ahead
        acc = np.zeros((valid, self.m))
        power = np.eye(self.m)
        for i in range(rows_ahead):
            acc += g[i:i + valid] @ power.T
            power = self.smoother @ power
        acc += filtered[rows_ahead:rows_ahead + valid] @ power.T
        out[:valid] = acc
        return out


def design(unit, t, states, air):
    """Per axis: the law's terms as columns (one per term, the bias a constant), rows x terms."""
    out = []
    for terms in fl.law_terms(unit, t, states, air):
        names = sorted(terms)
        out.append(np.column_stack([np.ones(len(t)) if name == "bias" else terms[name] for name in names]))
    return out


def law(seed, state_kinds, intensities=INTENSITIES):
    unit = fl.draw_unit(seed)
    programme = fl.draw_profile("cycle", unit, seed, cycles=2)
    truth = {}
    columns, starts = fl.simulate(unit, programme, noise_seed=fb.fl_seed(seed, 1), states_out=truth)
    second = int(round(starts[1]))
    runs = [("train", columns, truth)]
    for k, kind in enumerate(fb.OTHER_KINDS):
        profile = fl.draw_profile(kind, unit, fb.fl_seed(seed, 20 + k))
        states = {}
        runs.append((kind, fl.simulate(unit, profile, noise_seed=fb.fl_seed(seed, 2 + k), states_out=states)[0], states))

    def thermometers(cols):
        return np.column_stack([cols[f"temp_{a}"] for a in fl.AXES])

    # The intensity: the training cycle's likelihood (the filter run on cycle 1 alone).
    best = max(intensities, key=lambda q: Filter(unit, q).run(thermometers(fl.rows(columns, 0, second)))[1])
    kalman = Filter(unit, best)
    result = {"seed": seed, "describe": fl.describe(unit), "air_rate_intensity": best, "states": {}}
    filtered_runs = {}
    for kind in state_kinds:
        designs = {}
        for name, cols, states in runs:
            t = cols["time_s"]
            if kind == "true":
                x, air = states["states"], states["air"]
            else:
                if name not in filtered_runs:
                    filtered_runs[name] = kalman.run(thermometers(cols))[0]
                filtered = filtered_runs[name]
                estimate = kalman.ahead(filtered, None if kind == "inf" else int(kind))
                x, air = estimate[:, 2:], estimate[:, 0]
            designs[name] = design(unit, t, x, air)
        tests = {}
        # (name, run, first row, last row): the next cycle is rows second.. of the training run
        judged = [("next cycle", "train", second, len(columns["time_s"]))]
        judged += [(name, name, 0, len(cols["time_s"])) for name, cols, _ in runs[1:]]
        all_columns = {name: cols for name, cols, _ in runs}
        floors = {name: fl.noise_floor(fl.rows(all_columns[source], begin, end), int(fb.SETTLE_S))
                  for name, source, begin, end in judged}
        first = int(fb.SETTLE_S) - (WINDOW - 1)  # the first judged row of the 100 s means
        for a in range(3):
            gyro = trailing_mean(columns[f"gyro_{fl.AXES[a]}"][:second])
            x = trailing_mean(designs["train"][a][:second])
            scale = np.linalg.norm(x, axis=0)
            scale[scale == 0] = 1
            beta = np.linalg.lstsq(x / scale, gyro, rcond=1e-12)[0] / scale
            for name, source, begin, end in judged:
                cols = all_columns[source]
                y = trailing_mean(cols[f"gyro_{fl.AXES[a]}"][begin:end])
                prediction = trailing_mean(designs[source][a][begin:end]) @ beta
                mse = float(np.mean((y[first:] - prediction[first:]) ** 2))
                tests.setdefault(name, [None] * 3)[a] = mse / floors[name][a]
        result["states"][kind] = tests
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", default="development")
    parser.add_argument("--limit", type=int, default=0)
    parser.add_argument("--states", default="true,0,50,inf")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--json")
    args = parser.parse_args()
    seeds = {"development": fl.DEVELOPMENT_SEEDS, "acceptance": fl.ACCEPTANCE_SEEDS}.get(args.seeds)
    if seeds is None:
        seeds = [int(s) for s in args.seeds.split(",")]
    if args.limit:
        seeds = seeds[:args.limit]
    kinds = args.states.split(",")
    laws = []
    with ProcessPoolExecutor(args.jobs) as pool:
        for law_result in pool.map(law, seeds, [kinds] * len(seeds)):
            worst = {kind: max(max(v) for v in law_result["states"][kind].values()) for kind in kinds}
            print(f"law {law_result['seed']}: air rate intensity {law_result['air_rate_intensity']:g}; worst "
                  + ", ".join(f"{kind} {w:.3g}" for kind, w in worst.items()), file=sys.stderr, flush=True)
            laws.append(law_result)
    print("held-out MSE / true noise floor of the law's own terms, per axis: median  p90  worst (law)")
    for kind in kinds:
        label = "true states" if kind == "true" else f"rebuilt, {kind} s ahead"
        for group in ("next cycle", "other programmes"):
            cells = []
            for a in range(3):
                values = [(r["states"][kind][name][a], r["seed"]) for r in laws for name in r["states"][kind]
                          if (name == "next cycle") == (group == "next cycle")]
                ratios = [v for v, _ in values]
                worst = max(values)
                cells.append(f"{np.median(ratios):7.2f} {fb.quantile(ratios, 0.9):7.2f} {worst[0]:8.1f} ({worst[1]})")
            print(f"{label:24} {group:17} | " + " | ".join(cells))
        every = [v for r in laws for name in r["states"][kind] for v in r["states"][kind][name]]
        print(f"{label:24} ratios above 10: {sum(v > 10 for v in every)} of {len(every)}; "
              f"geometric mean {math.exp(np.mean(np.log(every))):.2f}")
    if args.json:
        with open(args.json, "w") as out:
            json.dump({"seeds": seeds, "states": kinds, "laws": laws}, out, indent=1)


if __name__ == "__main__":
    main()
