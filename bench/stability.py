#!/usr/bin/python3
"""How much a method's held-out figures move when its training data are drawn again.

    /usr/bin/python3 bench/stability.py [--method linear] RUN.json RUN.json [RUN.json ...]

Each RUN.json is a `generalization_bench --json` run on the same seeds, differing only in
`--training-noise K` (the training cycle's noise drawn again; the test logs are the same
in every run). For every ratio (law, test, axis) present in all runs it prints the spread
across runs (largest over smallest ratio), how many ratios exceed 4, 10 and 100 in every
run and in at least one, and each run's geometric mean. A choice stable under
resampling keeps the spread near 1; a spread of 10 means one noise draw of the same
chamber cycle decides between a good model and a bad one. The "next cycle, carried"
diagnostic is left out, as in the summary table's groups. docs/generalization.md,
"Stable under resampling?", has the figures.
"""
import argparse
import json
import math
import statistics
import sys


def ratios(path, method):
    with open(path) as file:
        run = json.load(file)
    out = {}
    for law in run["laws"]:
        for result in law["methods"]:
            if result["method"] != method or result.get("error"):
                continue
            for test in result["tests"]:
                if test["test"] == "next cycle, carried":
                    continue
                for axis, ratio in enumerate(test["ratio"]):
                    out[(law["seed"], test["test"], axis)] = ratio
    return run, out


def quantile(values, p):
    """Type 7 (linear between order statistics), as generalization_bench's tables."""
    return statistics.quantiles(values, n=100, method="inclusive")[round(p * 100) - 1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", help="generalization_bench --json files")
    parser.add_argument("--method", default="linear")
    args = parser.parse_args()
    if len(args.runs) < 2:
        sys.exit("stability.py: give at least two runs")
    loaded = [ratios(path, args.method) for path in args.runs]
    seeds = {run.get("seeds") for run, _ in loaded}
    if len(seeds) > 1:
        sys.exit(f"stability.py: the runs are on different seeds: {sorted(map(str, seeds))}")
    keys = sorted(set(loaded[0][1]).intersection(*(r for _, r in loaded[1:])))
    if not keys:
        sys.exit(f"stability.py: no ratio of method {args.method} is in every run")
    for path, (run, found) in zip(args.runs, loaded):
        values = [found[k] for k in keys]
        mean = math.exp(sum(math.log(v) for v in values) / len(values))
        print(f"{path}: --training-noise {run.get('training_noise', 0)}, "
              f"geometric mean {mean:.2f}, median {quantile(values, 0.5):.2f}, "
              f"p90 {quantile(values, 0.9):.1f}, worst {max(values):.0f}")
    spread = [max(r[k] for _, r in loaded) / min(r[k] for _, r in loaded) for k in keys]
    print(f"\n{len(keys)} ratios ({args.method}) in {len(loaded)} runs; largest / smallest across runs: "
          f"median {quantile(spread, 0.5):.2f}, p90 {quantile(spread, 0.9):.1f}, worst {max(spread):.0f}; "
          f"above 1.5: {sum(s > 1.5 for s in spread)}")
    for threshold in (4, 10, 100):
        counts = [sum(r[k] > threshold for _, r in loaded) for k in keys]
        print(f"  ratios above {threshold:>3}: in every run {sum(c == len(loaded) for c in counts)}, "
              f"in at least one {sum(c > 0 for c in counts)}")


if __name__ == "__main__":
    main()
