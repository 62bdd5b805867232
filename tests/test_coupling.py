"""Coupling variables: the pivot's acceleration in, the force on the support out."""

import math
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from conical_pendulum import Scene
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.analysis.simulate import simulate
from conical_pendulum.builder.compiler import load_core
from fmu_helpers import Instance

COUPLED = Scene.uniform(3, coupling=True)
TOTAL_MASS = 3 * (10.0 + 5.0)
REST = {f"{s}{i}": 0.0 for s in ("alpha", "beta") for i in range(3)}
TIGHT = {"solver": 2, "rtol": 1e-12, "atol": 1e-12}


def constant_input(**values):
    """An fmpy input signal holding the pivot's acceleration at these values."""
    names = ["a_pivot_x", "a_pivot_y", "a_pivot_z"]
    return np.array(
        [(0.0, *(values.get(n, 0.0) for n in names))], dtype=[("time", float)] + [(n, float) for n in names]
    )


def test_model_description_declares_inputs_and_feedthrough(coupled_fmu):
    assert validate_fmu(str(coupled_fmu)) == []
    root = ET.fromstring(zipfile.ZipFile(coupled_fmu).read("modelDescription.xml"))
    variables = root.find("ModelVariables").findall("ScalarVariable")
    index = {v.get("name"): k for k, v in enumerate(variables, start=1)}
    for axis in "xyz":
        var = variables[index[f"a_pivot_{axis}"] - 1]
        assert (var.get("causality"), var.get("variability")) == ("input", "continuous")
        assert float(var.find("Real").get("start")) == 0.0
        assert "held over each communication step" in var.get("description")
    inputs = " ".join(str(index[f"a_pivot_{axis}"]) for axis in "xyz")
    outputs = {
        int(u.get("index")): u.get("dependencies")
        for u in root.find("ModelStructure/Outputs").findall("Unknown")
    }
    for name, k in index.items():
        if k in outputs:
            assert outputs[k] == (inputs if name.startswith("F_pivot_") else ""), name
    assert "held over each communication step" in root.get("description")


def test_hanging_at_rest_the_pivot_carries_the_weight(coupled_fmu):
    result = run_fmu(coupled_fmu, stop_time=5.0, start_values={**REST, "g": 9.81})
    np.testing.assert_allclose(result["F_pivot_y"], -TOTAL_MASS * 9.81, rtol=1e-13)
    assert np.abs(result["F_pivot_x"]).max() == 0.0 and np.abs(result["F_pivot_z"]).max() == 0.0
    assert np.abs(result["alpha0"]).max() == 0.0


def test_upward_pivot_acceleration_is_stronger_gravity(coupled_fmu):
    """Seen from the support, accelerating up by a is gravity g + a: the same motion."""
    result = run_fmu(coupled_fmu, input=constant_input(a_pivot_y=5.0), start_values=TIGHT)
    native = simulate(Scene.uniform(3), result["time"], parameters={"g": 9.8 + 5.0}, rtol=1e-12, atol=1e-12)
    for name in ("alpha0", "beta1", "delta2", "bob2_x"):
        assert np.abs(result[name] - native[name]).max() < 1e-9, name


def swing_period(fmu, a_up):
    """Period of a small planar swing (beta) of one link, from its zero crossings."""
    result = run_fmu(
        fmu,
        stop_time=20.0,
        output_interval=1e-3,
        input=constant_input(a_pivot_y=a_up),
        start_values={**TIGHT, "alpha0": 0.0, "beta0": 0.01},
    )
    t, beta = result["time"], result["beta0"]
    k = np.nonzero((beta[:-1] > 0) & (beta[1:] <= 0))[0]
    crossings = t[k] + (t[k + 1] - t[k]) * beta[k] / (beta[k] - beta[k + 1])
    return np.diff(crossings).mean()


def test_upward_pivot_acceleration_changes_the_period_as_g_plus_a(built_fmu):
    fmu = built_fmu(Scene.uniform(1, coupling=True))
    still, lifted = swing_period(fmu, 0.0), swing_period(fmu, 4.0)
    assert lifted / still == pytest.approx(math.sqrt(9.8 / (9.8 + 4.0)), rel=1e-6)
    # and the compound pendulum's own small-swing period, to the amplitude correction
    l, M, m, r = 10.0, 10.0, 5.0, 0.5
    inertia = M * (3 * r**2 + l**2) / 12 + M * (l / 2) ** 2 + m * l**2
    small = 2 * math.pi * math.sqrt(inertia / ((M * l / 2 + m * l) * 9.8))
    assert still == pytest.approx(small * (1 + 0.01**2 / 16), rel=1e-6)


def test_pivot_force_and_acceleration_obey_newton_for_the_whole_chain(coupled_fmu):
    """-F_pivot + M g = M (a_pivot + r_cm''), r_cm'' by finite differences of the outputs."""
    a = np.array([1.3, -2.1, 0.7])
    dt = 1e-3
    result = run_fmu(
        coupled_fmu,
        stop_time=3.0,
        output_interval=dt,
        start_values=TIGHT,
        input=constant_input(a_pivot_x=a[0], a_pivot_y=a[1], a_pivot_z=a[2]),
    )
    centre = sum(
        10.0 * np.column_stack([result[f"link{i}_{c}"] for c in "xyz"])
        + 5.0 * np.column_stack([result[f"bob{i}_{c}"] for c in "xyz"])
        for i in range(3)
    )
    centre /= TOTAL_MASS
    # fourth-order central difference for the second derivative
    acc = (-centre[4:] + 16 * centre[3:-1] - 30 * centre[2:-2] + 16 * centre[1:-3] - centre[:-4]) / (
        12 * dt**2
    )
    force = np.column_stack([result[f"F_pivot_{c}"] for c in "xyz"])[2:-2]
    gravity = np.array([0.0, -9.8, 0.0])
    residual = -force + TOTAL_MASS * gravity - TOTAL_MASS * (a + acc)
    assert np.abs(residual).max() < 1e-5 * TOTAL_MASS * 9.8
    assert np.abs(acc).max() > 1.0  # the chain does swing hard


def test_inputs_are_set_while_stepping_and_the_force_answers_at_once(coupled_fmu):
    core = load_core(COUPLED)
    fmu = Instance(coupled_fmu)
    fmu.step(0.5)
    fmu.set({"a_pivot_x": 3.0, "a_pivot_z": -1.0})
    state = fmu.get(*COUPLED.state_names())
    p = COUPLED.parameters({"a_pivot_x": 3.0, "a_pivot_z": -1.0})
    expected = core.outputs(state, p)[[COUPLED.output_names().index(f"F_pivot_{c}") for c in "xyz"]]
    assert fmu.get("F_pivot_x", "F_pivot_y", "F_pivot_z") == pytest.approx(expected, rel=1e-14)
    fmu.step(0.5)
    assert fmu.get("a_pivot_x", "a_pivot_z") == [3.0, -1.0]
    with pytest.raises(FMICallException):
        fmu.set({"a_pivot_y": float("nan")})
    assert any(text.startswith("a_pivot_y = nan: must be finite") for _, text in fmu.messages)
    fmu.close(after_fatal=True)


def test_input_held_over_a_step_equals_the_native_constant_input(coupled_fmu):
    """Steps of 0.25 s with a different input in each, against native runs piece by piece."""
    core = load_core(COUPLED)
    fmu = Instance(coupled_fmu, start_values=TIGHT)
    state = np.array(COUPLED.initial_state())
    for k in range(8):
        inputs = {"a_pivot_x": math.sin(k), "a_pivot_y": 0.5 * k, "a_pivot_z": -math.cos(k)}
        fmu.set(inputs)
        fmu.step(0.25)
        native = simulate(
            COUPLED,
            [0.0, 0.25],
            parameters=inputs,
            core=core,
            rtol=1e-12,
            atol=1e-12,
            state=dict(zip(COUPLED.state_names(), state)),
        )
        state = native.states[-1]
        assert np.abs(np.array(fmu.get(*COUPLED.state_names())) - state).max() < 1e-9
    fmu.close()
