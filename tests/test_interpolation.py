"""Coupling beyond first order (issue 29): the native FMUs' exact time derivatives of their
continuous outputs (fmi2GetRealOutputDerivatives, fmi3GetOutputDerivatives, orders 1 and 2)
and their interpolated inputs (fmi2SetRealInputDerivatives: over a step an input follows the
Taylor polynomial the master set).

- The output derivatives equal Richardson-extrapolated central differences in time of the
  outputs themselves, the inputs moving as their derivatives say, for the pendulum (expanded
  and recursive formulations, FMI 2.0 and 3.0) and the cart.
- A step whose inputs are a line or a parabola in time, given as derivatives, equals scipy's
  integration of the same model (the compiled core's right-hand side) with the same inputs as
  functions of time, to the solvers' tolerance; the cart's equals scipy's to rounding.
- Refusals name what they refuse; reset forgets the derivatives, FMU states keep them."""

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from scipy.integrate import solve_ivp

from conical_pendulum import Link, Scene
from conical_pendulum.builder.compiler import load_core
from fmu_helpers import INSTANCES

COUPLED = Scene.uniform(3, coupling=True)  # expanded, a_pivot inputs
RECURSIVE = Scene.uniform(7, coupling=True)  # chain.c
# joint damping, the air's drag and a force on a bob: more inputs (v_pivot, F_bob1_x/y/z, wind),
# the energy's books as states
FORCED = Scene(
    links=(Link(damping=0.3), Link(damping=0.2, bob_force=True)),
    joint_damping=True,
    air_drag=True,
    coupling=True,
)
INPUTS = ("a_pivot_x", "a_pivot_y", "a_pivot_z")
TIGHT = {"rtol": 1e-13, "atol": 1e-13}
U = (0.3, -0.2, 0.1)  # the inputs at the step's start, then their first and second derivatives
U1 = (0.7, 0.4, -0.5)
U2 = (1.5, -0.8, 0.6)
# The pythonfmu FMU's scalar outputs compared in FMI 3.0 (its arrays hold the rest)
FMI3_OUTPUTS = ("energy", "F_pivot_x", "F_pivot_y", "F_pivot_z", "F_free_x", "M_pivot_xx", "M_pivot_yz")


def continuous_outputs(inst):
    return [
        v.name
        for v in inst.md.modelVariables
        if v.causality == "output" and v.variability == "continuous" and v.type in ("Real", "Float64")
    ]


def set_input_derivatives(inst, names, first, second):
    vr = [inst.vr[n] for n in names]
    inst.fmu.setRealInputDerivatives(vr + vr, [1] * len(vr) + [2] * len(vr), [*first, *second])


def output_derivatives(inst, names, order):
    vr = [inst.vr[n] for n in names]
    if hasattr(inst.fmu, "getRealOutputDerivatives"):
        return np.array(inst.fmu.getRealOutputDerivatives(vr, [order] * len(vr)))
    return np.array(inst.fmu.getOutputDerivatives(vr, [order] * len(vr)))


def assert_derivatives_match_differences(inst, names, h, bound):
    """From the instance's state at its time t0, the outputs at t0 + k h (k = 0..4, each one
    step from t0) give (4 D(h) - D(2h)) / 3 of the first and second central differences at
    t0 + 2 h, where the FMU's derivatives are read: they agree within bound of each output's
    scale (the larger of its value's and its derivative's size, and 1)."""
    state = inst.get_state()
    values = {}
    for k in (0, 1, 3, 4, 2):  # the centre last: its derivatives are read there
        inst.set_state(state)
        inst.fmu.doStep(inst.time, k * h) if k else None
        values[k] = np.array(inst.get(*names))
    first, second = output_derivatives(inst, names, 1), output_derivatives(inst, names, 2)

    def d1(s):
        return (values[2 + s] - values[2 - s]) / (2 * s * h)

    def d2(s):
        return (values[2 + s] - 2 * values[2] + values[2 - s]) / (s * h) ** 2

    for exact, differences in ((first, (4 * d1(1) - d1(2)) / 3), (second, (4 * d2(1) - d2(2)) / 3)):
        scale = np.maximum(np.maximum(np.abs(exact), np.abs(values[2])), 1.0)
        worst = np.abs(exact - differences) / scale
        assert worst.max() < bound, names[int(worst.argmax())]
    inst.free_state(state)


@pytest.mark.parametrize(
    ("scene", "fmi_version"),
    [(COUPLED, 2), (RECURSIVE, 2), (COUPLED, 3), (FORCED, 2)],
    ids=["fmi2", "recursive", "fmi3", "forced"],
)
def test_pendulum_output_derivatives_equal_richardson_differences_in_time(built_fmu, scene, fmi_version):
    inst = INSTANCES[fmi_version](
        built_fmu(scene, backend="native", fmi_version=fmi_version), start_values=TIGHT
    )
    inst.step(0.3)  # a moving point, not the start
    names = continuous_outputs(inst) if fmi_version == 2 else list(FMI3_OUTPUTS)
    if fmi_version == 2:  # the inputs move (every one of them): their derivatives enter the outputs'
        inputs, times = scene.input_names(), len(scene.input_names()) // len(INPUTS)
        inst.fmu.setReal([inst.vr[n] for n in inputs], list(U) * times)
        set_input_derivatives(inst, inputs, U1 * times, U2 * times)
    assert_derivatives_match_differences(inst, names, h=5e-3, bound=1e-7)
    inst.close()


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_cart_output_derivatives_equal_richardson_differences_in_time(built_cart, fmi_version):
    inst = INSTANCES[fmi_version](
        built_cart(fmi_version), start_values={"m_cart": 2.0, "M_x": 0.5, "F_x": 3.0}
    )
    if fmi_version == 2:
        set_input_derivatives(inst, ("F_x", "M_x"), (40.0, 0.8), (-30.0, -1.0))
    assert_derivatives_match_differences(inst, ["x", "v", "a"], h=1e-3, bound=1e-7)
    inst.close()


def reference_step(scene, start, parameters, dt, inputs_at):
    """The state after dt from start, scipy's DOP853 on the compiled core's right-hand side with
    the inputs (which end p) as functions of time."""
    core = load_core(scene)

    def rhs(t, x):
        return core.rhs(x, np.concatenate([parameters, inputs_at(t)]))

    return solve_ivp(rhs, (0.0, dt), start, method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]


@pytest.mark.parametrize("solver", [0, 1, 2], ids=["rk4", "rk45", "dop853"])
@pytest.mark.parametrize("order", [1, 2])
def test_a_step_with_moving_inputs_is_the_integration_of_those_inputs(built_fmu, solver, order):
    """a_pivot a line (order 1) or a parabola (2) in time, given as derivatives: one step of 0.2 s
    equals the integration of a_pivot(t) (the held step would be off by some 1e-3), the state to
    the solver's tolerance; the outputs at the end are the model's with the inputs there."""
    inst = INSTANCES[2](
        built_fmu(COUPLED, backend="native"),
        start_values={**TIGHT, "solver": solver, "max_step": 1e-3 if solver == 0 else 0.0},
    )
    states = list(COUPLED.state_names())
    parameters = np.array(inst.get(*COUPLED.parameter_names()))
    inst.fmu.setReal([inst.vr[n] for n in INPUTS], list(U))
    set_input_derivatives(inst, INPUTS, U1, U2 if order == 2 else (0.0, 0.0, 0.0))
    start = np.array(inst.get(*states))
    dt = 0.2
    inst.step(dt)

    def inputs_at(t):
        return np.array(U) + np.array(U1) * t + (np.array(U2) * t * t / 2 if order == 2 else 0.0)

    expected = reference_step(COUPLED, start, parameters, dt, inputs_at)
    bound = 1e-9 if solver == 0 else 1e-11  # RK4 at 1e-3: its own error
    np.testing.assert_allclose(inst.get(*states), expected, rtol=0, atol=bound)
    # the inputs stepped along their polynomials, and the outputs are the model's there
    np.testing.assert_allclose(inst.get(*INPUTS), inputs_at(dt), rtol=1e-15, atol=0)
    held = reference_step(COUPLED, start, parameters, dt, lambda t: np.array(U))
    assert np.abs(held - expected).max() > 1e-4  # what holding the inputs would have cost
    inst.close()


def test_the_cart_steps_exactly_with_moving_force_and_mass(built_cart):
    inst = INSTANCES[2](built_cart(2), start_values={"m_cart": 2.0, "M_x": 0.5, "F_x": 3.0})
    force, mass = (3.0, 40.0, -30.0), (0.5, 0.8, -1.0)
    set_input_derivatives(inst, ("F_x", "M_x"), (force[1], mass[1]), (force[2], mass[2]))
    x0, v0, k, c, m = inst.get("x", "v", "k_cart", "c_cart", "m_cart")

    def rhs(t, z):
        F = force[0] + force[1] * t + force[2] * t * t / 2
        P = m + mass[0] + mass[1] * t + mass[2] * t * t / 2
        return [z[1], (F - k * z[0] - c * z[1]) / P]

    state = inst.get_state()
    for dt in (0.1, 1.0):
        inst.set_state(state)
        inst.fmu.doStep(0.0, dt)
        expected = solve_ivp(rhs, (0, dt), [x0, v0], method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
        np.testing.assert_allclose(inst.get("x", "v"), expected, rtol=0, atol=1e-12)
    inst.close()


def refused(inst, call):
    with pytest.raises(FMICallException):
        call()
    return inst.messages[-1][1]


def test_refusals_name_the_variable_the_order_and_the_value(built_fmu):
    inst = INSTANCES[2](built_fmu(COUPLED, backend="native"))
    vr = inst.vr
    cases = [
        (
            lambda: inst.fmu.setRealInputDerivatives([vr["F_pivot_x"]], [1], [1.0]),
            "F_pivot_x) is not a continuous input",
        ),
        (
            lambda: inst.fmu.setRealInputDerivatives([vr["a_pivot_x"]], [3], [1.0]),
            "order 3 of the derivative of a_pivot_x: must be 1 to 2",
        ),
        (
            lambda: inst.fmu.setRealInputDerivatives([vr["a_pivot_x"]], [0], [1.0]),
            "order 0 of the derivative of a_pivot_x",
        ),
        (
            lambda: inst.fmu.setRealInputDerivatives([vr["a_pivot_y"]], [1], [float("nan")]),
            "derivative 1 of a_pivot_y = nan: must be finite",
        ),
        (
            lambda: inst.fmu.getRealOutputDerivatives([vr["a_pivot_x"]], [1]),
            "a_pivot_x) is not a continuous output",
        ),
        (lambda: inst.fmu.getRealOutputDerivatives([vr["n_rhs"]], [1]), "n_rhs) is not a continuous output"),
        (
            lambda: inst.fmu.getRealOutputDerivatives([vr["F_pivot_x"]], [3]),
            "order 3 of the derivative of F_pivot_x",
        ),
    ]
    for call, words in cases:
        assert words in refused(inst, call)
    # nothing of a refused call was taken: a valid one before the bad value stays unset
    before = inst.get("F_pivot_x")
    refused(
        inst,
        lambda: inst.fmu.setRealInputDerivatives(
            [vr["a_pivot_x"], vr["a_pivot_y"]], [1, 1], [5.0, float("inf")]
        ),
    )
    assert output_derivatives(inst, ["alpha0"], 2) == output_derivatives(inst, ["alpha0"], 2)
    inst.step(0.1)
    assert inst.get("a_pivot_x") == [0.0]  # held: the 5.0 was not taken
    assert inst.get("F_pivot_x") != before
    inst.close()


def test_fmi3_refuses_output_derivatives_of_what_has_none(built_fmu):
    inst = INSTANCES[3](built_fmu(COUPLED, backend="native", fmi_version=3))
    words = refused(inst, lambda: inst.fmu.getOutputDerivatives([inst.vr["a_pivot_x"]], [1]))
    assert "fmi3GetOutputDerivatives" in words and "is not a continuous output" in words
    words = refused(inst, lambda: inst.fmu.getOutputDerivatives([inst.vr["energy"]], [3]))
    assert "order 3 of the derivative of energy: must be 1 to 2" in words
    inst.close()


def test_fmu_states_keep_the_derivatives_and_reset_forgets_them(built_fmu):
    inst = INSTANCES[2](built_fmu(COUPLED, backend="native"), start_values=TIGHT)
    states = ["alpha0", "omega2", "F_pivot_x"]
    inst.fmu.setReal([inst.vr[n] for n in INPUTS], list(U))
    set_input_derivatives(inst, INPUTS, U1, U2)
    saved = inst.get_state()
    serialized = inst.serialize(saved)
    inst.step(0.2)
    moved = inst.get(*states)
    set_input_derivatives(inst, INPUTS, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    for state in (saved, inst.deserialize(serialized)):
        inst.set_state(state)
        inst.time = 0.0
        inst.step(0.2)
        assert inst.get(*states) == moved
    inst.fmu.reset()
    inst.initialize()
    inst.fmu.setReal([inst.vr[n] for n in INPUTS], list(U))
    inst.time = 0.0
    inst.step(0.2)
    assert inst.get("a_pivot_x") == [U[0]]  # held again
    assert inst.get(*states) != moved
    inst.close()


@pytest.mark.parametrize("scene", [COUPLED, RECURSIVE], ids=["expanded", "recursive"])
def test_energy_conserved_has_derivatives_zero_to_rounding(built_fmu, scene):
    """With the support at rest the energy is conserved: its first and second time derivatives,
    sums of terms of the energy's size times the rates squared, vanish to rounding (1e-14 of
    the energy), which no difference in time resolves: exact, not approximate."""
    inst = INSTANCES[2](built_fmu(scene, backend="native"))
    inst.step(0.7)
    (energy,) = inst.get("energy")
    for order in (1, 2):
        assert abs(output_derivatives(inst, ["energy"], order)[0]) < 1e-14 * abs(energy)
    inst.close()
