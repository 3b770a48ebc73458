"""A second family of drift laws, written apart from the C++ simulator.

The C++ law family (sim/law_family.hpp) is what the identification was developed on; a
method that reaches the floor only there has learnt its forms. This family is written
independently, in Python, with physics that family cannot produce:

- the coil is a radial diffusion problem (SHELLS concentric shells, not 1-3 lumped nodes),
  so its temperature has a continuum of time constants, and the Shupe term is the rate of
  the gradient across the shells;
- one housing and one mount are shared by the three coils and load each other; a
  thermometer sits on the housing, on the mount (a path the coils are not on), on its
  own coil's outer shell or on another coil's;
- statics: polynomial, exponential, a Gaussian bump or a logistic step;
- a rate sensitivity that changes with temperature, and an asymmetric (heating/cooling)
  rate response;
- hysteresis as a Preisach sum of three plays, or a relay with a threshold followed by a
  lag;
- a static radial-gradient term and a turn-on transient;
- noise: ARW, flicker-like bias (five Gauss-Markov processes from 10 s to 10^5 s),
  quantization, thermometer noise and resolution;
- programmes: chamber cycles, slow and fast ramps, staircases, random setpoints, sines.

Seeds: DEVELOPMENT_SEEDS to develop on, ACCEPTANCE_SEEDS to judge; disjoint. Every draw
comes from numpy's PCG64 seeded with (seed, stream), so a seed gives the same log on every
machine with the same numpy.

    /usr/bin/python3 bench/foreign_laws.py --seed 3 --profile cycle --cycles 2 --out log.csv
"""

import argparse
import math
import sys

import numpy as np
from scipy.linalg import expm

SHELLS = 6
DEVELOPMENT_SEEDS = list(range(1, 31))
ACCEPTANCE_SEEDS = list(range(5001, 5041))
PROFILE_KINDS = ["cycle", "slow", "fast", "staircase", "random", "sine"]
AXES = "xyz"


def rng_for(seed, stream):
    return np.random.Generator(np.random.PCG64([int(seed), int(stream)]))


def log_uniform(rng, low, high):
    return math.exp(rng.uniform(math.log(low), math.log(high)))


def signed(rng, low, high):
    return (1.0 if rng.random() < 0.5 else -1.0) * rng.uniform(low, high)


# ------------------------------------------------------------------------------ unit

def draw_unit(seed, without=()):
    """The whole 3-axis unit: thermal network, drift laws, noise. A plain dict.

    without: physics to leave out (a diagnostic: which of it a method fails on), any of
    "asymmetry", "tempco", "hysteresis", "turn_on", "self_heating", "shupe", "gradient",
    "far_sensor" (every thermometer on the housing), "diffusion" (a coil of one lumped node)."""
    rng = rng_for(seed, 1)
    unit = {
        "seed": seed,
        "min_c": rng.uniform(-45, -30),
        "max_c": rng.uniform(55, 70),
        "reference_c": rng.uniform(15, 25),
        "housing_tau": log_uniform(rng, 100, 1000),
        "housing_heat": rng.uniform(0, 4) if rng.random() < 0.7 else 0.0,
        "coil_load": rng.uniform(0.0, 0.3),
        "mount_tau": log_uniform(rng, 100, 2000),
        "mount_to_housing": rng.uniform(0.0, 1.0),
        "axes": [],
    }
    for a in range(3):
        axis = {
            "link_tau": log_uniform(rng, 50, 1500),
            "diffusion_tau": log_uniform(rng, 200, 3000),
            "coil_heat": rng.uniform(0, 1.0) if rng.random() < 0.4 else 0.0,
            "sensor_tau": log_uniform(rng, 1, 30),
            "bias": rng.uniform(-1, 1),
        }
        site = rng.random()
        if site < 0.45:
            axis["sensor_site"] = "housing"
        elif site < 0.65:
            axis["sensor_site"] = "mount"
        elif site < 0.85:
            axis["sensor_site"] = f"coil{a}"
        else:
            axis["sensor_site"] = f"coil{(a + 1 + int(rng.integers(0, 2))) % 3}"
        kind = rng.choice(["poly", "exp", "bump", "logistic"])
        static = {"kind": str(kind), "a1": signed(rng, 0.005, 0.05)}
        if kind == "poly":
            static["a2"] = signed(rng, 0.0, 6e-4)
            static["a3"] = signed(rng, 0.0, 1e-5) if rng.random() < 0.5 else 0.0
        elif kind == "exp":
            static["theta"] = rng.uniform(15, 40)
            static["size"] = signed(rng, 0.3, 1.5)  # °/h at 45 °C above the reference
        elif kind == "bump":
            static["size"] = signed(rng, 0.2, 1.0)
            static["centre"] = rng.uniform(unit["min_c"] + 15, unit["max_c"] - 15)
            static["width"] = rng.uniform(6, 20)
        else:
            static["size"] = signed(rng, 0.3, 1.5)
            static["centre"] = rng.uniform(unit["min_c"] + 15, unit["max_c"] - 15)
            static["width"] = rng.uniform(3, 10)
        axis["static"] = static
        axis["rate"] = signed(rng, 0.2, 2.5)  # °/h per °C/min of the coil's mean
        axis["rate_tempco"] = signed(rng, 0.0, 0.01) if rng.random() < 0.5 else 0.0  # per °C
        axis["asymmetry"] = signed(rng, 0.1, 0.8) if rng.random() < 0.4 else 0.0
        axis["shupe"] = signed(rng, 0.5, 5.0) if rng.random() < 0.8 else 0.0  # per °C/min of the gradient
        axis["gradient"] = signed(rng, 0.02, 0.3) if rng.random() < 0.4 else 0.0  # per °C of the gradient
        hysteresis = rng.random()
        if hysteresis < 0.35:
            axis["hysteresis"] = {
                "kind": "preisach",
                "widths": [rng.uniform(0.3, 1), rng.uniform(1, 3), rng.uniform(3, 8)],
                "weights": [signed(rng, 0.02, 0.15) for _ in range(3)],
            }
        elif hysteresis < 0.7:
            axis["hysteresis"] = {
                "kind": "relay",
                "threshold": log_uniform(rng, 0.05, 0.3),  # °C/min
                "tau": log_uniform(rng, 100, 2000),
                "size": signed(rng, 0.05, 0.4),
            }
        else:
            axis["hysteresis"] = {"kind": "none"}
        axis["turn_on"] = signed(rng, 0.05, 0.4) if rng.random() < 0.5 else 0.0
        axis["turn_on_tau"] = log_uniform(rng, 100, 1200)
        unit["axes"].append(axis)
    for axis in unit["axes"]:
        if "asymmetry" in without: axis["asymmetry"] = 0.0
        if "tempco" in without: axis["rate_tempco"] = 0.0
        if "hysteresis" in without: axis["hysteresis"] = {"kind": "none"}
        if "turn_on" in without: axis["turn_on"] = 0.0
        if "self_heating" in without: axis["coil_heat"] = 0.0
        if "shupe" in without: axis["shupe"] = 0.0
        if "gradient" in without: axis["gradient"] = 0.0
        if "far_sensor" in without: axis["sensor_site"] = "housing"
        if "diffusion" in without: axis["diffusion_tau"] = 1.0
    if "self_heating" in without: unit["housing_heat"] = 0.0
    unit["without"] = sorted(without)
    unit["noise"] = {
        "arw": log_uniform(rng, 0.002, 0.008),  # °/√h
        "bias_instability": log_uniform(rng, 0.003, 0.02),  # °/h
        "quantization_arcsec": rng.uniform(0.01, 0.05) if rng.random() < 0.6 else 0.0,
        "temperature_noise": log_uniform(rng, 0.001, 0.02),
        "temperature_resolution": float(rng.choice([0.001, 0.01, 0.0625])),
    }
    return unit


def describe(unit):
    lines = [f"foreign law {unit['seed']}: range {unit['min_c']:.0f}..{unit['max_c']:.0f} °C, housing τ "
             f"{unit['housing_tau']:.0f} s (+{unit['housing_heat']:.1f} °C), mount τ {unit['mount_tau']:.0f} s"]
    for a, axis in enumerate(unit["axes"]):
        # A ramp's steady lag of the coil's mean temperature behind the housing: the link's
        # time constant plus the diffusion's share, (N - 1)(2N - 1) / (6 N²) of its τ (N shells).
        delay = axis["link_tau"] + axis["diffusion_tau"] * (SHELLS - 1) * (2 * SHELLS - 1) / (6 * SHELLS ** 2)
        lines.append(f"  {AXES[a]}: coil τ {axis['link_tau']:.0f} s through its link, diffusion "
                     f"{axis['diffusion_tau']:.0f} s (mean delay {delay:.0f} s behind the housing), sensor on "
                     f"{axis['sensor_site']} ({axis['sensor_tau']:.0f} s); static {axis['static']}; rate "
                     f"{axis['rate']:.2f} (tempco {axis['rate_tempco']:.4f}, asym {axis['asymmetry']:.2f}); shupe "
                     f"{axis['shupe']:.2f}; gradient {axis['gradient']:.3f}; hysteresis {axis['hysteresis']}; turn-on "
                     f"{axis['turn_on']:.2f} ({axis['turn_on_tau']:.0f} s)")
    return "\n".join(lines)


# ------------------------------------------------------------------------------ programmes

def draw_profile(kind, unit, seed, cycles=1):
    """Knots (t in s, setpoint in °C) of a piecewise-linear chamber programme, and the cycle starts."""
    rng = rng_for(seed, 2 + PROFILE_KINDS.index(kind))
    lo, hi = unit["min_c"], unit["max_c"]
    start = rng.uniform(18, 25)
    times, temps, cycle_starts = [0.0], [start], []

    def go(target, rate, soak_min):
        now, level = times[-1], temps[-1]
        times.append(now + abs(target - level) / rate * 60.0)
        temps.append(target)
        if soak_min > 0:
            times.append(times[-1] + soak_min * 60.0)
            temps.append(target)

    def soak(minutes):
        times.append(times[-1] + minutes * 60.0)
        temps.append(temps[-1])

    if kind == "sine":
        hours = rng.uniform(7, 9) * cycles
        centre = 0.5 * (lo + hi)
        periods = [rng.uniform(1, 5) * 3600 for _ in range(2)]
        amplitudes = [rng.uniform(0.1, 0.22) * (hi - lo) for _ in range(2)]
        phases = [rng.uniform(0, 2 * math.pi) for _ in range(2)]
        t = np.arange(0.0, hours * 3600 + 1, 60.0)
        value = centre + sum(a * (np.sin(2 * math.pi * t / p + f) - math.sin(f)) for a, p, f in zip(amplitudes, periods, phases))
        ramp_in = np.clip(t / 3600.0, 0, 1)  # from the start temperature to the sines over an hour
        value = start + ramp_in * (value - start)
        return list(t), list(value), [0.0]

    for _ in range(cycles):
        cycle_starts.append(times[-1])
        if kind in ("cycle", "slow", "fast"):
            if kind == "cycle":
                rate = rng.uniform(0.8, 1.2)
                hot, cold = rng.uniform(hi - 10, hi), rng.uniform(lo, lo + 10)
                soaks = lambda: rng.uniform(40, 90)
            elif kind == "slow":
                rate = rng.uniform(0.3, 0.6)
                hot, cold = rng.uniform(40, min(55, hi)), rng.uniform(max(-25, lo), -10)
                soaks = lambda: rng.uniform(30, 60)
            else:
                rate = rng.uniform(2.5, 3.5)
                hot, cold = rng.uniform(hi - 5, hi), rng.uniform(lo, lo + 5)
                soaks = lambda: rng.uniform(20, 40)
            soak(soaks())
            first, second = (hot, cold) if rng.random() < 0.5 else (cold, hot)
            go(first, rate, soaks())
            go(second, rate, soaks())
            go(start, rate, 0)
        elif kind == "staircase":
            rate = rng.uniform(1.5, 2.5)
            soak(rng.uniform(20, 40))
            for target_end, sign in ((hi - 3, 1), (lo + 3, -1), (start, 1)):
                while (target_end - temps[-1]) * sign > 1:
                    step = rng.uniform(8, 15)
                    target = temps[-1] + sign * step
                    target = min(target, target_end) if sign > 0 else max(target, target_end)
                    go(target, rate, rng.uniform(20, 40))
        elif kind == "random":
            soak(rng.uniform(20, 40))
            for _ in range(int(rng.integers(8, 13))):
                go(rng.uniform(lo + 3, hi - 3), rng.uniform(0.2, 3.0), rng.uniform(0, 60))
            go(start, rng.uniform(0.5, 2.0), 0)
        else:
            raise ValueError(f"unknown profile kind {kind}")
    soak(10)
    return times, temps, cycle_starts


# ------------------------------------------------------------------------------ simulation

def network(unit):
    """dx/dt = A x + b·T_air + c (self-heating) of the whole unit's thermal network."""
    n = 2 + 3 * SHELLS + 3
    A = np.zeros((n, n))
    b = np.zeros(n)
    c = np.zeros(n)
    H, M = 0, 1
    th, tm = unit["housing_tau"], unit["mount_tau"]
    A[H, H] -= 1 / th
    b[H] += 1 / th
    c[H] += unit["housing_heat"] / th
    A[M, M] -= 1 / tm
    b[M] += 1 / tm
    k = unit["mount_to_housing"]
    A[M, M] -= k / tm
    A[M, H] += k / tm
    for a, axis in enumerate(unit["axes"]):
        first = 2 + a * SHELLS
        tl, ts = axis["link_tau"], axis["diffusion_tau"] / SHELLS ** 2
        # the outer shell exchanges with the housing through a link whose conductance makes
        # tl the time constant of the whole coil (SHELLS shells of one unit of heat capacity
        # each) behind it; the housing is loaded by the coils
        A[first, first] -= SHELLS / tl
        A[first, H] += SHELLS / tl
        load = unit["coil_load"] / 3
        A[H, H] -= load / th
        A[H, first] += load / th
        for i in range(SHELLS - 1):
            p, q = first + i, first + i + 1
            A[p, p] -= 1 / ts
            A[p, q] += 1 / ts
            A[q, q] -= 1 / ts
            A[q, p] += 1 / ts
        # a source in the inner shell that holds it coil_heat °C above the housing in a soak
        c[first + SHELLS - 1] += axis["coil_heat"] / (tl / SHELLS + (SHELLS - 1) * ts)
    for a, axis in enumerate(unit["axes"]):
        s = 2 + 3 * SHELLS + a
        site = axis["sensor_site"]
        source = H if site == "housing" else M if site == "mount" else 2 + int(site[4]) * SHELLS
        A[s, s] -= 1 / axis["sensor_tau"]
        A[s, source] += 1 / axis["sensor_tau"]
    return A, b, c


def law_terms(unit, t, states, air, internal=None):
    """Per axis, a dict of the drift law's terms (each the part of the drift it contributes)
    evaluated on the network's states row by row (true or estimated) with the air at `air`;
    internal: as in simulate."""
    A, b, c = network(unit)
    dt = t[1] - t[0] if len(t) > 1 else 1.0
    derivative = states @ A.T + np.outer(air, b) + c  # °C/s, exact at each sample
    out = []
    for a, axis in enumerate(unit["axes"]):
        first = 2 + a * SHELLS
        shells = states[:, first:first + SHELLS]
        shell_rates = derivative[:, first:first + SHELLS] * 60.0
        coil = shells.mean(axis=1)
        coil_rate = shell_rates.mean(axis=1)
        gradient = shells[:, 0] - shells[:, -1]
        gradient_rate = shell_rates[:, 0] - shell_rates[:, -1]
        delta = coil - unit["reference_c"]
        st = axis["static"]
        terms = {"bias": np.full(len(t), axis["bias"])}
        terms["linear"] = st["a1"] * delta
        if st["kind"] == "poly":
            terms["static"] = st["a2"] * delta ** 2 + st["a3"] * delta ** 3
        elif st["kind"] == "exp":
            terms["static"] = st["size"] * np.expm1(delta / st["theta"]) / math.expm1(45.0 / st["theta"])
        elif st["kind"] == "bump":
            terms["static"] = st["size"] * np.exp(-((coil - st["centre"]) / st["width"]) ** 2)
        else:
            terms["static"] = st["size"] * (1 / (1 + np.exp(-(coil - st["centre"]) / st["width"])) - 0.5)
        terms["rate"] = axis["rate"] * coil_rate
        terms["rate_tempco"] = axis["rate"] * axis["rate_tempco"] * delta * coil_rate
        terms["asymmetry"] = axis["asymmetry"] * coil_rate * np.tanh(coil_rate / 0.05)
        terms["shupe"] = axis["shupe"] * gradient_rate
        terms["gradient"] = axis["gradient"] * gradient
        hyst = axis["hysteresis"]
        if hyst["kind"] == "preisach":
            for width, weight in zip(hyst["widths"], hyst["weights"]):
                play = np.empty(len(t))
                p = coil[0]
                for k in range(len(t)):
                    p = min(max(p, coil[k] - width), coil[k] + width)
                    play[k] = p
                terms[f"play{width:.2f}"] = weight * (coil - play) / width
        elif hyst["kind"] == "relay":
            relay = np.empty(len(t))
            state, h = 0.0, 0.0
            a_h = math.exp(-dt / hyst["tau"])
            for k in range(len(t)):
                if coil_rate[k] > hyst["threshold"]:
                    state = 1.0
                elif coil_rate[k] < -hyst["threshold"]:
                    state = -1.0
                h = a_h * h + (1 - a_h) * state
                relay[k] = h
            terms["relay"] = hyst["size"] * relay
        terms["turn_on"] = axis["turn_on"] * np.exp(-t / axis["turn_on_tau"])
        out.append(terms)
        if internal is not None:
            internal.append({"coil": coil, "coil_rate": coil_rate, "gradient": gradient})
    return out


def simulate(unit, profile, noise_seed, rate_hz=1.0, regressors=None, internal=None, states_out=None):
    """Columns of a 1 Hz log: time, the three thermometers, gyros, and the true drift.

    regressors: a list that receives, per axis, a dict of the drift law's terms (each the
    noise-free part of the drift it contributes, before smoothing): the oracle's columns.
    internal: a list that receives, per axis, a dict of the coil's mean temperature and its
    rate (°C/min) and the radial gradient. states_out: a dict that receives the network's
    states row by row ("states") and the air ("air")."""
    times, temps, cycle_starts = profile
    dt = 1.0 / rate_hz
    t = np.arange(0.0, times[-1], dt)
    air = np.interp(t, times, temps)
    A, b, c = network(unit)
    n = A.shape[0]
    # Exact discretization for an input linear over each step (first-order hold).
    big = np.zeros((n + 2, n + 2))
    big[:n, :n] = A * dt
    big[:n, n] = b * dt
    big[n, n + 1] = 1.0
    e = expm(big)
    phi, gamma0, gamma1 = e[:n, :n], e[:n, n], e[:n, n + 1]
    heat = np.linalg.solve(A, (phi - np.eye(n)) @ c)  # the constant source over one step
    x = np.full(n, air[0])
    states = np.empty((len(t), n))
    for k in range(len(t)):
        states[k] = x
        if k + 1 < len(t):
            x = phi @ x + gamma0 * air[k] + gamma1 * (air[k + 1] - air[k]) + heat
    if states_out is not None:
        states_out.update(states=states, air=air)

    rng = rng_for(noise_seed, 99)
    noise = unit["noise"]
    columns = {"time_s": t}
    for a in range(3):
        s = 2 + 3 * SHELLS + a
        reading = states[:, s] + rng.normal(0, noise["temperature_noise"], len(t))
        res = noise["temperature_resolution"]
        columns[f"temp_{AXES[a]}"] = np.round(reading / res) * res
    terms_per_axis = law_terms(unit, t, states, air, internal)
    drifts = [sum(terms.values()) for terms in terms_per_axis]
    if regressors is not None:
        regressors.extend(terms_per_axis)

    # Gyro noise: white (ARW), a flicker-like bias from five Gauss-Markov processes, quantization.
    sigma_w = noise["arw"] * 60.0 * math.sqrt(rate_hz)
    sigma_b = noise["bias_instability"] * 0.6643 / 0.6174
    correlation = [10.0 ** j for j in range(1, 6)]
    for a in range(3):
        white = rng.normal(0, sigma_w, len(t))
        bias = np.zeros(len(t))
        for tau in correlation:
            phi_b = math.exp(-dt / tau)
            sd = sigma_b / math.sqrt(1.9)
            drive = rng.normal(0, sd * math.sqrt(1 - phi_b ** 2), len(t))
            drive[0] = rng.normal(0, sd)
            bias += lfilter_ar1(drive, phi_b)
        measured = drifts[a] + white + bias
        q = noise["quantization_arcsec"] / 3600.0 * 3600.0  # °/h·s per quantum: 1″ = 1 °/h·s
        if q > 0:
            angle = np.cumsum(measured * dt)
            pulses = np.floor(angle / q)
            out = np.diff(np.concatenate([[0.0], pulses])) * q / dt
            measured = out
        columns[f"gyro_{AXES[a]}"] = measured
    for a in range(3):
        columns[f"drift_{AXES[a]}"] = drifts[a]
    return columns, cycle_starts


def lfilter_ar1(drive, phi):
    from scipy.signal import lfilter
    return lfilter([1.0], [1.0, -phi], drive)


def trailing_mean(column, window):
    """The trailing mean over `window` rows (of a column, or of each column of a matrix),
    from the first full window on: row k of the result is row k + window - 1 of the input."""
    column = np.asarray(column, dtype=float)
    csum = np.concatenate([np.zeros((1,) + column.shape[1:]), np.cumsum(column, axis=0)])
    return (csum[window:] - csum[:-window]) / window


def noise_floor(columns, first_row, window_s=100.0, rate_hz=1.0):
    """Per axis: the variance, about its mean, of the gyro noise after a trailing mean of window_s, from first_row on."""
    w = int(round(window_s * rate_hz))
    floors = []
    for a in AXES:
        mean = trailing_mean(columns[f"gyro_{a}"] - columns[f"drift_{a}"], w)
        rows = mean[max(first_row - (w - 1), 0):]
        floors.append(float(np.var(rows)))
    return floors


def rows(columns, begin, end):
    return {name: values[begin:end] for name, values in columns.items()}


def write_csv(columns, path, with_drift=False):
    names = ["time_s", "temp_x", "temp_y", "temp_z", "gyro_x", "gyro_y", "gyro_z"]
    if with_drift:
        names += ["drift_x", "drift_y", "drift_z"]
    data = np.column_stack([columns[n] for n in names])
    with open(path, "w") as out:
        out.write(",".join(names) + "\n")
        np.savetxt(out, data, delimiter=",", fmt="%.10g")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seed", type=int, required=True, help="law seed")
    parser.add_argument("--profile", default="cycle", choices=PROFILE_KINDS)
    parser.add_argument("--profile-seed", type=int, help="default: the law seed")
    parser.add_argument("--noise-seed", type=int, default=1)
    parser.add_argument("--cycles", type=int, default=1)
    parser.add_argument("--describe", action="store_true")
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    unit = draw_unit(args.seed)
    if args.describe:
        print(describe(unit), file=sys.stderr)
    profile = draw_profile(args.profile, unit, args.profile_seed or args.seed, args.cycles)
    columns, _ = simulate(unit, profile, args.noise_seed)
    write_csv(columns, args.out, with_drift=True)


if __name__ == "__main__":
    main()
