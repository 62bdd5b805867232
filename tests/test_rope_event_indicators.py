"""Model Exchange's event indicators: each elastic rope's taut margin (taut_margin<i>), whose
sign changes are the rope's snaps and slackenings. A host's solver finds them from the indicators
(fmpy's CVode here), and the FMU's event update counts the snaps (snaps<i>, taut<i>). Checked
against the closed forms of a load dropped onto an undamped rope that tests/test_elastic_ropes.py
checks the core with: the meeting time sqrt(2 h / g) and the peak tension
m g (1 + sqrt(1 + 2 k h / (m g))), k = EA / l."""

import contextlib
import ctypes
import shutil

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model
from fmpy.fmi3 import FMU3Model
from fmpy.validation import validate_fmu

from conical_pendulum import Link, Scene
from conical_pendulum.analysis.fmpy_runs import logging_callbacks, run_fmu
from test_elastic_ropes import G, elastic

M, LENGTH, H, STIFFNESS = 100.0, 10.0, 0.5, 1e6
DROP = Scene(links=(elastic(length=LENGTH, stiffness=STIFFNESS, mass=M),), outputs=("energy",))
DROPPED = {"alpha0": 0.0, "beta0": 0.0, "r0": LENGTH - H, "v_r0": 0.0}  # 0.5 m of slack, at rest
PLAIN = Scene(links=(Link(),))
N_ARGUMENT = {2: "ni", 3: "nEventIndicators"}


@contextlib.contextmanager
def model_exchange(path, fmi_version, reals=None):
    """A Model Exchange instance through fmpy's low-level API, reals (by the FMU's own names: an
    FMI 3.0 array whole) set and initialized (in event mode), and the messages its logger sent;
    freed on leaving."""
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipdir = extract(str(path))
    messages = []
    options = {
        "guid": md.guid,
        "unzipDirectory": unzipdir,
        "modelIdentifier": md.modelExchange.modelIdentifier,
        "instanceName": "me",
    }
    fmu = FMU2Model(**options) if fmi_version == 2 else FMU3Model(**options)
    try:
        if fmi_version == 2:
            callbacks = logging_callbacks(lambda status, text: messages.append(text))
            fmu.instantiate(callbacks=callbacks, loggingOn=True)
            for name, value in (reals or {}).items():
                fmu.setReal([vr[name]], [value])
            fmu.setupExperiment(startTime=0.0)
            fmu.enterInitializationMode()
        else:
            fmu.instantiate(
                loggingOn=True, logMessage=lambda env, status, category, text: messages.append(text.decode())
            )
            for name, values in (reals or {}).items():
                fmu.setFloat64([vr[name]], values)
            fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        yield fmu, messages
    finally:
        fmu.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)


@pytest.mark.parametrize(
    "fmi_version, arrays, indicator", [(2, True, None), (3, True, "taut_margin"), (3, False, "taut_margin0")]
)
def test_the_model_description_declares_the_taut_margin_and_validates(
    built_fmu, fmi_version, arrays, indicator
):
    path = built_fmu(DROP, backend="native", fmi_version=fmi_version, arrays=arrays)
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    assert md.numberOfEventIndicators == 1
    if indicator:  # FMI 3.0 names it in ModelStructure, as an output of the same dependencies
        assert [u.variable.name for u in md.eventIndicators] == [indicator]
        (output,) = [u for u in md.outputs if u.variable.name == indicator]
        assert md.eventIndicators[0].dependencies == output.dependencies != []


def snap(result):
    """The rows fmpy recorded at each event (before and after the event update: one time twice),
    as (time, the row before, the row after)."""
    twice = np.flatnonzero(np.diff(result["time"]) == 0)
    return [(result["time"][k], result[k], result[k + 1]) for k in twice]


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_model_exchange_locates_the_snap_and_its_peak_from_the_taut_margin(built_fmu, fmi_version):
    """fmpy's CVode at 1e-10 finds the rope's snap and its slackening a spring's half cycle
    later; the taut margin changes sign there, the event update counts one snap, and the
    tension peaks as the energy balance says (its largest sample, refined by a parabola)."""
    path = built_fmu(DROP, backend="native", fmi_version=fmi_version)
    result = run_fmu(
        path,
        stop_time=0.6,
        output_interval=1e-4,
        fmi_type="ModelExchange",
        relative_tolerance=1e-10,
        start_values=DROPPED,
    )
    (taut_at, before_taut, after_taut), (slack_at, before_slack, after_slack) = snap(result)
    fall = np.sqrt(2 * H / G)
    assert abs(taut_at - fall) < 1e-8
    earlier = result[result["time"] < taut_at]
    assert (
        (earlier["taut_margin0"] < 0).all()
        and (earlier["snaps0"] == 0).all()
        and (earlier["taut0"] == 0).all()
    )
    assert abs(before_taut["taut_margin0"]) < 1e-3  # N, of 5e4 at the start: at the root
    assert (after_taut["taut0"], after_taut["snaps0"]) == (1.0, 1.0)
    k, v0 = STIFFNESS / LENGTH, np.sqrt(2 * G * H)
    omega, s_e = np.sqrt(k / M), M * G / k
    # the half cycle's time: the solver's error over it besides the location's
    assert abs(slack_at - fall - (np.pi + 2 * np.arctan(omega * s_e / v0)) / omega) < 5e-8
    assert abs(before_slack["taut_margin0"]) < 1e-3 and before_slack["taut0"] == 1.0
    assert (after_slack["taut0"], after_slack["snaps0"]) == (0.0, 1.0)
    between = result[(result["time"] > taut_at) & (result["time"] < slack_at)]
    assert (between["taut_margin0"] > 0).all() and (between["taut0"] == 1).all()
    tension = between["T_rope0"]
    i = int(np.argmax(tension))
    low, top, high = tension[i - 1 : i + 2]
    peak = top + (high - low) ** 2 / (8 * (2 * top - low - high))  # the parabola's vertex
    expected = M * G * (1 + np.sqrt(1 + 2 * k * H / (M * G)))
    assert abs(peak / expected - 1) < 1e-6


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_a_scene_without_elastic_ropes_has_no_event_indicators(built_fmu, fmi_version):
    path = built_fmu(PLAIN, backend="native", fmi_version=fmi_version)
    assert read_model_description(str(path)).numberOfEventIndicators == 0
    with model_exchange(path, fmi_version) as (fmu, messages):
        if fmi_version == 3:
            assert fmu.getNumberOfEventIndicators() == 0
        fmu.getEventIndicators(None, 0)
        with pytest.raises(FMICallException) as refused:
            fmu.getEventIndicators((ctypes.c_double * 1)(), 1)
        assert refused.value.status == 3
    name = f"fmi{fmi_version}GetEventIndicators"
    assert messages == [f"{name}: {N_ARGUMENT[fmi_version]} = 1, but the number of event indicators is 0"]


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_the_taut_margin_is_the_indicator_and_a_bad_call_is_refused_naming_its_argument(
    built_fmu, fmi_version
):
    path = built_fmu(DROP, backend="native", fmi_version=fmi_version)
    vr = {v.name: v.valueReference for v in read_model_description(str(path)).modelVariables}
    slack = {"r0": LENGTH - H} if fmi_version == 2 else {"r": [LENGTH - H]}  # FMI 3.0: an array of one
    with model_exchange(path, fmi_version, slack) as (fmu, messages):
        z = (ctypes.c_double * 2)()
        fmu.getEventIndicators(z, 1)
        if fmi_version == 2:
            margin = fmu.getReal([vr["taut_margin0"]])
        else:
            margin = fmu.getFloat64([vr["taut_margin"]], nValues=1)
        assert list(z) == [*margin, 0.0] and margin[0] == -STIFFNESS * H / LENGTH
        for n, array in ((2, z), (0, z), (1, None)):
            with pytest.raises(FMICallException) as refused:
                fmu.getEventIndicators(array, n)
            assert refused.value.status == 3
    name, n = f"fmi{fmi_version}GetEventIndicators", N_ARGUMENT[fmi_version]
    assert messages == [
        f"{name}: {n} = 2, but the number of event indicators is 1",
        f"{name}: {n} = 0, but the number of event indicators is 1",
        f"{name}: eventIndicators is NULL",
    ]
