"""Held-out accuracy of `thermodrift fit --features auto` on the second law family.

For each law of bench/foreign_laws.py: the unit runs two chamber cycles (~1 °C/min);
cycle 1 is the training log, cycle 2 the "next cycle"; five more runs of the same unit
(powered on anew, noise of their own) follow the other programmes (slow, fast,
staircase, random, sine). The CLI fits each method on cycle 1 and `evaluate --settle
1800` judges every test log; the ratio is the held-out MSE over the true noise floor of
the same rows (the 100 s trailing mean of gyro minus true drift, from 1800 s on).

    /usr/bin/python3 bench/foreign_bench.py [--seeds development|acceptance|S,S,...] [--limit N]
        [--methods linear,svr] [--jobs 2] [--fit-option=--node-channel=any ...] [--json FILE]

Everything the CLI sees is a CSV file and its command line, as a user's would be.
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import foreign_laws as fl  # noqa: E402

SETTLE_S = 1800.0
OTHER_KINDS = ["slow", "fast", "staircase", "random", "sine"]
CARRIED = "next cycle, carried"  # a diagnostic, not a test
COLUMNS = ["--gyro", "gyro_x,gyro_y,gyro_z", "--temp", "temp_x,temp_y,temp_z"]


def run(command):
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)}: exit {done.returncode}: {done.stderr.strip()[-400:]}")
    return done.stdout


def law(seed, args):
    unit = fl.draw_unit(seed, args.without)
    result = {"seed": seed, "methods": {}, "describe": fl.describe(unit)}
    with tempfile.TemporaryDirectory(prefix=f"foreign{seed}-") as folder:
        programme = fl.draw_profile("cycle", unit, seed, cycles=2)
        columns, starts = fl.simulate(unit, programme, noise_seed=fl_seed(seed, 1))
        second = int(round(starts[1]))
        train = os.path.join(folder, "train.csv")
        fl.write_csv(fl.rows(columns, 0, second), train)
        tests = []
        next_rows = fl.rows(columns, second, len(columns["time_s"]))
        tests.append(("next cycle", next_rows))
        for k, kind in enumerate(OTHER_KINDS):
            profile = fl.draw_profile(kind, unit, fl_seed(seed, 20 + k))
            tests.append((kind, fl.simulate(unit, profile, noise_seed=fl_seed(seed, 2 + k))[0]))
        paths = []
        for name, test_columns in tests:
            path = os.path.join(folder, name.replace(" ", "_") + ".csv")
            fl.write_csv(test_columns, path)
            paths.append((name, path, fl.noise_floor(test_columns, int(SETTLE_S)), SETTLE_S, args.log_start))
        # A diagnostic beside the tests: cycle 2 judged with every state carried from cycle 1,
        # as a running compensator would carry it (the whole run, cycle 1 inside the settle).
        whole = os.path.join(folder, "whole_run.csv")
        fl.write_csv(columns, whole)
        paths.append((CARRIED, whole, fl.noise_floor(columns, second + int(SETTLE_S)), second + SETTLE_S, "power-on"))
        for method in args.methods:
            model = os.path.join(folder, f"{method}.json")
            start = time.monotonic()
            try:
                fitted = json.loads(run([args.thermodrift, "fit", "--data", train, *COLUMNS, "--model", method,
                                         "--features", "auto", "--threads", "1", "--seed", "1", *args.fit_option,
                                         "--out", model, "--json"]))
            except RuntimeError as error:
                result["methods"][method] = {"error": str(error)}
                continue
            seconds = time.monotonic() - start
            judged = {}
            for name, path, floor, settle, log_start in paths:
                metrics = json.loads(run([args.thermodrift, "evaluate", "--model", model, "--data", path, *COLUMNS,
                                          "--settle", str(settle), "--log-start", log_start, "--json"]))
                judged[name] = [a["mse_after"] / f for a, f in zip(metrics["axes"], floor)]
            result["methods"][method] = {
                "seconds": seconds,
                "tests": judged,
                "terms": [a.get("terms", []) for a in fitted["axes"]],
                "in_sample": [a.get("mse_after_x_floor") for a in fitted["axes"]],
            }
    return result


def fl_seed(seed, stream):
    return seed * 1000 + stream


def quantile(values, q):
    values = sorted(values)
    if not values:
        return math.nan
    position = q * (len(values) - 1)
    low = int(math.floor(position))
    high = min(low + 1, len(values) - 1)
    return values[low] + (values[high] - values[low]) * (position - low)


def summary(laws, methods):
    lines = ["held-out MSE / true noise floor, per axis: median  p90  worst (law)"]
    lines.append(f"{'method':8} {'test':15} {'n':>3} | " + " | ".join(f"{a}: median    p90   worst  (law)" for a in fl.AXES))
    groups = [("next cycle", ["next cycle"]), ("other profiles", OTHER_KINDS)] + [(k, [k]) for k in OTHER_KINDS]
    groups.append((CARRIED, [CARRIED]))
    for method in methods:
        for group, names in groups:
            cells = []
            count = 0
            for a in range(3):
                values = []
                for law in laws:
                    m = law["methods"].get(method, {})
                    for name in names:
                        if name in m.get("tests", {}):
                            values.append((m["tests"][name][a], law["seed"]))
                count = len(values)
                if not values:
                    cells.append(" " * 30)
                    continue
                ratios = [v for v, _ in values]
                worst = max(values)
                cells.append(f"{quantile(ratios, 0.5):9.3g} {quantile(ratios, 0.9):6.3g} {worst[0]:7.4g} ({worst[1]:>4})")
            lines.append(f"{method:8} {group:15} {count:3} | " + " | ".join(cells))
        seconds = [law["methods"][method]["seconds"] for law in laws if "seconds" in law["methods"].get(method, {})]
        failed = sum(1 for law in laws if "error" in law["methods"].get(method, {}))
        if seconds:
            lines.append(f"{method:8} fit seconds (3 axes, --threads 1): median {quantile(seconds, 0.5):.1f}, worst "
                         f"{max(seconds):.1f}; failed fits: {failed}")
        everything = [r for law in laws for name, t in law["methods"].get(method, {}).get("tests", {}).items()
                      if name != CARRIED for r in t]
        if everything:
            geo = math.exp(sum(math.log(max(r, 1e-12)) for r in everything) / len(everything))
            lines.append(f"{method:8} all held-out ratios: geometric mean {geo:.3g}, > 5: {sum(r > 5 for r in everything)}, "
                         f"> 10: {sum(r > 10 for r in everything)} of {len(everything)}")
    return "\n".join(lines)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", default="development")
    parser.add_argument("--limit", type=int, default=0)
    parser.add_argument("--methods", default="linear")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--thermodrift", default=os.path.join(here, "..", "build", "bin", "thermodrift"))
    parser.add_argument("--fit-option", action="append", default=[],
                        help="passed to fit as it stands, e.g. --fit-option=--node-channel=any")
    parser.add_argument("--without", default="", help="physics left out of every law (foreign_laws.draw_unit), a diagnostic")
    parser.add_argument("--log-start", default="estimated", choices=["estimated", "power-on", "running"],
                        help="evaluate --log-start of the test logs (the carried diagnostic starts at power-on); "
                             "tables before 2026-11-28 were measured with power-on, then the default")
    parser.add_argument("--json")
    args = parser.parse_args()
    args.without = [w for w in args.without.split(",") if w]
    args.fit_option = [part for option in args.fit_option for part in option.split("=", 1)]
    if args.seeds == "development":
        seeds = fl.DEVELOPMENT_SEEDS
    elif args.seeds == "acceptance":
        seeds = fl.ACCEPTANCE_SEEDS
    else:
        seeds = [int(s) for s in args.seeds.split(",")]
    if args.limit:
        seeds = seeds[:args.limit]
    args.methods = args.methods.split(",")
    print(f"foreign_bench: {len(seeds)} law(s) ({args.seeds}), methods {','.join(args.methods)}, {args.jobs} job(s)"
          + (f", fit options {' '.join(args.fit_option)}" if args.fit_option else ""), flush=True)
    laws = []
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        for result in pool.map(lambda s: law(s, args), seeds):
            worst = {m: max((max(t) for n, t in r.get("tests", {}).items() if n != CARRIED), default=math.nan)
                     for m, r in result["methods"].items()}
            print(f"law {result['seed']}: worst " + ", ".join(f"{m} {w:.3g}" for m, w in worst.items()), file=sys.stderr,
                  flush=True)
            laws.append(result)
    print(summary(laws, args.methods))
    if args.json:
        with open(args.json, "w") as out:
            json.dump({"seeds": args.seeds, "settle_s": SETTLE_S, "laws": laws}, out, indent=1)


if __name__ == "__main__":
    main()
