"""DriftModel.compensate on a DataFrame against `thermodrift compensate` on the same log.

    PYTHONPATH=build/python python3 bench/python_compensate.py [--rows 1000000] [--model linear|svr]

Simulates a 50 Hz, 3-axis log of `--rows` rows, fits a model on it (linear: dT, rate and a
900 s lag; svr: the paper's pair, C = 10, σ = 1, at most 64 vectors), then times, best of
three runs each, in this one process and run:
  cli     `thermodrift compensate --model M --data LOG --out OUT` (reads the CSV, writes one);
  python  `model.compensate(df)` on the DataFrame read_log returned (no file either way).
Prints rows/s of each and the ratio python / cli (issue target: at least 0.8).
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time

import thermodrift as td

HERE = os.path.dirname(os.path.abspath(__file__))
CLI = os.environ.get("THERMODRIFT_CLI", os.path.join(HERE, "..", "build", "bin", "thermodrift"))
TEMPS = ["temp_x", "temp_y", "temp_z"]

parser = argparse.ArgumentParser()
parser.add_argument("--rows", type=int, default=1_000_000)
parser.add_argument("--model", default="linear", choices=["linear", "svr"])
args = parser.parse_args()


def best_of(runs, work):
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        work()
        times.append(time.perf_counter() - start)
    return min(times)


with tempfile.TemporaryDirectory() as scratch:
    log = os.path.join(scratch, "log.csv")
    hours = args.rows / 50 / 3600
    cycles = max(1, int(hours / 6.3 + 0.999))
    subprocess.run([CLI, "simulate", "--out", log, "--rate", "50", "--cycles", str(cycles), "--seed", "2"],
                   check=True, capture_output=True)
    frame = td.read_log(log, temp=TEMPS).iloc[: args.rows]
    if len(frame) < args.rows:
        sys.exit(f"simulated {len(frame)} rows, fewer than {args.rows}")
    subset = os.path.join(scratch, "subset.csv")
    with open(log) as source, open(subset, "w") as target:
        for i, line in enumerate(source):
            if i > args.rows:
                break
            target.write(line)
    options = dict(features=["dT", "rate", "lag:900"]) if args.model == "linear" else \
        dict(C=10, sigma=1, max_vectors=64)
    model = td.fit(frame, model=args.model, progress=False, **options)
    model_file = os.path.join(scratch, "model.json")
    model.save(model_file)
    out = os.path.join(scratch, "out.csv")
    cli_seconds = best_of(3, lambda: subprocess.run(
        [CLI, "compensate", "--model", model_file, "--data", subset, "--out", out], check=True,
        capture_output=True))
    python_seconds = best_of(3, lambda: model.compensate(frame))
    cli_rate, python_rate = args.rows / cli_seconds, args.rows / python_seconds
    print(f"compensate, {args.rows} rows, 50 Hz, 3 axes, {args.model} model ({', '.join(model.terms['gyro_x'])})")
    print(f"  cli     {cli_seconds:8.3f} s  {cli_rate / 1e3:9.1f} k rows/s  (CSV in, CSV out)")
    print(f"  python  {python_seconds:8.3f} s  {python_rate / 1e3:9.1f} k rows/s  (DataFrame in, DataFrame out)")
    print(f"  python / cli rows/s: {python_rate / cli_rate:.2f} (target >= 0.8)")
