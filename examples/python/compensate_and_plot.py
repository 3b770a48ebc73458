"""Fit a drift model on one chamber run, compensate another, and plot both.

    PYTHONPATH=build/python python3 examples/python/compensate_and_plot.py [--out DIR]
        [--train LOG --test LOG --temp temp_x,temp_y,temp_z] [--features auto]

Without logs it simulates two runs of the simulator's default unit (different noise
seeds), so it runs anywhere. It writes to DIR (default: the current folder):
  before_after.png  the 100 s-smoothed gyro rate of the test run, before and after
                    compensation, per axis;
  allan.png         the Allan deviation of the test run's raw and compensated rates;
  model.json        the model, as `thermodrift fit --out` writes it.
"""

import argparse
import os

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import thermodrift as td  # noqa: E402

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", default=".")
parser.add_argument("--train")
parser.add_argument("--test")
parser.add_argument("--temp", default="temp_x,temp_y,temp_z")
parser.add_argument("--features", default="auto", help="auto (default), or a list such as dT,rate,lag:600")
parser.add_argument("--model", default="linear", help="linear (default), stepwise or svr")
args = parser.parse_args()
os.makedirs(args.out, exist_ok=True)
temps = args.temp.split(",")

# 1. The logs: a training run and a run the model does not see.
if args.train and args.test:
    train, test = td.read_log(args.train, temp=temps), td.read_log(args.test, temp=temps)
else:
    train = td.simulate(seed=3, cycles=1)
    test = td.simulate(seed=4, cycles=1)
    # The simulated file's columns (time_s, temp_chamber, temp_*, gyro_*, drift_*): fit takes
    # the gyro* columns and, named here, the axes' own thermometers.

# 2. Fit: one model per axis. With features="auto" the thermal-lag terms are chosen per
#    axis by blocked cross-validation (docs/features.md); the paper's pair is "dT,rate".
features = args.features if args.features == "auto" else args.features.split(",")
model = td.fit(train, model=args.model, features=features, temp=temps)
model.save(os.path.join(args.out, "model.json"))
print(model)
for axis, terms in model.terms.items():
    print(f"  {axis}: {', '.join(terms)}")

# 3. Held out: metrics on the other run (the first 30 min left out while the lags settle).
result = model.evaluate(test, settle=1800, temp=temps)
for axis in result["axes"]:
    floor = axis.get("mse_after_x_floor")
    print(f"  {axis['name']}: MSE {axis['mse_before']:.4g} -> {axis['mse_after']:.4g} (°/h)² held out"
          + (f", {floor:.3g} x the noise floor estimate" if floor else ""))

# 4. Compensate the held-out run, row by row as the navigation computer would.
out = model.compensate(test, temp=temps)
time_column = "time_s" if "time_s" in test.columns else "time"
hours = (test[time_column] - test[time_column].iloc[0]) / 3600
rate_hz = 1 / np.median(np.diff(test[time_column]))
window = max(1, int(round(100 * rate_hz)))  # the paper's 100 s moving average

fig, axes = plt.subplots(len(model.axes), 1, figsize=(9, 2.6 * len(model.axes)), sharex=True)
for ax, name in zip(np.atleast_1d(axes), model.axes):
    before = test[name].rolling(window).mean()
    after = out[f"{name}_comp_dph"].rolling(window).mean()
    ax.plot(hours, before - before.mean(), label="before (mean removed)", lw=0.8)
    ax.plot(hours, after - after.mean(), label="after compensation", lw=0.8)
    ax.set_ylabel(f"{name} (°/h)")
    ax.legend(loc="upper right", fontsize=8)
np.atleast_1d(axes)[-1].set_xlabel("time (h)")
fig.suptitle("Held-out run, 100 s moving average")
fig.tight_layout()
fig.savefig(os.path.join(args.out, "before_after.png"), dpi=110)

# 5. Allan deviation of the raw and compensated rates (the field's view of what is left).
fig, ax = plt.subplots(figsize=(7, 5))
for name in model.axes:
    raw = td.allan_deviation(test[name], rate_hz)
    comp = td.allan_deviation(out[f"{name}_comp_dph"].iloc[window:], rate_hz)
    line, = ax.loglog(raw["tau_s"], raw["deviation"], "--", lw=1, label=f"{name} raw")
    ax.loglog(comp["tau_s"], comp["deviation"], "-", lw=1.5, color=line.get_color(), label=f"{name} compensated")
ax.set_xlabel("τ (s)")
ax.set_ylabel("Allan deviation (°/h)")
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(os.path.join(args.out, "allan.png"), dpi=110)
print(f"wrote {args.out}/before_after.png, {args.out}/allan.png, {args.out}/model.json")
