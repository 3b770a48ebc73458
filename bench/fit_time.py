"""Wall time of `thermodrift fit --model svr --features auto` on single chamber cycles.

Issue 13's target: 3 axes of a 6-hour 1 Hz log in at most 60 s on 2 cores. For each
development law (default 2, 8 and 29: 5.0, 6.6 and 7.5 hours, the last two the heaviest
searches of laws 1-40), `thermodrift simulate --law N --profile cycle --cycles 1` writes
the log, then the fit runs as a user would run it (all cores), one fit at a time. Each
row: the log's length, wall and CPU seconds, peak memory, and wall / 60 s. With
`--previous BIN`, that build fits the same logs in the same run, interleaved with this one
(previous, current, per law), and the rows add its wall time and the ratio previous /
current. The timings are the machine's at that moment: run it on an idle machine.

    /usr/bin/python3 bench/fit_time.py [--laws 2,8,29] [--model svr] [--previous BIN]
        [--thermodrift BIN] [--json FILE]
"""

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

TARGET_S = 60.0
COLUMNS = ["--gyro", "gyro_x,gyro_y,gyro_z", "--temp", "temp_x,temp_y,temp_z"]


def timed(command):
    """Runs `command`; its wall seconds, CPU seconds and peak resident MB."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.monotonic()
    done = subprocess.run(command, capture_output=True, text=True)
    wall = time.monotonic() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)}: exit {done.returncode}: {done.stderr.strip()[-400:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    # ru_maxrss of RUSAGE_CHILDREN is the largest child's so far, in kB: a fit is the largest.
    return {"wall_s": wall, "cpu_s": cpu, "peak_mb": after.ru_maxrss / 1024.0}


def fit(binary, log, model, out):
    return timed([binary, "fit", "--data", log, *COLUMNS, "--model", model, "--features", "auto", "--out", out])


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--laws", default="2,8,29")
    parser.add_argument("--model", default="svr")
    parser.add_argument("--thermodrift", default=os.path.join(here, "..", "build", "bin", "thermodrift"))
    parser.add_argument("--previous", help="another build's thermodrift, timed on the same logs in the same run")
    parser.add_argument("--json")
    args = parser.parse_args()
    laws = [int(law) for law in args.laws.split(",")]
    print(f"fit_time: `fit --model {args.model} --features auto` on one cycle of development law(s) "
          f"{','.join(map(str, laws))}; {os.cpu_count()} core(s); target {TARGET_S:.0f} s wall", flush=True)
    header = f"{'law':>4} {'hours':>6} {'rows':>7} | {'wall s':>7} {'cpu s':>7} {'peak MB':>8} {'/ target':>8}"
    if args.previous:
        header += f" | {'previous wall s':>15} {'previous / now':>14}"
    print(header)
    rows = []
    with tempfile.TemporaryDirectory(prefix="thermodrift-fit-time-") as scratch:
        for law in laws:
            log = os.path.join(scratch, f"law{law}.csv")
            done = subprocess.run([args.thermodrift, "simulate", "--law", str(law), "--profile", "cycle", "--cycles", "1",
                                   "--out", log], capture_output=True, text=True, check=True)
            # "wrote N rows (H h, 1 cycle) to ...": the log's size, as simulate reports it.
            words = done.stderr.split()
            row = {"law": law, "rows": int(words[words.index("wrote") + 1]),
                   "hours": float(words[words.index("wrote") + 3].lstrip("("))}
            if args.previous:
                row["previous"] = fit(args.previous, log, args.model, os.path.join(scratch, "previous.json"))
            row["current"] = fit(args.thermodrift, log, args.model, os.path.join(scratch, "current.json"))
            now = row["current"]
            line = (f"{law:>4} {row['hours']:>6.1f} {row['rows']:>7} | {now['wall_s']:>7.1f} {now['cpu_s']:>7.1f} "
                    f"{now['peak_mb']:>8.0f} {now['wall_s'] / TARGET_S:>8.2f}")
            if args.previous:
                line += f" | {row['previous']['wall_s']:>15.1f} {row['previous']['wall_s'] / now['wall_s']:>14.2f}"
            print(line, flush=True)
            rows.append(row)
    over = [row["law"] for row in rows if row["current"]["wall_s"] > TARGET_S]
    print(f"over {TARGET_S:.0f} s: " + (", ".join(f"law {law}" for law in over) if over else "none"))
    if args.json:
        with open(args.json, "w") as out:
            json.dump({"model": args.model, "target_s": TARGET_S, "laws": rows}, out, indent=1)


if __name__ == "__main__":
    sys.exit(main())
