"""thermodrift from Python: temperature-drift models of gyroscopes, fitted on chamber logs.

The same C++ library as the ``thermodrift`` command line, with the same options, checks,
warnings and numbers (docs/python.md)::

    import thermodrift as td
    log = td.read_log("chamber.csv")                # a pandas DataFrame
    model = td.fit(log, model="svr", features="auto")
    model.save("drift.json")                        # what `thermodrift fit --out` writes
    out = model.compensate(td.read_log("next.csv"))  # + one <axis>_comp_dph column per axis
    model.evaluate(td.read_log("next.csv"), settle=1800)  # as `evaluate --json`

A keyword of ``fit`` is the option of ``thermodrift fit`` of the same name (``rate_span``
for ``--rate-span``); a value the option refuses raises ``UsageError`` with its message.
Bad data raises ``DataError`` (file, line, column); Ctrl-C stops a long call within a
fraction of a second with ``KeyboardInterrupt``.
"""

import os
import sys
import tempfile
import time as _time

import numpy as np
import pandas as pd

from . import _core
from .errors import DataError, ThermodriftError, ThermodriftWarning, UsageError

__all__ = [
    "read_log", "fit", "load_model", "simulate", "report", "allan_deviation", "DriftModel", "DriftRegressor",
    "DataError", "UsageError", "ThermodriftError", "ThermodriftWarning",
]

# Options that say how a file is read: for a DataFrame from read_log the values are already
# converted (°/h, °C, s), so these come from its attrs and cannot be given again.
_READING = ("gyro_unit", "time_unit", "temp_scale", "temp_offset", "gyro_scale", "despike", "format")
# Where read_log keeps what the DataFrame is (pandas' DataFrame.attrs).
_ATTRS = "thermodrift"


def _text(value):
    if isinstance(value, float):
        return repr(value)  # shortest exact form: the C++ side reads the same double
    return str(value)


def _arguments(options):
    """Keywords to the command line's arguments: rate_span=100 -> ["--rate-span", "100"]."""
    arguments = []
    for key, value in options.items():
        if value is None or value is False:
            continue
        flag = "--" + key.replace("_", "-")
        if value is True:
            arguments.append(flag)
        elif isinstance(value, (list, tuple)):
            arguments += [flag, ",".join(_text(v) for v in value)]
        else:
            arguments += [flag, _text(value)]
    return arguments


def _check_keywords(command, options, extra=()):
    known = set(_core.keywords(command)) | set(extra)
    unknown = sorted(set(options) - known)
    if unknown:
        raise UsageError(f"{command}: unknown keyword '{unknown[0]}'; the keywords are the options of "
                         f"thermodrift {command.replace('read_log', 'fit')}: {', '.join(sorted(known))}")


def _names(value):
    if value is None:
        return None
    return [value] if isinstance(value, str) else list(value)


def read_log(path, time=None, gyro=None, temp=None, rate=None, gyro_unit="dph", **options):
    """Reads a chamber log as ``thermodrift`` reads ``--data``: a DataFrame.

    Columns: ``time`` (seconds since the first row), one per gyro axis (°/h) and one per
    temperature channel (°C), named as in the file. Keywords are the data options of the
    command line (``time_unit``, ``temp_scale``, ``temp_offset``, ``gyro_scale``,
    ``despike``, ...). Warnings (skipped banner lines, dropped rows) are Python warnings.
    ``attrs["thermodrift"]`` remembers how the file was read, so ``fit`` records it in the
    model and the model reads the raw file again as the command line would.
    """
    _check_keywords("read_log", options)
    if "data" in options:
        raise UsageError("read_log: the file is the first argument, not data=")
    given = dict(time=time, gyro=gyro, temp=temp, rate=rate, gyro_unit=gyro_unit, **options)
    arguments = _arguments(given)
    log = _core.read_log(["--data", os.fspath(path)] + arguments)
    columns = {"time": log["time"]}
    for name, values in zip(log["gyro_names"], log["gyro"]):
        columns[name] = values
    for name, values in zip(log["temperature_names"], log["temperature"]):
        columns.setdefault(name, values)
    frame = pd.DataFrame(columns, copy=False)
    frame.attrs[_ATTRS] = {
        "file": os.fspath(path),
        "arguments": arguments,
        "time": "time",
        "gyro": list(log["gyro_names"]),
        "temp": list(log["temperature_names"]),
        "time_origin": log["time_origin"],
    }
    return frame


def _time_column(frame):
    """The command line's rule for a log without --time: time_s, time, t, then time*/t_*."""
    names = [str(c) for c in frame.columns]
    for name in ("time_s", "time", "t"):
        if name in names:
            return name
    for name in names:
        lower = name.lower()
        if lower == "t" or lower.startswith("time") or lower.startswith("t_"):
            return name
    return None


def _column(frame, name, what):
    if name not in frame.columns:
        raise UsageError(f"no {what} column '{name}' in the DataFrame (columns: {', '.join(map(str, frame.columns))})")
    position = frame.columns.get_loc(name) + 1
    try:
        values = frame[name].to_numpy(dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise DataError(f"DataFrame: column '{name}': {what} values must be numbers ({error})",
                        "DataFrame", 0, position) from None
    return np.ascontiguousarray(values), position


def _to_frame(frame, gyro=None, temp=None, time=None, rate=None, model=None):
    """A DataFrame's columns as the C++ core takes a log; column choice as the CLI's."""
    if not isinstance(frame, pd.DataFrame):
        raise UsageError(f"expected a pandas DataFrame or a path, not {type(frame).__name__}")
    meta = frame.attrs.get(_ATTRS, {})

    def choose(given, from_model, from_meta, prefix, what):
        if given is not None:
            return _names(given)
        for candidate in (from_model, from_meta):
            if candidate and all(name in frame.columns for name in candidate):
                return list(candidate)
        found = [c for c in frame.columns if str(c).lower().startswith(prefix)]
        if not found:
            raise UsageError(f"no column named {prefix}* in the DataFrame; name the {what} columns with {what}=")
        return found

    gyro_names = choose(gyro, model.gyro_columns if model else None, meta.get("gyro"), "gyro", "gyro")
    temp_names = choose(temp, model.temperature_columns if model else None, meta.get("temp"), "temp", "temp")
    if model is None and temp is None and len(temp_names) not in (1, len(gyro_names)):
        raise UsageError(f"{len(temp_names)} temp* columns for {len(gyro_names)} gyro axes; name one for all axes "
                         "or one per axis with temp=")
    if rate is not None:
        if not rate > 0:
            raise UsageError(f"rate must be a positive number of hertz, not {rate}")
        times, time_position = np.arange(len(frame), dtype=np.float64) / rate, 0
    else:
        name = time if time is not None else meta.get("time") if meta.get("time") in frame.columns else _time_column(frame)
        if name is None:
            raise UsageError("no time column found in the DataFrame; name one with time= or give rate=")
        times, time_position = _column(frame, name, "time")
    gyro_columns = [_column(frame, name, "gyro") for name in gyro_names]
    temp_columns = [_column(frame, name, "temperature") for name in temp_names]
    return {
        "source": "DataFrame",
        "file": meta.get("file", ""),
        "time": times,
        "time_position": time_position,
        "gyro_names": [str(n) for n in gyro_names],
        "gyro": [c for c, _ in gyro_columns],
        "gyro_positions": [p for _, p in gyro_columns],
        "temperature_names": [str(n) for n in temp_names],
        "temperature": [c for c, _ in temp_columns],
        "temperature_positions": [p for _, p in temp_columns],
    }


class _ProgressBar:
    """The default progress: one line on stderr, redrawn at most ten times a second."""

    def __init__(self, what):
        self.what = what
        self.last = 0.0
        self.drawn = False

    def __call__(self, axis, axes, fraction, message):
        now = _time.monotonic()
        if now - self.last < 0.1:
            return True
        self.last = now
        done = (axis + fraction) / max(axes, 1)
        bar = "#" * int(done * 20)
        sys.stderr.write(f"\r{self.what} [{bar:<20}] axis {axis + 1}/{axes}: {message[:60]:<60}")
        sys.stderr.flush()
        self.drawn = True
        return True

    def close(self):
        if self.drawn:
            sys.stderr.write("\n")
            sys.stderr.flush()


def _is_path(data):
    return isinstance(data, (str, os.PathLike))


def fit(data, model="linear", features=None, seed=1, progress=None, **options):
    """Fits one drift model per gyro axis, as ``thermodrift fit`` does: a DriftModel.

    ``data``: a path, a DataFrame (``read_log``'s, or any with time, gyro* and temp*
    columns; ``time=``, ``gyro=``, ``temp=`` name others), or a list of either (several
    runs fitted together). ``features``: None (the paper's dT, rate), ``"auto"``, or a list
    of terms. Every other option of ``thermodrift fit`` is a keyword (``C``, ``sigma``,
    ``evaluations``, ``rate_span``, ``identify``, ``threads``, ...). ``progress``: None
    for a bar on stderr, False for none, or ``f(axis, axes, fraction, message)``; a false
    return value stops the fit (KeyboardInterrupt).
    """
    _check_keywords("fit", options)
    items = list(data) if isinstance(data, (list, tuple)) else [data]
    if not items:
        raise UsageError("no data")
    if isinstance(features, str) and features != "auto":
        features = [f for f in features.split(",") if f]
    given = dict(model=model, features=features, seed=seed)
    frames = []
    if all(_is_path(item) for item in items):
        arguments = [a for item in items for a in ("--data", os.fspath(item))]
        arguments += _arguments({**given, **options})
    elif all(isinstance(item, pd.DataFrame) for item in items):
        reading = sorted(key for key in options if key in _READING)
        if reading:
            raise UsageError(f"{', '.join(reading)}: options of reading a file; the DataFrame's values are "
                             "already in °/h, °C and s (give them to read_log)")
        selection = {key: options.pop(key, None) for key in ("gyro", "temp", "time", "rate")}
        frames = [_to_frame(item, **selection) for item in items]
        metas = [item.attrs.get(_ATTRS, {}) for item in items]
        read_with = [tuple(m.get("arguments", [])) for m in metas]
        if len(set(read_with)) > 1:
            raise UsageError("the DataFrames were read with different options; fit them separately")
        arguments = _recorded_reading(list(read_with[0]), metas[0], frames[0], selection)
        arguments += _arguments({**given, **options})
    else:
        raise UsageError("data: a path, a DataFrame or a list of one kind")
    bar = None
    if progress is None:
        progress = bar = _ProgressBar("thermodrift fit")
    elif progress is False:
        progress = None
    try:
        core, summary = _core.fit(arguments, frames, progress)
    finally:
        if bar:
            bar.close()
    return DriftModel(core, summary)


def _recorded_reading(arguments, meta, frame, selection):
    """How the DataFrame was read, for the model's record: read_log's options, with the
    columns actually fitted when they differ from the ones read."""
    def drop(flag):
        while flag in arguments:
            i = arguments.index(flag)
            del arguments[i:i + 2]

    if frame["gyro_names"] != meta.get("gyro"):
        drop("--gyro")
        arguments += ["--gyro", ",".join(frame["gyro_names"])]
    if frame["temperature_names"] != meta.get("temp"):
        drop("--temp")
        arguments += ["--temp", ",".join(frame["temperature_names"])]
    if selection["time"] is not None:
        drop("--time")
        drop("--rate")
        arguments += ["--time", str(selection["time"])]
    if selection["rate"] is not None:
        drop("--time")
        drop("--rate")
        arguments += ["--rate", _text(float(selection["rate"]))]
    return arguments


def _logs(model, data, selection):
    items = list(data) if isinstance(data, (list, tuple)) else [data]
    frames = []
    for item in items:
        if _is_path(item):
            raise UsageError("give a DataFrame (td.read_log(path))")
        frames.append(_to_frame(item, model=model, **selection))
    return frames


class DriftModel:
    """A fitted drift model: one per gyro axis, as in a ``thermodrift fit`` model file."""

    def __init__(self, core, summary=None):
        self._core = core
        self.fit_summary = summary  # in-sample figures of the fit (None for a loaded model)

    @property
    def axes(self):
        """The axes' names (the gyro columns')."""
        return list(self._core.axes)

    @property
    def terms(self):
        """Feature terms per axis: {axis: [term, ...]}."""
        return dict(zip(self._core.axes, self._core.terms))

    @property
    def params(self):
        """Fitted parameters per axis (C, σ, ε, ... for SVR): {axis: {...}}."""
        return dict(zip(self._core.axes, self._core.params))

    @property
    def kinds(self):
        """Model kind per axis: linear, stepwise or svr."""
        return dict(zip(self._core.axes, self._core.kinds))

    @property
    def path(self):
        """The file this model was loaded from or last saved to ('' if none)."""
        return self._core.path

    def save(self, path):
        """Writes the model file (atomically: never a half-written file)."""
        self._core.save(os.fspath(path))

    def to_json(self):
        """The model file's content as a dict."""
        return self._core.to_json()

    def _run(self, data, gyro, temp, time, rate):
        frame = _to_frame(data, gyro=gyro, temp=temp, time=time, rate=rate, model=self._core)
        inputs = len(self._core.temperature_columns)
        shared = len(frame["temperature"]) == 1 and inputs == len(self._core.axes)
        return self._core.compensate(frame, shared)

    def compensate(self, data, gyro=None, temp=None, time=None, rate=None, flags=False):
        """``data`` with one ``<axis>_comp_dph`` column per axis (and ``<axis>_flags`` when
        ``flags``: 0 ok, 1 not ready, 2 outside the training envelope), as ``thermodrift
        compensate`` writes them, through the same real-time compensator."""
        _, compensated, flag_values = self._run(data, gyro, temp, time, rate)
        out = data.copy()
        for a, axis in enumerate(self._core.axes):
            out[f"{axis}_comp_dph"] = compensated[:, a]
        if flags:
            for a, axis in enumerate(self._core.axes):
                out[f"{axis}_flags"] = flag_values[:, a]
        return out

    def drift(self, data, gyro=None, temp=None, time=None, rate=None):
        """The predicted drift (°/h) of every row at that row's time, one column per axis
        (causal, as the compensator runs it: the model's smoothed drift advanced half the
        window along its slope; rows still in a warm-up carry the estimate there is)."""
        drift, _, _ = self._run(data, gyro, temp, time, rate)
        return pd.DataFrame(drift, columns=self._core.axes, index=data.index)

    def evaluate(self, data, settle=0, gyro=None, temp=None, time=None, rate=None, log_start="estimated"):
        """Metrics on a DataFrame (or a list: several runs), as ``evaluate --json``;
        ``log_start`` as ``--log-start``: ``"estimated"`` (the default: between power-on and a
        running start, as the settling rows say), ``"power-on"`` or ``"running"`` (a log cut
        from a running recording)."""
        if not settle >= 0:
            raise UsageError(f"settle must be a non-negative number of seconds, not {settle}")
        if log_start not in ("power-on", "running", "estimated"):
            raise UsageError(f"log_start must be 'power-on', 'running' or 'estimated', not {log_start!r}")
        frames = _logs(self._core, data, dict(gyro=gyro, temp=temp, time=time, rate=rate))
        return self._core.evaluate(frames, float(settle), log_start)

    def __repr__(self):
        kinds = ", ".join(f"{axis}: {kind} ({len(terms)} terms)"
                          for axis, kind, terms in zip(self._core.axes, self._core.kinds, self._core.terms))
        return f"<thermodrift.DriftModel {kinds}>"


def load_model(path):
    """Loads a model file written by ``thermodrift fit`` or ``DriftModel.save``."""
    return DriftModel(_core.Model.load(os.fspath(path)))


def simulate(out=None, **options):
    """A simulated chamber log (``thermodrift simulate``'s options as keywords: seed,
    cycles, rate, law, profile, ...) as a DataFrame of the file's columns (time_s, the
    chamber's and the axes' temperatures, gyro_*, and the true drift_*); also written to
    ``out`` when given. Fit it with ``temp=["temp_x", "temp_y", "temp_z"]``."""
    with tempfile.TemporaryDirectory() as scratch:
        path = os.fspath(out) if out is not None else os.path.join(scratch, "simulated.csv")
        _core.run_command(["simulate", "--out", path] + _arguments(options))
        return pd.read_csv(path, float_precision="round_trip")


def report(data, out, **options):
    """Writes the HTML report of ``thermodrift report`` into the folder ``out`` (its
    options as keywords); returns the path of report.html."""
    if not _is_path(data):
        raise UsageError("report reads its log from a file: give the path")
    _core.run_command(["report", "--data", os.fspath(data), "--out", os.fspath(out)] + _arguments(options))
    return os.path.join(os.fspath(out), "report.html")


def allan_deviation(rate, sample_rate_hz, points_per_decade=10, max_tau_fraction=0.25):
    """Overlapping Allan deviation of an evenly sampled rate series (IEEE Std 952), as the
    report computes it: a DataFrame of tau_s, deviation (the rate's unit) and terms (the
    second differences averaged at that τ)."""
    tau, deviation, terms = _core.allan_deviation(np.ascontiguousarray(rate, dtype=np.float64), float(sample_rate_hz),
                                                  int(points_per_decade), float(max_tau_fraction))
    return pd.DataFrame({"tau_s": tau, "deviation": deviation, "terms": terms})


def __getattr__(name):
    if name == "DriftRegressor":  # scikit-learn is imported only when asked for
        from .estimator import DriftRegressor
        return DriftRegressor
    raise AttributeError(f"module 'thermodrift' has no attribute '{name}'")
