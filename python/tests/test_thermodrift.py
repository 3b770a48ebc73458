"""The Python package against the command line it wraps: the same models, numbers,
errors and warnings, on logs the CLI simulates (PYTHONPATH=build/python)."""

import json
import os
import signal
import sys
import subprocess
import threading
import time
import warnings

import numpy as np
import pandas as pd
import pytest

import thermodrift as td

HERE = os.path.dirname(os.path.abspath(__file__))
CLI = os.environ.get("THERMODRIFT_CLI", os.path.join(HERE, "..", "..", "build", "bin", "thermodrift"))
TEMPS = ["temp_x", "temp_y", "temp_z"]


def cli(*arguments, check=True):
    result = subprocess.run([CLI, *map(str, arguments)], capture_output=True, text=True)
    if check and result.returncode != 0:
        raise AssertionError(f"thermodrift {' '.join(map(str, arguments))}: exit {result.returncode}\n{result.stderr}")
    return result


@pytest.fixture(scope="session")
def logs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("logs")
    train, test = folder / "train.csv", folder / "test.csv"
    cli("simulate", "--out", train, "--seed", 3, "--cycles", 1)
    cli("simulate", "--out", test, "--seed", 4, "--cycles", 1)
    return train, test


def model_axes(path):
    with open(path) as f:
        return json.load(f)["axes"]


def assert_same_models(python_file, cli_file):
    """Every number of the two model files within 1e-9 (relative), every text equal."""
    def compare(a, b, where):
        if isinstance(a, dict):
            assert set(a) == set(b), where
            for key in a:
                compare(a[key], b[key], f"{where}.{key}")
        elif isinstance(a, list):
            assert len(a) == len(b), where
            for i, (x, y) in enumerate(zip(a, b)):
                compare(x, y, f"{where}[{i}]")
        elif isinstance(a, float) or isinstance(b, float):
            assert a == pytest.approx(b, rel=1e-9, abs=1e-12), where
        else:
            assert a == b, where
    compare(model_axes(python_file), model_axes(cli_file), "axes")


@pytest.mark.parametrize("options", [
    dict(),
    dict(model="svr", C=10, sigma=1),
    dict(model="stepwise", features=["dT", "rate", "lag:600"]),
])
def test_fit_from_read_log_writes_the_cli_model(logs, tmp_path, options):
    train, _ = logs
    model = td.fit(td.read_log(train, temp=TEMPS), progress=False, **options)
    model.save(tmp_path / "python.json")
    arguments = []
    for key, value in options.items():
        arguments += [f"--{key}", ",".join(value) if isinstance(value, list) else value]
    cli("fit", "--data", train, "--temp", ",".join(TEMPS), "--out", tmp_path / "cli.json", *arguments)
    assert_same_models(tmp_path / "python.json", tmp_path / "cli.json")
    # The model Python wrote is one the CLI loads and applies.
    cli("evaluate", "--model", tmp_path / "python.json", "--data", train)


def test_fit_from_a_path_and_from_a_plain_dataframe_agree(logs, tmp_path):
    train, _ = logs
    from_path = td.fit(train, temp=TEMPS, progress=False)
    frame = pd.read_csv(train)  # the user's own DataFrame: no attrs, time in seconds already
    from_frame = td.fit(frame, temp=TEMPS, progress=False)
    from_path.save(tmp_path / "path.json")
    from_frame.save(tmp_path / "frame.json")
    assert_same_models(tmp_path / "frame.json", tmp_path / "path.json")
    assert from_frame.axes == ["gyro_x", "gyro_y", "gyro_z"]
    assert from_frame.terms["gyro_y"] == ["dT", "rate"]
    assert set(from_frame.params) == {"gyro_x", "gyro_y", "gyro_z"}


def test_compensate_gives_the_cli_columns(logs, tmp_path):
    train, test = logs
    cli("fit", "--data", train, "--temp", ",".join(TEMPS), "--features", "dT,rate,lag:900", "--out",
        tmp_path / "m.json")
    model = td.load_model(tmp_path / "m.json")
    out = model.compensate(td.read_log(test, temp=TEMPS), flags=True)
    cli("compensate", "--model", tmp_path / "m.json", "--data", test, "--out", tmp_path / "c.csv", "--flags")
    expected = pd.read_csv(tmp_path / "c.csv")
    assert len(out) == len(expected)
    for axis in model.axes:
        # The CLI writes 9 significant digits: a relative rounding of at most 5e-9.
        np.testing.assert_allclose(out[f"{axis}_comp_dph"], expected[f"{axis}_comp_dph"], rtol=6e-9, atol=1e-12)
        np.testing.assert_array_equal(out[f"{axis}_flags"], expected[f"{axis}_flags"])
    assert (out["gyro_x_flags"] & 1).sum() > 0  # the warm-up is flagged, as in the file


def test_evaluate_matches_evaluate_json(logs, tmp_path):
    train, test = logs
    cli("fit", "--data", train, "--temp", ",".join(TEMPS), "--out", tmp_path / "m.json")
    model = td.load_model(tmp_path / "m.json")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", td.ThermodriftWarning)
        results = {start: model.evaluate(td.read_log(test, temp=TEMPS), settle=1800, log_start=start)
                   for start in ("power-on", "running", "estimated")}
    for start, result in results.items():
        expected = json.loads(cli("evaluate", "--model", tmp_path / "m.json", "--data", test, "--settle", 1800,
                                  "--log-start", start, "--json").stdout)
        assert result.keys() == expected.keys()
        assert result["log_start"] == start
        for mine, theirs in zip(result["axes"], expected["axes"]):
            assert mine.keys() == theirs.keys()
            for key, value in theirs.items():
                if isinstance(value, float):
                    assert mine[key] == pytest.approx(value, rel=1e-12), key
                else:
                    assert mine[key] == value, key
    # the history before the log moves its lags (the test log starts at power-on: `running` is the wrong start for it)
    assert results["running"]["axes"][0]["mse_after"] != results["power-on"]["axes"][0]["mse_after"]


def test_a_bad_file_is_a_data_error_where_the_cli_says(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("time,gyro_x,temp_x\n0,0.1,20\n1,0.2,20\n2,nan,20\n")
    with pytest.raises(td.DataError) as caught:
        td.read_log(bad)
    assert (caught.value.file, caught.value.line, caught.value.column) == (str(bad), 4, 2)
    message = cli("fit", "--data", bad, "--out", tmp_path / "m.json", check=False)
    assert message.returncode == 3
    assert str(caught.value) in message.stderr


def test_a_nan_in_a_dataframe_names_its_row_and_column():
    frame = pd.DataFrame({"time": np.arange(500.0), "gyro_x": 0.1, "temp_x": 20.0})
    frame.loc[123, "temp_x"] = np.nan
    with pytest.raises(td.DataError) as caught:
        td.fit(frame, progress=False)
    assert (caught.value.file, caught.value.line, caught.value.column) == ("DataFrame", 124, 3)
    assert isinstance(caught.value, ValueError)


def test_options_are_checked_as_the_cli_checks_them(logs):
    train, _ = logs
    with pytest.raises(td.UsageError, match="--C applies to --model svr"):
        td.fit(train, temp=TEMPS, C=10)
    with pytest.raises(td.UsageError, match="--folds"):
        td.fit(train, temp=TEMPS, model="svr", folds=1)
    with pytest.raises(td.UsageError, match="gyro_unit"):
        td.fit(td.read_log(train, temp=TEMPS), gyro_unit="dps")
    with pytest.raises(td.UsageError, match="unknown keyword 'no_such_option'"):
        td.fit(train, temp=TEMPS, no_such_option=1)
    with pytest.raises(td.UsageError, match="unknown keyword 'evaluations'"):  # fit's, not read_log's
        td.read_log(train, evaluations=3)


def test_reader_warnings_are_python_warnings(tmp_path):
    log = tmp_path / "banner.csv"
    rows = "\n".join(f"{t},{0.1 + 0.001 * t},{20 + 0.01 * t}" for t in range(400))
    log.write_text("# chamber run 7, operator A\ntime,gyro_x,temp_x\n" + rows + "\n")
    with pytest.warns(td.ThermodriftWarning, match="banner|skipped") as record:
        frame = td.read_log(log)
    assert record[0].filename == __file__  # the warning points at the caller's line
    assert len(frame) == 400
    assert list(frame.columns) == ["time", "gyro_x", "temp_x"]


def test_the_estimator_clones_fits_and_predicts_one_row_per_row(logs):
    from sklearn.base import clone

    train, test = logs
    estimator = clone(td.DriftRegressor(temp=TEMPS))
    estimator.fit(td.read_log(train, temp=TEMPS))
    frame = td.read_log(test, temp=TEMPS)
    drift = estimator.predict(frame)
    assert drift.shape == (len(frame), 3)
    assert np.isfinite(drift).all()
    # The estimator's drift is the compensator's: gyro - compensated.
    out = estimator.model_.compensate(frame)
    np.testing.assert_allclose(drift[:, 1], frame["gyro_y"] - out["gyro_y_comp_dph"], rtol=1e-12, atol=1e-12)
    assert estimator.get_params()["temp"] == TEMPS
    assert estimator.score(frame) < 0


def test_a_progress_callback_sees_the_tuning_and_can_stop_it(logs):
    train, _ = logs
    calls = []

    def progress(axis, axes, fraction, message):
        calls.append((axis, axes, fraction, message))
        return len(calls) < 3

    with pytest.raises(KeyboardInterrupt):
        td.fit(train, temp=TEMPS, model="svr", evaluations=49, progress=progress)
    assert len(calls) == 3
    assert calls[0][1] == 3


def test_ctrl_c_stops_a_long_fit():
    frame = td.simulate(seed=5, cycles=2)
    main = threading.get_ident()
    timer = threading.Timer(1.0, lambda: signal.pthread_kill(main, signal.SIGINT))
    timer.start()
    started = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        td.fit(frame, temp=TEMPS, model="svr", features="auto", evaluations=400, progress=False)
    timer.cancel()
    # A fit of this size takes minutes; stopped, it returns at the next check.
    assert time.monotonic() - started < 30


def test_simulate_returns_the_log_the_cli_writes(tmp_path):
    frame = td.simulate(out=tmp_path / "s.csv", seed=9, cycles=1, rate=0.5)
    expected = pd.read_csv(tmp_path / "s.csv")
    assert len(frame) == len(expected)
    np.testing.assert_array_equal(frame["gyro_z"].to_numpy(), expected["gyro_z"].to_numpy())
    np.testing.assert_array_equal(frame["time_s"].to_numpy(), expected["time_s"].to_numpy())
    assert "drift_x" in frame.columns  # the true drift, which a simulation knows


def test_allan_deviation_is_the_overlapping_estimator():
    """Against the definition (IEEE Std 952), computed here directly, and white noise's
    σ/√τ law."""
    rng = np.random.default_rng(7)
    rate = rng.normal(0, 2.0, 40000)
    result = td.allan_deviation(rate, 2.0)  # 2 Hz
    phase = np.concatenate([[0], np.cumsum(rate)]) / 2.0
    for _, row in result.iloc[::5].iterrows():
        m = int(round(row["tau_s"] * 2.0))
        second = phase[2 * m:] - 2 * phase[m:-m] + phase[:-2 * m]
        expected = np.sqrt(np.mean(second ** 2) / (2 * row["tau_s"] ** 2))
        assert row["deviation"] == pytest.approx(expected, rel=1e-9)
        assert row["terms"] == len(rate) - 2 * m + 1
    # White noise of σ = 2 at 2 Hz: σ(τ) = 2 / sqrt(2 τ), within the estimator's scatter.
    short = result[(result["tau_s"] >= 1) & (result["tau_s"] <= 20)]
    np.testing.assert_allclose(short["deviation"], 2 / np.sqrt(2 * short["tau_s"]), rtol=0.1)


def test_the_python_example_writes_its_plots(tmp_path):
    example = os.path.join(HERE, "..", "..", "examples", "python", "compensate_and_plot.py")
    result = subprocess.run([sys.executable, example, "--out", str(tmp_path), "--features", "dT,rate,lag:900"],
                            capture_output=True, text=True, env=os.environ)
    assert result.returncode == 0, result.stderr
    for name in ("before_after.png", "allan.png"):
        with open(tmp_path / name, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n", name
    model = td.load_model(tmp_path / "model.json")
    assert model.terms["gyro_x"] == ["dT", "rate", "lag:900"]
    # What it printed is the model's held-out evaluation: every axis' MSE falls.
    lines = [line for line in result.stdout.splitlines() if "held out" in line]
    assert len(lines) == 3
    for line in lines:
        before, after = (float(x) for x in line.split("MSE ")[1].split(" (°/h)")[0].split(" -> "))
        assert after < before, line


def test_report_writes_what_the_cli_report_writes(logs, tmp_path):
    train, _ = logs
    options = dict(temp=TEMPS, evaluations=6, seed=2, threads=1)
    page = td.report(train, tmp_path / "python", **options)
    assert os.path.basename(page) == "report.html" and os.path.exists(page)
    cli("report", "--data", train, "--temp", ",".join(TEMPS), "--evaluations", 6, "--seed", 2, "--threads", 1,
        "--out", tmp_path / "cli")
    with open(tmp_path / "python" / "summary.json") as a, open(tmp_path / "cli" / "summary.json") as b:
        mine, theirs = json.load(a), json.load(b)
    for summary in (mine, theirs):  # what may differ: timings, and the command line (its --out)
        drop_keys(summary, lambda key: key.endswith("seconds") or key in ("command", "timings"))
    assert mine == theirs
    with pytest.raises(td.UsageError):
        td.report(train, tmp_path / "bad", temp=TEMPS, holdout_fraction=0.3, split_time=100)


def drop_keys(value, dropped):
    if isinstance(value, dict):
        for key in [k for k in value if dropped(k)]:
            del value[key]
        for item in value.values():
            drop_keys(item, dropped)
    elif isinstance(value, list):
        for item in value:
            drop_keys(item, dropped)
