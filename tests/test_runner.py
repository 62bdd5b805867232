"""conical_pendulum.analysis.runner: fmpy.simulate_fmu's Co-Simulation run with the loop in C,
bit for bit fmpy's rows (every column, time too) on our two FMUs and on a small FMU of
another shape (tests/shapes_fmu.c: Integer and Boolean outputs, steps that fail on
request), with fmpy's exceptions and the FMU's messages where fmpy raises."""

import logging
from pathlib import Path

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from conical_pendulum.analysis import runner
from conical_pendulum.analysis.fmpy_runs import simulate_fmu
from conical_pendulum.analysis.sweep import LOOPS, LoadedFmu
from shapes import build_shapes_fmus


@pytest.fixture(scope="module")
def shapes_fmu(tmp_path_factory):
    """The shapes FMU by whether it handles a variable communication step."""
    return build_shapes_fmus(tmp_path_factory.mktemp("shapes"))


@pytest.fixture(scope="module")
def loaded():
    """FMUs loaded once per path and loop, as a sweep's worker has them."""
    fmus = {}

    def load(path, loop):
        if (path, loop) not in fmus:  # setdefault would extract a copy at every call, never removed
            fmus[path, loop] = LoadedFmu(Path(path).read_bytes(), loop)
        return fmus[path, loop]

    yield load
    for fmu in fmus.values():
        fmu.close()


def outcome(fmu: LoadedFmu, *args):
    """(rows, None, messages) or (the rows the exception kept or None, the exception's text as
    fmpy's, messages) of one simulate()."""
    fmu.messages = []
    try:
        return fmu.simulate(*args), None, fmu.messages
    except Exception as exc:
        kind = "FMICallException" if isinstance(exc, FMICallException) else type(exc).__name__
        return getattr(exc, "rows", None), f"{kind}: {exc}", fmu.messages


def assert_same_rows(got, expected):
    assert got.dtype == expected.dtype and len(got) == len(expected)
    for name in expected.dtype.names:
        assert np.array_equal(got[name], expected[name], equal_nan=True), name


def test_the_runner_compiles_here():
    assert runner.unavailable() is None


@pytest.mark.parametrize("backend", ["pythonfmu", "native"])
def test_our_fmus_bit_for_bit(backend, seed_fmu, native_seed_fmu, loaded):
    path = seed_fmu if backend == "pythonfmu" else native_seed_fmu
    fmu = loaded(path, "runner")
    outputs = [v.name for v in fmu.md.modelVariables if v.causality == "output"]
    for start_values in ({}, {"l0": 7.5, "alpha0": 0.9, "delta2": -1.0}, {"solver": 1, "rtol": 1e-6}):
        got = fmu.simulate(start_values, 10.0, 1 / 60, outputs)
        expected = simulate_fmu(
            str(path), stop_time=10.0, output_interval=1 / 60, start_values=start_values, output=outputs
        )
        assert len(got) == 601 and got["time"][-1] == 10.0
        assert_same_rows(got, expected)


@pytest.mark.parametrize("backend", ["pythonfmu", "native"])
def test_a_discarded_step_stops_where_fmpy_stops(backend, seed_fmu, native_seed_fmu, loaded):
    """pythonfmu's FMU says it terminated: fmpy records the last good point again and stops.
    The native FMU says it did not: fmpy steps again, the FMU refuses (fmi2Error) and fmpy
    raises; the runner raises the same, with the rows before the failure."""
    path = seed_fmu if backend == "pythonfmu" else native_seed_fmu
    start_values = {"alpha0": 1.2, "delta2": 3.0, "max_steps": 25}  # fails from 1.5 s by 0.5 s
    start_values |= {"solver": 1, "rtol": 1e-8, "atol": 1e-8, "across_points": 0}  # as measured
    got, got_error, got_messages = outcome(loaded(path, "runner"), start_values, 10.0, 0.5, ["energy"])
    expected, error, messages = outcome(loaded(path, "fmpy"), start_values, 10.0, 0.5, ["energy"])
    assert (got_error, got_messages) == (error, messages)
    assert "more than max_steps = 25 internal steps" in messages[0]
    if backend == "pythonfmu":
        assert_same_rows(got, expected)
        assert list(got["time"]) == [0.0, 0.5, 1.0, 1.5, 1.5]
    else:
        assert error == "FMICallException: fmi2DoStep failed with status 3 (error)." and expected is None
        assert list(got["time"]) == [0.0, 0.5, 1.0, 1.5, 1.5]  # the discard's repeat, as fmpy records it
        assert np.isfinite(got["energy"]).all()


@pytest.mark.parametrize("variable_steps", [True, False])
@pytest.mark.parametrize(
    "start_values, stop_time, interval",
    [
        ({}, 1.0, 0.1),  # 0.1 is not exact: the points are start + k interval, as fmpy's
        ({"gain": 2.0}, 1.05, 0.1),  # the last step short, or none, as the FMU allows
        ({}, 2.0 / 3.0, 1.0 / 30.0),
        ({"mode": 1, "fail_at": 0.55}, 1.0, 0.1),  # discard, terminated: stops at 0.5 s
        ({"mode": 2, "fail_at": 0.55, "repeats": 20}, 1.0, 0.1),  # discards 20 times, goes on
        ({"nan_at": 0.3, "gain": 5.0}, 0.5, 0.1),  # NaN outputs are rows like any other
    ],
)
def test_another_shape_bit_for_bit(shapes_fmu, loaded, variable_steps, start_values, stop_time, interval):
    path = shapes_fmu[variable_steps]
    outputs = ["x", "h", "count", "above"]
    got, got_error, got_messages = outcome(loaded(path, "runner"), start_values, stop_time, interval, outputs)
    expected = simulate_fmu(
        str(path), stop_time=stop_time, output_interval=interval, start_values=start_values, output=outputs
    )
    assert got_error is None
    assert_same_rows(got, expected)
    assert got.dtype["count"] == np.int32 and got.dtype["above"] == np.bool_ and got["above"].any()
    assert got_messages == outcome(loaded(path, "fmpy"), start_values, stop_time, interval, outputs)[2]


@pytest.mark.parametrize(
    "start_values, error, messages",
    [
        (
            {"gain": -1.0},
            "FMICallException: fmi2SetReal failed with status 3 (error).",
            ["gain = -1: must not be negative"],
        ),
        ({"x": 1.0}, "Exception: The start values for the following variables could not be set: x", []),
        (
            {"mode": 3, "fail_at": 0.25},
            "FMICallException: fmi2DoStep failed with status 3 (error).",
            ["step from t = 0.2 s by 0.1 s refused"],
        ),
    ],
)
def test_refusals_raise_as_fmpy_raises(shapes_fmu, loaded, start_values, error, messages):
    args = (start_values, 1.0, 0.1, ["x", "count"])
    kept, *got = outcome(loaded(shapes_fmu[True], "runner"), *args)
    assert outcome(loaded(shapes_fmu[True], "fmpy"), *args) == (None, *got)
    assert got == [error, messages]
    # a failed step: the runner also keeps the rows before it; a refused start value has none
    if "fail_at" in start_values:
        assert list(kept["time"]) == [0.0, 0.1, 0.2]
    else:
        assert kept is None


def test_a_failing_get_raises_with_its_function(shapes_fmu, loaded, monkeypatch):
    fmu = loaded(shapes_fmu[True], "runner")
    rows = fmu.simulate({}, 0.3, 0.1, ["x", "count"])
    assert list(rows["count"]) == [0, 1, 2, 3]
    shapes = runner.Runner(fmu.slave, fmu.md, ["x"])
    shapes._arrays[0][:] = 99  # a value reference the FMU refuses
    fmu.slave.instantiate(callbacks=fmu._callbacks, loggingOn=True)
    try:
        with pytest.raises(FMICallException, match=r"fmi2GetReal failed with status 3 \(error\)"):
            shapes.simulate(0.3, 0.1)
    finally:
        fmu.slave.fmi2FreeInstance(fmu.slave.component)


def test_the_sweep_reports_failures_alike_by_either_loop(shapes_fmu, loaded):
    runs = [{}, {"mode": 1, "fail_at": 0.55}, {"nan_at": 0.3}, {"gain": -1.0}, {"mode": 3, "fail_at": 0.25}]
    for variable_steps in (True, False):
        results = {
            loop: [
                loaded(shapes_fmu[variable_steps], loop).run(run, 1.05, 0.1, ["x", "count"]) for run in runs
            ]
            for loop in LOOPS
        }
        for run, (rows, ok, message), (fmpy_rows, fmpy_ok, fmpy_message) in zip(runs, *results.values()):
            assert (ok, message) == (fmpy_ok, fmpy_message)
            if run.get("mode") == 3:  # a step refused (fmi2Error): fmpy's loop keeps no rows
                assert fmpy_rows is None and list(rows["time"]) == [0.0, 0.1, 0.2]
            elif rows is None:
                assert fmpy_rows is None
            else:
                assert_same_rows(rows, fmpy_rows)
        oks = [ok for _, ok, _ in results["runner"]]
        messages = [message for _, _, message in results["runner"]]
        assert oks == [variable_steps, False, False, False, False]
        assert messages[0] == ("" if variable_steps else "stopped at t = 1 s, short of the stop time 1.05 s")
        assert messages[1] == "step from t = 0.5 s by 0.1 s refused"
        assert messages[2].endswith("non-finite values in x")
        assert messages[3].startswith("gain = -1: must not be negative; fmi2SetReal failed")


def test_without_a_compiler_a_loaded_fmu_falls_back_to_fmpy(shapes_fmu, monkeypatch, caplog):
    monkeypatch.setattr(runner, "unavailable", lambda: "no C compiler cc")
    with caplog.at_level(logging.WARNING):
        fmu = LoadedFmu(shapes_fmu[True].read_bytes())
    try:
        assert (fmu.loop, fmu.fallback) == ("fmpy", "no C compiler cc")
        assert "Shapes: fmpy's loop instead of the compiled runner: no C compiler cc" in caplog.text
        rows, ok, message = fmu.run({}, 1.0, 0.1, ["x"])
        assert ok and message == "" and rows["time"][-1] == 1.0
    finally:
        fmu.close()
