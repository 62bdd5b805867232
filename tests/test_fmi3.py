"""The native FMI 3.0 FMU (builder.fmi.fmi3, runtime/csrc/fmi/fmi3_glue.c): the FMI 2.0 native FMU's
behaviour through FMI 3.0's API, run by fmpy against the FMI 2.0 native FMU of the same scene."""

import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from ctypes import c_double
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from conical_pendulum import Scene
from conical_pendulum.analysis.fmpy_runs import run_fmu, simulate_fmu
from conical_pendulum.builder.fmi.contract import LOG_CATEGORIES
from conical_pendulum.builder.packaging.native import fmi_headers
from fmu_helpers import Instance3, fmi3_names, fmi3_start_values

ROOT = Path(__file__).resolve().parent.parent
OK, DISCARD, ERROR = 0, 2, 3
SCENE = Scene.uniform(3, coupling=True)
START = {"l0": 8.0, "alpha0": 0.5, "delta2": 0.3}


@pytest.fixture(scope="module")
def fmus(built_fmu):
    """(FMI 3.0 native FMU, FMI 2.0 native FMU) of the coupled 3-link chain."""
    return tuple(built_fmu(SCENE, backend="native", fmi_version=version) for version in (3, 2))


def column(result, name, elements):
    """An FMI 2.0 scalar's column of an fmpy result of the FMI 3.0 FMU."""
    if name in elements:
        array, k = elements[name]
        return result[array][:, k]
    return result[name]


def test_fmpy_validates_it_and_it_ships_what_fmi_3_asks(fmus):
    fmi3, _ = fmus
    assert validate_fmu(str(fmi3)) == []
    archive = zipfile.ZipFile(fmi3)
    names = archive.namelist()
    assert "binaries/x86_64-linux/ConicalPendulum.so" in names
    assert {"sources/buildDescription.xml", "sources/fmi3_glue.c", "sources/fmu_config.h"} <= set(names)
    assert "sources/fmi2_glue.c" not in names
    build = ET.fromstring(archive.read("sources/buildDescription.xml"))
    listed = [f.get("name") for f in build.iter("SourceFile")]
    assert "fmi3_glue.c" in listed and all(f"sources/{name}" in names for name in listed)
    root = ET.fromstring(archive.read("modelDescription.xml"))
    assert root.get("fmiVersion") == "3.0" and root.get("instantiationToken")
    for interface in ("ModelExchange", "CoSimulation"):
        element = root.find(interface)
        assert element.get("providesEvaluateDiscreteStates") == "false"
        assert element.get("canGetAndSetFMUState") == element.get("canSerializeFMUState") == "true"
    assert root.find("CoSimulation").get("hasEventMode") == "false"
    assert [c.get("name") for c in root.find("LogCategories")] == list(LOG_CATEGORIES)


def test_exports_only_fmi3_functions(fmus, tmp_path):
    fmi3, _ = fmus
    zipfile.ZipFile(fmi3).extractall(tmp_path)
    so = tmp_path / "binaries" / "x86_64-linux" / "ConicalPendulum.so"
    symbols = subprocess.run(
        ["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True
    ).stdout.split()[2::3]
    assert symbols and all(name.startswith("fmi3") for name in symbols)
    header = (fmi_headers() / "fmi3Functions.h").read_text()
    declared = set(re.findall(r"FMI3_Export\s+fmi3\w+TYPE\s+(fmi3\w+)", header))
    assert len(declared) == 75 and set(symbols) == declared  # the whole FMI 3.0 API


def test_same_variables_and_value_references_as_the_fmi2_fmu_per_link_ones_as_arrays(fmus):
    ours, theirs = (read_model_description(str(path)) for path in fmus)
    elements, _ = fmi3_names(fmus[0])
    by_name = {v.name: v for v in ours.modelVariables}
    types = {"Real": "Float64", "Integer": "Int32", "Enumeration": "Enumeration"}
    n_links = by_name["n_links"]
    assert (n_links.type, n_links.causality, n_links.start) == ("UInt64", "structuralParameter", "3")
    for v in theirs.modelVariables:
        array, k = elements.get(v.name, (v.name, None))
        mine = by_name[array]
        assert (mine.type, mine.causality, mine.variability) == (types[v.type], v.causality, v.variability)
        assert (mine.unit, mine.displayUnit, mine.min, mine.max, mine.nominal) == (
            v.unit,
            v.displayUnit,
            v.min,
            v.max,
            v.nominal,
        )  # builder.fmi.units: the same declarations in both versions
        if k is None:
            assert (mine.valueReference, mine.start, mine.dimensions) == (v.valueReference, v.start, [])
            continue
        assert [d.variable for d in mine.dimensions] == [n_links]
        if k == 0:  # an array's value reference is its first element's
            assert mine.valueReference == v.valueReference
        if v.start is not None:
            assert mine.start.split()[k] == v.start
    for name, (array, k) in {"l0": ("l", 0), "alpha2": ("alpha", 2), "bob1_x": ("bob_x", 1)}.items():
        assert elements[name] == (array, k)
    assert elements["der(omega1)"] == ("der(omega)", 1)
    assert by_name["der(alpha)"].derivative.name == "alpha"
    assert by_name["time"].causality == "independent"
    assert len(ours.derivatives) == 4  # der(alpha), der(beta), der(omega), der(delta)
    assert {"energy", "F_pivot_x", "alpha", "link_qw"} <= {u.variable.name for u in ours.outputs}


def test_co_simulation_is_the_fmi2_fmus_bit_for_bit(fmus):
    """fmpy's simulate_fmu on both: it records the FMI 3.0 FMU's arrays as (n,) columns and takes
    an array's start values as a list."""
    fmi3, fmi2 = fmus
    elements, _ = fmi3_names(fmi3)
    ours, theirs = (
        simulate_fmu(
            str(path), fmi_type="CoSimulation", stop_time=3.0, output_interval=0.05, start_values=starts
        )
        for path, starts in ((fmi3, fmi3_start_values(fmi3, START)), (fmi2, START))
    )
    assert len(ours) == len(theirs) == 61
    assert ours["alpha"].shape == (61, 3)
    for name in theirs.dtype.names:
        assert np.array_equal(column(ours, name, elements), theirs[name]), name


def test_model_exchange_with_cvode_agrees_with_the_fmi2_fmu(fmus):
    fmi3, fmi2 = fmus
    elements, _ = fmi3_names(fmi3)
    ours, theirs = (
        simulate_fmu(
            str(path),
            fmi_type="ModelExchange",
            solver="CVode",
            relative_tolerance=1e-8,
            stop_time=3.0,
            output_interval=0.05,
            start_values=starts,
        )
        for path, starts in ((fmi3, fmi3_start_values(fmi3, START)), (fmi2, START))
    )
    for name in SCENE.state_names():
        assert np.allclose(column(ours, name, elements), theirs[name], rtol=1e-6, atol=1e-6), name


def test_wrong_calls_are_refused_naming_what(fmus):
    fmu = Instance3(fmus[0])
    with pytest.raises(FMICallException):
        fmu.fmu.getFloat64([10000])
    with pytest.raises(FMICallException):
        fmu.fmu.getBoolean([0])
    with pytest.raises(FMICallException):
        fmu.fmu.setFloat64([fmu.vr["time"]], [1.0])
    with pytest.raises(FMICallException):  # alpha stands for 3 values
        fmu.fmu.getFloat64([fmu.vr["alpha"]], nValues=2)
    with pytest.raises(FMICallException):  # an array's element other than the first is no variable
        fmu.fmu.getFloat64([fmu.records["alpha1"]["value_reference"]])
    with pytest.raises(FMICallException):
        fmu.fmu.setUInt64([fmu.vr["n_links"]], [4])
    texts = fmu.texts(ERROR)
    assert "value reference 10000 is not a Float64 variable" in texts
    assert "this FMU has no Boolean variables" in texts
    assert "time is the independent variable" in texts
    assert "nValues = 2, but the 1 value references have 3 values" in texts
    assert "is not a variable (it is alpha1, an element of an array" in texts
    assert "n_links = 4: the number of links is fixed when the FMU is built (3)" in texts
    assert fmu.fmu.getUInt64([fmu.vr["n_links"]]) == [3]
    both = fmu.fmu.getFloat64([fmu.vr["g"], fmu.vr["l"], fmu.vr["energy"]], nValues=5)
    assert both[:4] == [*fmu.get("g"), *fmu.get("l0", "l1", "l2")] and both[4] == fmu.get("energy")[0]
    assert fmu.get("time") == [0.0]
    fmu.step(0.25)
    assert fmu.get("time") == [0.25]
    fmu.close()


def test_a_bad_tolerance_is_refused_naming_fmi3_enter_initialization_mode(fmus):
    """FMI 3.0 has no setupExperiment: the tolerance comes with fmi3EnterInitializationMode, and
    its refusal names that; the instance stays where it was and takes a good one."""
    fmu = Instance3(fmus[0], initialize=False)
    with pytest.raises(FMICallException) as refusal:
        fmu.fmu.enterInitializationMode(tolerance=-1.0, startTime=0.0)
    assert refusal.value.status == ERROR
    assert "fmi3EnterInitializationMode: tolerance = -1.0: " in fmu.texts(ERROR)
    assert "setupExperiment" not in fmu.texts()
    fmu.fmu.enterInitializationMode(tolerance=1e-6, startTime=0.0)
    fmu.fmu.exitInitializationMode()
    fmu.step(0.1)
    assert np.isfinite(fmu.get("alpha0")).all()
    fmu.close()


def test_early_return_and_event_mode_are_what_the_model_description_says(fmus):
    with pytest.raises(Exception, match="Failed to instantiate"):
        Instance3(fmus[0], eventModeUsed=True)
    fmu = Instance3(fmus[0], earlyReturnAllowed=True)
    event, terminate, early, last = fmu.step(0.5)
    assert (event, terminate, early, last) == (False, False, False, 0.5)
    fmu.close()


def test_reset_gives_a_fresh_instance(fmus):
    fmu = Instance3(fmus[0], start_values=START)
    for _ in range(4):
        fmu.step(0.25)
    first = fmu.get(*SCENE.state_names())
    fmu.fmu.reset()
    assert fmu.fmu.getFMUState  # still usable
    fmu.set(START)
    fmu.fmu.enterInitializationMode(startTime=0.0)
    fmu.fmu.exitInitializationMode()
    fmu.time = 0.0
    for _ in range(4):
        fmu.step(0.25)
    assert fmu.get(*SCENE.state_names()) == first
    fmu.close()


def test_log_categories_as_the_model_description_declares_them(fmus):
    fmu = Instance3(fmus[0])
    fmu.fmu.setDebugLogging(True, list(LOG_CATEGORIES))
    with pytest.raises(FMICallException):
        fmu.fmu.setDebugLogging(True, ["logEverything"])
    assert 'log category "logEverything" is not this FMU\'s' in fmu.texts(ERROR)
    fmu.close()


# FMI 3.0's state machines, a few functions in each state this FMU enters: (state, function,
# allowed). Calls that are allowed but need arguments the test does not give are left out.
def _reach(fmu, state):
    if state == "Instantiated":
        return
    fmu.fmu.enterInitializationMode(startTime=0.0)
    if state == "Initialization Mode":
        return
    fmu.fmu.exitInitializationMode()
    if state == "Continuous-Time Mode":
        fmu.fmu.enterContinuousTimeMode()
    if state == "Terminated":
        fmu.fmu.terminate()


CALLS = {
    "doStep": lambda i: i.fmu.doStep(0.0, 0.01),
    "getFloat64": lambda i: i.fmu.getFloat64([i.vr["g"]]),
    "setFloat64 input": lambda i: i.fmu.setFloat64([i.vr["a_pivot_x"]], [0.5]),
    "enterInitializationMode": lambda i: i.fmu.enterInitializationMode(startTime=0.0),
    "exitInitializationMode": lambda i: i.fmu.exitInitializationMode(),
    "terminate": lambda i: i.fmu.terminate(),
    "enterContinuousTimeMode": lambda i: i.fmu.fmi3EnterContinuousTimeMode(i.fmu.component),
    "setTime": lambda i: i.fmu.fmi3SetTime(i.fmu.component, 0.0),
    "updateDiscreteStates": lambda i: i.fmu.updateDiscreteStates(),
    "enterEventMode": lambda i: i.fmu.enterEventMode(),
    "enterConfigurationMode": lambda i: i.fmu.fmi3EnterConfigurationMode(i.fmu.component),
    "getFMUState": lambda i: i.fmu.freeFMUState(i.fmu.getFMUState()),
}
CO_SIMULATION_TABLE = {
    # state: calls allowed (the rest of CO_SIMULATION_CALLS refused)
    "Instantiated": {"enterInitializationMode", "setFloat64 input", "getFMUState"},
    "Initialization Mode": {"exitInitializationMode", "getFloat64", "setFloat64 input", "getFMUState"},
    "Step Mode": {"doStep", "getFloat64", "setFloat64 input", "terminate", "getFMUState"},
    "Terminated": {"getFloat64", "getFMUState"},
}
CO_SIMULATION_CALLS = [
    "doStep",
    "getFloat64",
    "setFloat64 input",
    "enterInitializationMode",
    "exitInitializationMode",
    "terminate",
    "enterContinuousTimeMode",
    "setTime",
    "enterEventMode",
    "enterConfigurationMode",
    "getFMUState",
]
MODEL_EXCHANGE_TABLE = {
    "Instantiated": {"enterInitializationMode", "setFloat64 input", "getFMUState"},
    "Initialization Mode": {"exitInitializationMode", "getFloat64", "setFloat64 input", "getFMUState"},
    "Event Mode": {
        "getFloat64",
        "setFloat64 input",
        "terminate",
        "enterContinuousTimeMode",
        "setTime",
        "updateDiscreteStates",
        "getFMUState",
    },
    "Continuous-Time Mode": {
        "getFloat64",
        "setFloat64 input",
        "terminate",
        "setTime",
        "enterEventMode",
        "getFMUState",
    },
    "Terminated": {"getFloat64", "getFMUState"},
}
MODEL_EXCHANGE_CALLS = [
    "getFloat64",
    "setFloat64 input",
    "enterInitializationMode",
    "exitInitializationMode",
    "terminate",
    "enterContinuousTimeMode",
    "setTime",
    "updateDiscreteStates",
    "enterEventMode",
    "enterConfigurationMode",
    "getFMUState",
]


@pytest.mark.parametrize(
    ("interface", "state", "call"),
    [("CoSimulation", s, c) for s in CO_SIMULATION_TABLE for c in CO_SIMULATION_CALLS]
    + [("ModelExchange", s, c) for s in MODEL_EXCHANGE_TABLE for c in MODEL_EXCHANGE_CALLS],
)
def test_state_table(fmus, interface, state, call):
    table = CO_SIMULATION_TABLE if interface == "CoSimulation" else MODEL_EXCHANGE_TABLE
    fmu = Instance3(fmus[0], interface, initialize=False)
    _reach(fmu, state)
    fmu.messages.clear()
    allowed = call in table[state]
    try:
        status = CALLS[call](fmu)
        status = status if isinstance(status, int) else OK
    except FMICallException as exc:
        status = exc.status
    except Exception:  # fmpy's wrappers that return a tuple raise on the status themselves
        status = ERROR
    if allowed:
        assert status == OK, (call, state, fmu.texts())
    else:
        assert status == ERROR, (call, state)
        if (call, state) == ("enterEventMode", "Step Mode"):  # hasEventMode is false
            assert "no event mode in Co-Simulation" in fmu.texts(ERROR)
        elif call == "enterConfigurationMode" and state in ("Instantiated", "Step Mode", "Event Mode"):
            assert "no tunable structural parameters" in fmu.texts(ERROR)
        else:
            assert "is not allowed in" in fmu.texts(ERROR), fmu.texts()
    fmu.close()


def test_directional_derivatives_against_central_differences(fmus):
    """Unknowns and knowns by array: der(alpha) .. der(delta) (12 values) against one element of
    a state array, seeded by its unit vector (3 values)."""
    fmu = Instance3(fmus[0], "ModelExchange", start_values=START)
    fmu.fmu.enterContinuousTimeMode()
    names = SCENE.state_names()
    n = len(names)
    x = np.array(fmu.get(*names))
    derivatives = [fmu.vr[f"der({array})"] for array in ("alpha", "beta", "omega", "delta")]
    for known in ("alpha0", "beta1", "omega2", "delta0"):
        array, index = fmu.elements[known]
        seed = [1.0 if k == index else 0.0 for k in range(3)]
        exact = fmu.fmu.getDirectionalDerivative(derivatives, [fmu.vr[array]], seed, nSensitivity=n)
        h, columns = 1e-6, []
        for sign in (1, -1):
            shifted = x.copy()
            shifted[names.index(known)] += sign * h
            fmu.fmu.setContinuousStates((c_double * n)(*shifted), n)
            dx = (c_double * n)()
            fmu.fmu.getContinuousStateDerivatives(dx, n)
            columns.append(np.array(dx))
        fmu.fmu.setContinuousStates((c_double * n)(*x), n)
        central = (columns[0] - columns[1]) / (2 * h)
        assert np.allclose(exact, central, rtol=1e-6, atol=1e-6), known
    with pytest.raises(FMICallException):
        fmu.fmu.getDirectionalDerivative(derivatives, [fmu.vr["alpha"]], [0.0, float("nan"), 0.0], n)
    assert "seed of alpha1 = nan: must be finite" in fmu.texts(ERROR)
    with pytest.raises(FMICallException):
        fmu.fmu.getDirectionalDerivative(derivatives, [fmu.vr["alpha"]], [1.0], n)
    assert "nSeed = 1 and nSensitivity = 12, but the knowns have 3 values" in fmu.texts(ERROR)
    fmu.close()


def test_build_fmu_py_builds_it_and_refuses_fmi_3_without_native(tmp_path):
    out = tmp_path / "Two.fmu"
    command = [sys.executable, str(ROOT / "build_fmu.py"), "--links", "2", "--output", str(out), "--no-check"]
    run = subprocess.run([*command, "--native", "--fmi", "3"], check=False, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "FMI 3.0" in run.stdout and read_model_description(str(out)).fmiVersion == "3.0"
    run = subprocess.run([*command, "--fmi", "3"], check=False, capture_output=True, text=True)
    assert run.returncode != 0 and "--fmi 3: only the native FMU is FMI 3.0; add --native" in run.stderr


# about a minute: CMake's configure and compile from the FMI 3.0 build description alone
def test_a_host_rebuilds_the_binary_from_the_sources_and_build_description(fmus, tmp_path):
    """fmpy's build_platform_binary (CMake) reads sources/buildDescription.xml alone."""
    from fmpy.build import build_platform_binary

    fmi3, _ = fmus
    folder = tmp_path / "fmu"
    zipfile.ZipFile(fmi3).extractall(folder)
    shutil.rmtree(folder / "binaries")
    (tmp_path / "build").mkdir()
    build_platform_binary(folder, build_dir=tmp_path / "build")
    assert (folder / "binaries" / "x86_64-linux" / "ConicalPendulum.so").exists()
    starts = fmi3_start_values(fmi3, START)
    rebuilt, shipped = (
        simulate_fmu(str(path), stop_time=2.0, output_interval=0.05, start_values=starts)
        for path in (folder, fmi3)
    )
    for name in ("alpha", "beta", "energy"):
        np.testing.assert_allclose(rebuilt[name], shipped[name], rtol=1e-9, atol=1e-12)


def test_run_fmu_reads_it_by_the_fmi2_fmus_names(fmus):
    """analysis.fmpy_runs.run_fmu (what build_fmu.py's check, its CSV and plots read): the FMI
    3.0 FMU takes and gives the FMI 2.0 scalar names, its arrays set whole and split."""
    ours, theirs = (run_fmu(path, stop_time=1.0, output_interval=0.1, start_values=START) for path in fmus)
    assert set(ours.dtype.names) == set(theirs.dtype.names)
    for name in theirs.dtype.names:
        np.testing.assert_array_equal(ours[name], theirs[name], err_msg=name)
