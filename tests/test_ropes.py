"""Ropes (Link.rope): a massless link whose length l<i> is a state driven by its winch, the
input v_hoist<i>, with its tension T_rope<i>, its winch's power P_hoist<i> and the book
W_hoist; a length leaving its range or a negative tension discards the step. Checked against
what nobody here wrote: the lengthening pendulum's closed form in Bessel functions (LeCornu
1895; Boas, "The lengthening pendulum"), sympy's own KanesMethod with the rope's length a
function of time, and the energy less the books."""

from pathlib import Path

import numpy as np
import pytest
import sympy as sm
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu
from scipy.integrate import solve_ivp
from scipy.special import jv, yv

from conical_pendulum import Link, Scene, SceneError
from conical_pendulum.analysis.compare import compare
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.analysis.simulate import simulate
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.builder.core import dependencies
from conical_pendulum.builder.core.codegen import generate
from conical_pendulum.builder.core.equations import derive
from conical_pendulum.builder.core.kane import kanes_method
from conical_pendulum.scene import load_scene, scene_from_dict
from fmu_helpers import INSTANCES, Instance, Instance3, assert_model_exchange_follows
from formulations import assert_formulations_agree
from test_directional import Model
from test_interpolation import assert_derivatives_match_differences, continuous_outputs

G = 9.8
WARNING = 1  # fmi2Warning, fmi3Warning


def rope(length=10.0, low=1.0, high=30.0, **fields):
    """A rope with a bob of 5 kg (the default Link's) at its end."""
    return Link(has_mass=False, rope=True, rope_min=low, rope_max=high, length=length, **fields)


# one rope and its load: the lengthening pendulum
LOAD = Scene(links=(rope(),), outputs=("bobs", "energy"))
# a rope, a hook and a load slung below it on a massless sling, with every force a scene may add,
# on a moving support
SLUNG = Scene(
    links=(
        rope(damping=1.0, bob_force=True, bob_mass=20.0),
        Link(has_mass=False, length=3.0, bob_mass=200.0, damping=2.0),
        Link(length=1.0, mass=30.0, has_bob=False),
    ),
    joint_damping=True,
    air_drag=True,
    coupling=True,
)


def lengthening(l0, v, theta0, theta_dot0, times):
    """The small swing of a point mass on a rope of length l = l0 + v t (v != 0), from
    theta'' + 2 (v / l) theta' + (g / l) theta = 0: theta = u^-1 [A J1(u) + B Y1(u)] with
    u = (2 / |v|) sqrt(g l), which is the same for lengthening and shortening (in terms of
    l the equation has v only squared); d(u^-1 Z1(u))/du = -u^-1 Z2(u) and du/dt =
    sign(v) sqrt(g / l)."""
    length = l0 + v * times
    u = 2.0 / abs(v) * np.sqrt(G * length)
    u0, rate0 = u[0], np.sign(v) * np.sqrt(G / l0)
    system = np.array([[jv(1, u0) / u0, yv(1, u0) / u0], [-rate0 * jv(2, u0) / u0, -rate0 * yv(2, u0) / u0]])
    a, b = np.linalg.solve(system, [theta0, theta_dot0])
    return (a * jv(1, u) + b * yv(1, u)) / u


@pytest.mark.parametrize("l0, v", [(5.0, 0.2), (9.0, -0.2)], ids=["lengthening", "shortening"])
def test_a_small_swing_follows_the_lengthening_pendulums_bessel_functions(l0, v):
    """Over 20 s at 60 Hz, in the plane of beta (alpha = 0): 1e-3 rad, where the equation's
    linearization (sin theta = theta) errs by some 1e-10 rad over this time."""
    times = np.arange(1201) / 60.0
    theta0, theta_dot0 = 1e-3, 2e-4
    run = simulate(
        LOAD,
        times,
        parameters={"v_hoist0": v, "g": G},
        state={"alpha0": 0.0, "beta0": theta0, "omega0": 0.0, "delta0": theta_dot0, "l0": l0},
        rtol=1e-13,
        atol=1e-15,
    )
    closed = lengthening(l0, v, theta0, theta_dot0, times)
    np.testing.assert_allclose(run["l0"], l0 + v * times, rtol=0, atol=1e-12)
    assert np.abs(run["alpha0"]).max() == 0.0
    error = np.abs(run["beta0"] - closed).max()
    assert np.abs(closed).max() > 0.5 * theta0  # it swings
    assert error < 1e-8, error


def swing_amplitude(l0, v, seconds):
    """A small swing (1e-3 rad) while the rope goes from l0 at v: its amplitude
    sqrt(theta^2 + theta'^2 l / g) and what the adiabatic invariant predicts for it,
    a0 (l / l0)^(-3/4) (the action E / omega ~ l^(3/2) theta^2 kept)."""
    times = np.arange(int(seconds * 60) + 1) / 60.0
    run = simulate(
        LOAD,
        times,
        parameters={"v_hoist0": v, "g": G},
        state={"alpha0": 0.0, "beta0": 1e-3, "omega0": 0.0, "delta0": 0.0, "l0": l0},
        method="core",
        rtol=1e-10,
        atol=1e-14,
    )
    amplitude = np.sqrt(run["beta0"] ** 2 + run["delta0"] ** 2 * run["l0"] / G)
    return amplitude, amplitude[0] * (run["l0"] / l0) ** -0.75


@pytest.mark.parametrize("l0, direction", [(5.0, 1.0), (20.0, -1.0)], ids=["lengthening", "shortening"])
def test_slow_hoisting_keeps_the_swings_adiabatic_invariant(l0, direction):
    """The rope four times as long or a quarter as long, 15 m at 0.04 and at 0.02 m/s: the
    amplitude follows l^(-3/4) to 0.3 % and 0.15 %, the deviation halving with the speed (it is
    of the order of the speed over the swing's, v / (l omega))."""
    errors = []
    for speed in (0.04, 0.02):
        amplitude, predicted = swing_amplitude(l0, direction * speed, 15.0 / speed)
        assert amplitude[-1] / amplitude[0] == pytest.approx(4.0 ** (-0.75 * direction), rel=3e-3)
        errors.append(np.abs(amplitude / predicted - 1).max())
    assert errors[0] < 3e-3 and 0.4 < errors[1] / errors[0] < 0.6, errors


def sympy_functions(scene):
    """M and F from the fast derivation and from sympy's KanesMethod, as numpy functions of
    (x, p)."""
    eqs = derive(scene)
    mass, forcing, _ = eqs.lambdify()
    reference = kanes_method(scene)
    args = eqs.states + eqs.params
    kane_mass, kane_forcing = (sm.lambdify(args, matrix) for matrix in reference)
    return (
        (mass, forcing),
        (lambda x, p: kane_mass(*x, *p), lambda x, p: kane_forcing(*x, *p)),
    )


@pytest.mark.parametrize(
    "scene",
    [
        LOAD,
        Scene(links=(Link(length=2.0), rope(length=6.0)), coupling=True),  # a rope below a link
        Scene(links=SLUNG.links[:2], joint_damping=True, air_drag=True, coupling=True),
    ],
    ids=["load", "rope-below-a-link", "slung-forced-coupled"],
)
def test_it_is_sympys_kanes_method_with_the_ropes_length_a_function_of_time(scene):
    assert kane_difference(scene) < 1e-12


def kane_difference(scene, draws=20):
    """The largest difference of M and F from sympy's KanesMethod's, relative to their largest
    entry, at random states, lengths, hoist speeds and accelerations, inputs and parameters."""
    (mass, forcing), (kane_mass, kane_forcing) = sympy_functions(scene)
    rng = np.random.default_rng(41)
    worst = 0.0
    for _ in range(draws):
        x = rng.uniform(-1.5, 1.5, 4 * scene.n + len(scene.ropes()))  # as Equations.states
        x[4 * scene.n :] = rng.uniform(1.0, 20.0, len(scene.ropes()))
        # as Equations.params: the parameters, then the inputs and the lengths' accelerations
        p = rng.uniform(0.5, 4.0, len(scene.core_parameter_names()) + len(scene.ropes()))
        inputs = len(scene.parameter_names())
        p[inputs:] = rng.uniform(-3.0, 3.0, len(p) - inputs)
        for ours, theirs in ((mass, kane_mass), (forcing, kane_forcing)):
            a, b = np.asarray(ours(x, p), float), np.asarray(theirs(x, p), float)
            worst = max(worst, float(np.abs(a - b).max() / np.abs(a).max()))
    return worst


@pytest.mark.parametrize(
    "links, options",
    [
        ((rope(),), {}),
        (SLUNG.links, {"joint_damping": True, "air_drag": True, "coupling": True}),
        ((Link(length=2.0), rope(length=6.0, bob_force=True), Link(has_mass=False)), {"coupling": True}),
        ((rope(), Link(has_mass=False, length=3.0), rope(length=4.0)), {"air_drag": True}),  # two ropes
    ],
    ids=["load", "slung", "below-a-link", "two-ropes"],
)
def test_the_formulations_agree(links, options):
    """M, F, x' (the lengths' and books' rates too) and every output (the tensions, the
    winches' power, the pivot force) at random states, lengths, inputs and the lengths'
    accelerations."""
    assert_formulations_agree(links, options, seed=5, input_range=5)


def test_the_recursive_dependencies_are_what_the_expressions_say():
    scene = Scene(links=SLUNG.links, joint_damping=True, air_drag=True, coupling=True)
    assert dependencies._chain(scene) == dependencies._symbolic(scene, derive(scene))


def test_energy_less_the_books_stays_constant_with_the_winch_working():
    """The slung load hoisted at 0.4 m/s on a support accelerating and in a wind, its hook
    pushed: W_hoist holds what the winch put in."""
    inputs = {"v_hoist0": -0.4, "a_pivot_x": 0.6, "v_pivot_x": 0.2, "wind_x": 3.0, "F_bob0_z": 40.0}
    run = simulate(
        SLUNG,
        np.linspace(0, 10, 201),
        parameters=inputs,
        state={"beta0": 0.2, "alpha1": 0.3, "omega2": 0.2},
        rtol=1e-12,
        atol=1e-12,
    )
    energy = run["energy"]
    kept = energy - sum(run[name] for name in SLUNG.work_names())
    assert "W_hoist" in SLUNG.work_names()
    assert run["W_hoist"][-1] > 0.9 * 250.0 * G * 4.0  # it lifted 250 kg by 4 m
    np.testing.assert_allclose(run["l0"][-1], 6.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(run["P_hoist0"], 0.4 * run["T_rope0"], rtol=1e-14)
    assert np.abs(kept - kept[0]).max() < 1e-9 * np.abs(energy).max()


def test_a_long_chain_on_a_rope_keeps_its_books_in_the_recursive_formulation():
    """A rope with eight links below it (recursive by 'auto'), hoisted on a moving support."""
    scene = Scene(links=(rope(length=6.0),) + (Link(length=2.0, mass=3.0, bob_mass=1.0),) * 8, coupling=True)
    assert scene.resolved_formulation() == "recursive"
    run = simulate(
        scene,
        np.linspace(0, 5, 101),
        parameters={"v_hoist0": -0.6, "a_pivot_x": 0.8},
        state={"beta0": 0.3, "alpha4": 0.2},
        rtol=1e-12,
        atol=1e-12,
    )
    kept = run["energy"] - run["W_hoist"] - run["W_pivot"]
    assert abs(run["W_hoist"][-1]) > 100.0 and abs(run["W_pivot"][-1]) > 100.0
    assert np.abs(kept - kept[0]).max() < 1e-9 * np.abs(run["energy"]).max()


def test_a_hanging_ropes_tension_is_the_weight_below_it_and_points_along_it():
    """At rest: the weight of everything below. Swinging, the force what hangs below asks of
    the rope, sum m (a - g) less the forces on it, lies along the rope: a massless rope with a
    joint at each end transmits no other force (its tension is that force's length)."""
    core = load_core(SLUNG)
    names = SLUNG.state_names()
    x = np.zeros(len(names))
    x[names.index("l0")] = 8.0
    p = np.array(SLUNG.parameters())
    outputs = dict(zip(SLUNG.output_names(), core.outputs(x, p)))
    assert outputs["T_rope0"] == pytest.approx((20.0 + 200.0 + 30.0) * G, rel=1e-14)
    assert outputs["P_hoist0"] == 0.0


def test_the_rope_outputs_follow_newtons_law_along_the_rope():
    """A single load: T = m (g . e_y + a . e_y) with the bob's acceleration from second
    differences of its position, while it swings and is hoisted."""
    times = np.linspace(0, 4, 4001)
    run = simulate(
        LOAD,
        times,
        parameters={"v_hoist0": -0.8},
        state={"beta0": 0.4, "alpha0": 0.2, "omega0": 0.3},
        rtol=1e-12,
        atol=1e-12,
    )
    h = times[1] - times[0]
    position = np.stack([run[f"bob0_{c}"] for c in "xyz"], axis=1)
    acceleration = (position[2:] - 2 * position[1:-1] + position[:-2]) / h**2
    along = -position[1:-1] / np.linalg.norm(position[1:-1], axis=1)[:, None]  # bob to pivot
    expected = 5.0 * np.einsum("ij,ij->i", acceleration + [0.0, G, 0.0], along)
    tension = run["T_rope0"][1:-1]
    assert np.abs(tension - expected).max() < 1e-5 * np.abs(tension).max()


def core_step(scene, start, inputs, dt, steps):
    """Steps of the core's co-simulation (cosim.c, as both FMUs take it): the statuses and the
    states after each."""
    core = load_core(scene)
    p = np.array(scene.parameters(inputs))
    values = np.zeros(core.NSTATE + core.NOUTPUT)
    values[: core.NSTATE] = scene.initial_state(start)
    stepper = core.Stepper(p, values)
    stepper.update_outputs()
    found = []
    for k in range(steps):
        status = stepper.step(2, k * dt, dt, 1e-10, 1e-10, 0.0, 100000)
        found.append((status, values[: core.NSTATE].copy()))
        if status:
            break
    return core, found


def test_a_length_leaving_its_range_discards_the_step_and_keeps_the_state():
    """Hoisted from 1.3 m at 0.25 m/s towards its minimum of 1 m: 1.175 m at 0.5 s, 1.05 m at
    1 s, then 0.925 m, which the step from 1 s does not reach."""
    core, found = core_step(LOAD, {"l0": 1.3}, {"v_hoist0": -0.25}, 0.5, 10)
    statuses = [status for status, _ in found]
    assert statuses[:2] == [0, 0] and core.STATUS[statuses[2]] == "a rope's length left its range"
    assert len(found) == 3
    assert found[2][1][LOAD.state_names().index("l0")] == pytest.approx(1.05, abs=1e-12)  # kept at t


def test_a_load_thrown_upward_slackens_the_rope_and_the_step_is_discarded():
    """A kick upward (F_bob0_y, twice the load's weight) would need the rope to push the load
    down: the step is discarded, the state kept; hanging still before it, the rope is taut."""
    scene = Scene(links=(rope(bob_force=True),), outputs=())
    core = load_core(scene)
    p = np.array(scene.parameters())
    values = np.zeros(core.NSTATE + core.NOUTPUT)
    values[: core.NSTATE] = scene.initial_state({"beta0": 0.3, "alpha0": 0.0})
    stepper = core.Stepper(p, values)
    stepper.update_outputs()
    tension = scene.output_names().index("T_rope0")
    assert [stepper.step(2, k * 0.1, 0.1, 1e-10, 1e-10, 0.0, 100000) for k in range(3)] == [0, 0, 0]
    assert values[core.NSTATE + tension] > 0
    before = values.copy()
    p[scene.core_parameter_names().index("F_bob0_y")] = 2 * 5.0 * G
    status = stepper.step(2, 0.3, 0.1, 1e-10, 1e-10, 0.0, 100000)
    assert core.STATUS[status] == "a rope went slack"
    np.testing.assert_array_equal(values, before)


@pytest.mark.parametrize(
    "fields, message",
    [
        ({"mass": 10.0}, r"link\[0\]\.rope: a rope is a massless link; give link 0 mass = 0"),
        (
            {"rope": {"min": 12.0, "max": 30.0}},
            r"link\[0\]\.rope: link 0's length 10\.0 m is outside its range",
        ),
        (
            {"rope": {"min": -1.0, "max": 30.0}},
            r"link\[0\]\.rope\.min: must be a positive finite number, got -1\.0",
        ),
        ({"rope": {"max": 30.0}}, r"link\[0\]\.rope\.min: must be a positive finite number, got None"),
        ({"rope": {"min": 1.0, "max": 30.0, "speed": 2}}, r"link\[0\]\.rope: unknown field\(s\) \['speed'\]"),
        ({"rope": True}, r"link\[0\]\.rope: expected a table \{ min = \.\.\., max = \.\.\. \}, got True"),
    ],
)
def test_a_bad_rope_is_refused_naming_it(fields, message):
    link = {"length": 10.0, "mass": 0, "bob": {"mass": 5.0}, "rope": {"min": 1.0, "max": 30.0}, **fields}
    with pytest.raises(SceneError, match=message):
        scene_from_dict({"link": [link]})


def test_ropes_are_refused_where_their_lengths_are_not_derived():
    with pytest.raises(SceneError, match=r"link\[0\]\.rope: ropes need kinematics 'consistent'"):
        Scene(links=(rope(),), kinematics="pydy-example")


def test_a_rope_makes_its_length_a_state_and_adds_its_winch():
    assert LOAD.parameter_names() == ["m0", "g"]
    assert LOAD.input_names() == ["v_hoist0"]
    assert LOAD.state_names() == ["alpha0", "beta0", "omega0", "delta0", "W_hoist", "l0"]
    assert LOAD.output_names()[-2:] == ["T_rope0", "P_hoist0"]
    assert LOAD.initial_state()[-1] == 10.0
    header = generate(derive(LOAD))["model.h"]
    assert "static const double cp_rope_min[CP_NROPE] = {1.0};" in header


# the FMUs' scene: a rope with a hook, a load slung below it on a massless sling, on a moving
# support
HOISTED = Scene(
    links=(
        rope(length=10.0, low=2.0, high=30.0, bob_mass=50.0),
        Link(has_mass=False, length=3.0, bob_mass=500.0),
    ),
    coupling=True,
)
HOISTING = {"v_hoist0": -0.5, "beta0": 0.2, "alpha1": 0.3, "a_pivot_x": 0.5}


@pytest.fixture(scope="module")
def hoisted_fmu(built_fmu):
    return lambda backend, fmi_version=2: built_fmu(HOISTED, backend=backend, fmi_version=fmi_version)


@pytest.mark.parametrize("backend, fmi_version", [("pythonfmu", 2), ("native", 2), ("native", 3)])
def test_its_fmus_follow_the_reference_and_keep_the_books(hoisted_fmu, backend, fmi_version):
    """Hoisted by 5 m in 10 s while the support accelerates: the FMU against the native
    reference, and energy less W_hoist and W_pivot constant."""
    comparison = compare(hoisted_fmu(backend, fmi_version), HOISTED, start_values=HOISTING, stop_time=10.0)
    assert comparison.passed(), comparison.report()
    result = comparison.result
    np.testing.assert_allclose(result["l0"][-1], 5.0, rtol=0, atol=1e-12)
    kept = result["energy"] - result["W_hoist"] - result["W_pivot"]
    assert result["W_hoist"][-1] > 550.0 * G * 5.0 * 0.9
    assert np.abs(kept - kept[0]).max() < 1e-8 * np.abs(result["energy"]).max()


def test_model_exchange_follows_the_reference(hoisted_fmu):
    assert_model_exchange_follows(hoisted_fmu("native"), HOISTED, HOISTING, 10.0)


@pytest.mark.parametrize(
    "backend, fmi_version, solver",
    [("pythonfmu", 2, 2), ("pythonfmu", 2, 3), ("native", 2, 2), ("native", 3, 2)],
    ids=["pythonfmu", "pythonfmu-radau", "native-2", "native-3"],
)
def test_a_rope_hoisted_past_its_minimum_discards_the_step_naming_it(
    hoisted_fmu, backend, fmi_version, solver
):
    """From 3.1 m at 0.5 m/s towards its minimum of 2 m: the step from 2 s (2.1 m) to 2.5 s is
    discarded, the message naming the rope, the time and the length (DOP853, and the
    pythonfmu FMU's Radau, which scipy integrates)."""
    fmu = INSTANCES[fmi_version](
        hoisted_fmu(backend, fmi_version), start_values={"l0": 3.1, "v_hoist0": -0.5, "solver": solver}
    )
    for _ in range(4):
        fmu.step(0.5)
    assert fmu.get("l0") == [pytest.approx(2.1, abs=1e-12)]
    with pytest.raises(FMICallException):
        fmu.step(0.5)
    message = (
        "at t = 2.5 s rope l0's length is 1.85 m, outside its range [2, 30] m (the scene's rope min and "
        "max): its winch (v_hoist0) must stop or turn before"
    )
    assert message in fmu.texts(), fmu.messages
    assert fmu.get("l0") == [pytest.approx(2.1, abs=1e-12)]  # kept at 2 s
    fmu.close()


# the winch's speed and the support's acceleration at the step's start, then their first and
# second derivatives (fmi2SetRealInputDerivatives)
WINCH_INPUTS = ("v_hoist0", "a_pivot_x")
WINCH = ((-0.5, 0.3), (0.4, -0.2), (-0.6, 0.5))


def winch_inputs_at(t, order):
    """The inputs t after the step's start, on the polynomials the master set."""
    u, u1, u2 = (np.array(v) for v in WINCH)
    return u + u1 * t + (u2 * t * t / 2 if order == 2 else 0.0)


def winch_acceleration_at(t, order):
    """v_hoist0's rate there: the rope's l''."""
    return np.array([WINCH[1][0] + (WINCH[2][0] * t if order == 2 else 0.0)])


def winch_reference(start, parameters, dt, order, accelerating=True):
    """The state after dt from start: scipy's DOP853 on the compiled core's right-hand side, the
    inputs functions of time and the rope's l'' their rate (accelerating=False: 0, as an FMU
    that held the winch's acceleration would take it)."""
    core = load_core(HOISTED)
    inputs = {name: k for k, name in enumerate(WINCH_INPUTS)}

    def p_at(t):
        p = np.concatenate([parameters, np.zeros(len(HOISTED.input_names()))])
        values = winch_inputs_at(t, order)
        for name, k in inputs.items():
            p[HOISTED.core_parameter_names().index(name)] = values[k]
        return p

    def rhs(t, x):
        return core.rhs(x, p_at(t), winch_acceleration_at(t, order) if accelerating else None)

    end = solve_ivp(rhs, (0.0, dt), start, method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
    return core, end, p_at(dt)


def winch_instance(hoisted_fmu, order):
    """The native FMI 2.0 FMU at a swinging state, its winch's speed and the support's
    acceleration set with their derivatives to order."""
    inst = Instance(
        hoisted_fmu("native"), start_values={"rtol": 1e-13, "atol": 1e-13, "beta0": 0.2, "alpha1": 0.3}
    )
    inst.fmu.setReal([inst.vr[n] for n in WINCH_INPUTS], list(WINCH[0]))
    vr = [inst.vr[n] for n in WINCH_INPUTS]
    second = WINCH[2] if order == 2 else (0.0, 0.0)
    inst.fmu.setRealInputDerivatives(vr + vr, [1, 1, 2, 2], [*WINCH[1], *second])
    return inst


@pytest.mark.parametrize("order", [1, 2])
def test_a_winch_speed_given_with_its_derivatives_accelerates_the_rope(hoisted_fmu, order):
    """v_hoist0 a line (order 1) or a parabola (2) in time, as derivatives, with the support's
    acceleration: one step of 1 s equals scipy's integration with those inputs and the rope's l''
    their rate, the length l0 + v t + v' t^2 / 2 + v'' t^3 / 6 exactly; the tension at the end
    is the model's with l'' there (leaving l'' out would be off by the load's mass times it)."""
    inst = winch_instance(hoisted_fmu, order)
    states = list(HOISTED.state_names())
    parameters = np.array(inst.get(*HOISTED.parameter_names()))
    start = np.array(inst.get(*states))
    dt = 1.0
    inst.step(dt)
    core, expected, p_end = winch_reference(start, parameters, dt, order)
    scale = np.maximum(np.abs(expected), 1.0)  # the books in J: relative to their size
    np.testing.assert_array_less(np.abs(np.array(inst.get(*states)) - expected) / scale, 1e-11)
    v, v1, v2 = (WINCH[k][0] for k in range(3))
    length = start[states.index("l0")] + v * dt + v1 * dt**2 / 2 + (v2 * dt**3 / 6 if order == 2 else 0.0)
    assert inst.get("l0")[0] == pytest.approx(length, rel=0, abs=1e-12)
    outputs = HOISTED.output_names()
    x_end = np.array(inst.get(*states))
    with_acceleration = core.outputs(x_end, p_end, winch_acceleration_at(dt, order))
    np.testing.assert_allclose(inst.get(*outputs), with_acceleration, rtol=1e-12, atol=1e-9)
    # l'' left out: off by the apparent mass along the rope times l'', between the hook's 50 kg
    # and 550 kg with the load (its sling swings: the load's share is 500 kg cos^2 of the angle)
    held = core.outputs(x_end, p_end)[outputs.index("T_rope0")]
    acceleration = abs(winch_acceleration_at(dt, order)[0])
    assert 50.0 * acceleration < abs(held - inst.get("T_rope0")[0]) < 550.0 * acceleration
    _, held_end, _ = winch_reference(start, parameters, dt, order, accelerating=False)
    assert np.abs(held_end - expected).max() > 1e-4  # what leaving l'' out would have cost
    inst.close()


def accelerating_winch_books(path):
    """Three steps of 1 s along v_hoist0's parabola (the FMU steps its inputs along it, the rope
    from 10 m to 7.6 m): the spread of energy less the books over the four points, relative to
    the energy at the end, then the rope's length and W_hoist there."""
    inst = winch_instance(lambda backend: path, 2)
    kept = []
    for step in range(4):
        if step:
            inst.step(1.0)
        energy, hoist, pivot = inst.get("energy", "W_hoist", "W_pivot")
        kept.append(energy - hoist - pivot)
    length = inst.get("l0")[0]
    inst.close()
    return float(np.ptp(kept) / abs(energy)), length, hoist


def test_energy_less_the_books_stays_constant_while_the_winch_accelerates(hoisted_fmu):
    """W_hoist holds the winch's work, the acceleration's included."""
    drift, length, hoist = accelerating_winch_books(hoisted_fmu("native"))
    assert length == pytest.approx(7.6, abs=1e-12)
    assert abs(hoist) > 1000.0
    assert drift < 1e-9


@pytest.mark.parametrize("order", [1, 2])
def test_the_output_derivatives_see_the_winchs_acceleration(hoisted_fmu, order):
    """fmi2GetRealOutputDerivatives of the tension, the winch's power and every other continuous
    output, with v_hoist0 moving: Richardson differences in time of the outputs (over 0.4 ms:
    the light hook between its rope and the heavy load swings fast, its force's second derivative
    some 5e5 N/s^2, and the differences' error is of order h^4)."""
    inst = winch_instance(hoisted_fmu, order)
    inst.step(0.3)
    assert_derivatives_match_differences(inst, continuous_outputs(inst), h=4e-4, bound=1e-7)
    inst.close()


def test_model_exchange_discards_the_derivatives_of_a_rope_out_of_its_range(hoisted_fmu):
    """A host integrating past a rope's minimum gets fmi2Discard from fmi2GetDerivatives, the
    message naming the rope, the time and the length; back in range, derivatives again."""
    model = Model(hoisted_fmu("native"), HOISTED)
    names = HOISTED.state_names()
    x = np.array(HOISTED.initial_state({"l0": 1.5}))
    model.set(x, [0.0] * len(HOISTED.input_names()))
    with pytest.raises(FMICallException):
        model.values()
    message = "derivatives at t = 0 s: a rope's length left its range: at t = 0 s rope l0's length is 1.5 m"
    assert any(message in text for _, text in model.messages), model.messages
    x[names.index("l0")] = 2.5
    model.set(x)
    assert np.all(np.isfinite(model.values()))
    model.close()


CRANE = load_scene(Path(__file__).resolve().parents[1] / "scenes" / "crane.toml")
CRANE_START = {"rtol": 1e-10, "atol": 1e-10, "alpha0": 0.0, "alpha1": 0.0, "beta0": 0.0, "beta1": 0.0}


def crane_inputs():
    """fmpy's input table of a short crane run: the trolley accelerates at 0.4 m/s2 until
    2.5 s; the winch hoists at 0.5 m/s from 1 s to 5 s (two rows at each edge: the value before
    it, then after it)."""
    rows = [(0.0, 0.4, 0.0), (1.0, 0.4, 0.0), (1.0, 0.4, -0.5), (2.5, 0.4, -0.5), (2.5, 0.0, -0.5)]
    rows += [(5.0, 0.0, -0.5), (5.0, 0.0, 0.0), (8.0, 0.0, 0.0)]
    return np.array(rows, dtype=[("time", float), ("a_pivot_x", float), ("v_hoist0", float)])


def books_drift(run):
    """The largest change of energy less the books over the run, relative to the energy: some
    8e-4 where the books miss the winch's start (270 J of the crane's 3.3e5 J)."""
    kept = run["energy"] - run["W_hoist"] - run["W_pivot"]
    assert run["W_hoist"][-1] > 2150 * G * 2.0 * 0.9  # 2 m lifted
    return np.abs(kept - kept[0]).max() / np.abs(run["energy"]).max()


@pytest.mark.parametrize("backend, fmi_version", [("pythonfmu", 2), ("native", 2), ("native", 3)])
def test_the_winchs_starts_and_stops_are_booked_in_w_hoist(built_fmu, backend, fmi_version):
    """A new v_hoist at a communication point jumps the speed of everything below the rope
    along it (some 270 J of the crane's 2150 kg at 0.5 m/s): W_hoist takes the jump where the
    input is set, so energy less the books stays constant across the winch's start and stop."""
    fmu = built_fmu(CRANE, backend=backend, fmi_version=fmi_version)
    run = run_fmu(fmu, 8.0, 0.02, CRANE_START | {"solver": 2}, input=crane_inputs())
    assert books_drift(run) < 1e-11


# the crane's hook and load, and the winch's acceleration over its ramp from rest
CRANE_MASS, RAMP = 2150.0, 0.5


def winch_ramp(path):
    """The crane's native FMI 2.0 FMU, hook and load hanging straight at rest, the winch ramped
    from 0 to RAMP m/s in 1 s by v_hoist0's derivative set once, then held at that speed: the
    rope's tension at the ten points of the ramp and at 0.1 s after it, and (v_hoist0, l0,
    W_hoist) at the ramp's end."""
    fmu = Instance(path, start_values=CRANE_START)
    vr = fmu.vr["v_hoist0"]
    fmu.fmu.setRealInputDerivatives([vr], [1], [-RAMP])
    ramp = []
    for _ in range(10):
        fmu.step(0.1)
        ramp.append(fmu.get("T_rope0")[0])
    end = fmu.get("v_hoist0", "l0", "W_hoist")
    fmu.fmu.setRealInputDerivatives([vr], [1], [0.0])  # the ramp's end: at constant speed
    fmu.step(0.1)
    after = fmu.get("T_rope0")[0]
    fmu.close()
    return np.array(ramp), after, end


def test_a_winch_ramping_up_lifts_the_crane_load_with_its_weight_and_mass_times_acceleration(built_fmu):
    """Over the ramp the tension is (m_hook + m_load)(g + a), a the winch's acceleration upward,
    and W_hoist its integral times the speed, with no impulse booked (the speed is continuous);
    at constant speed after it, the weight alone."""
    ramp, after, end = winch_ramp(built_fmu(CRANE, backend="native"))
    np.testing.assert_allclose(ramp, CRANE_MASS * (G + RAMP), rtol=1e-12)
    work = CRANE_MASS * (G + RAMP) * RAMP / 2
    assert end == pytest.approx([-RAMP, 12.0 - RAMP / 2, work], rel=1e-12)
    assert after == pytest.approx(CRANE_MASS * G, rel=1e-12)


# a rope with six links below it: the recursive formulation (chain.c's cp_energy)
LONG_HOISTED = Scene(
    links=(rope(length=6.0),) + (Link(length=2.0, mass=3.0, bob_mass=1.0),) * 6, coupling=True
)


@pytest.mark.parametrize("scene", [HOISTED, LONG_HOISTED], ids=["expanded", "recursive"])
def test_a_winch_set_at_a_point_jumps_w_hoist_by_the_energys_jump(built_fmu, scene):
    """At a communication point the state keeps its angles and rates; the winch's new speed
    changes the energy (the speed of everything below along the rope) and W_hoist by as much,
    in both formulations; the state is otherwise as it was."""
    assert LONG_HOISTED.resolved_formulation() == "recursive"
    fmu = Instance(built_fmu(scene, backend="native"), start_values={"beta0": 0.3, "omega1": 0.4})
    names = ["energy", *scene.state_names()]

    def values():
        found = dict(zip(names, fmu.get(*names)))
        return found, found["energy"] - sum(found[name] for name in scene.work_names())

    fmu.set({"v_hoist0": -0.3})
    fmu.step(0.5)
    before, kept = values()
    fmu.set({"v_hoist0": 0.4})
    after, kept_after = values()
    jump = after["energy"] - before["energy"]
    assert abs(jump) > 1.0
    assert after["W_hoist"] - before["W_hoist"] == pytest.approx(jump, rel=1e-12)
    assert kept_after == pytest.approx(kept, rel=1e-15)
    assert {n: v for n, v in after.items() if n not in ("energy", "W_hoist")} == {
        n: v for n, v in before.items() if n not in ("energy", "W_hoist")
    }
    fmu.step(0.5)  # the integration restarts from there
    assert values()[1] == pytest.approx(kept, rel=1e-9)
    fmu.close()


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_model_exchange_books_the_winchs_jumps_set_in_event_mode(built_fmu, fmi_version):
    """fmpy sets an input's step change in event mode: the book jumps, fmi2NewDiscreteStates
    (fmi3UpdateDiscreteStates) says valuesOfContinuousStatesChanged, the host reads the states
    again, and energy less the books stays constant to the integrator's tolerance."""
    fmu = built_fmu(CRANE, backend="native", fmi_version=fmi_version)
    run = run_fmu(
        fmu, 8.0, 0.02, CRANE_START, input=crane_inputs(), fmi_type="ModelExchange", relative_tolerance=1e-10
    )
    assert books_drift(run) < 1e-9


def test_a_winch_set_in_continuous_time_mode_jumps_no_state_and_is_warned_of(hoisted_fmu):
    """In continuous-time mode the host integrates the states, which cannot jump: a new v_hoist
    there is taken, W_hoist stays, and energy less the books jumps by the impulse's work (what
    docs/model.md says a host that wants it booked does: set v_hoist in event mode). A speed
    that varies between events is integrated without its rate, the rope's l'' (Model Exchange
    gives no input derivatives): fmi2SetReal says so once, with fmi2Warning, and takes it."""
    model = Model(hoisted_fmu("native"), HOISTED)
    x = np.array(HOISTED.initial_state({"beta0": 0.2, "omega1": 0.3}))
    inputs = np.zeros(len(HOISTED.input_names()))
    model.set(x, inputs)
    assert model.messages == []  # the same values: nothing changed
    before = model.fmu.getReal([model.vr["energy"]])[0]
    inputs[HOISTED.input_names().index("v_hoist0")] = -0.5
    model.set(x, inputs)
    assert model.fmu.getReal([model.vr["v_hoist0"], model.vr["W_hoist"]]) == [-0.5, 0.0]
    assert abs(model.fmu.getReal([model.vr["energy"]])[0] - before) > 10.0  # 550 kg, 0.5 m/s
    warning = (
        "fmi2SetReal: v_hoist0 = -0.5 (was 0) set in continuous-time mode: a winch's speed that "
        "varies between events is integrated with its rope's acceleration l'' taken as 0"
    )
    assert [status for status, _ in model.messages] == [WARNING]
    assert model.messages[0][1].startswith(warning), model.messages
    inputs[HOISTED.input_names().index("v_hoist0")] = -0.4
    model.set(x, inputs)  # said once
    assert len(model.messages) == 1
    model.close()


def test_fmi3_model_exchange_warns_once_of_a_winch_speed_set_in_continuous_time_mode(hoisted_fmu):
    """fmi3SetFloat64 as fmi2SetReal: fmi3Warning once, the value taken; at an event, none."""
    inst = Instance3(hoisted_fmu("native", 3), interface="ModelExchange")
    vr = inst.vr["v_hoist0"]
    inst.fmu.setFloat64([vr], [-0.2])  # in event mode, where initialization ends: no warning
    inst.fmu.enterContinuousTimeMode()
    assert inst.messages == []
    inst.fmu.setFloat64([vr], [-0.3])
    inst.fmu.setFloat64([vr], [-0.4])
    assert [status for status, _ in inst.messages] == [WARNING]
    assert inst.messages[0][1].startswith(
        "fmi3SetFloat64: v_hoist0 = -0.3 (was -0.2) set in continuous-time mode"
    )
    assert inst.get("v_hoist0") == [-0.4]
    inst.close()


@pytest.mark.parametrize("backend, fmi_version", [("pythonfmu", 2), ("native", 2), ("native", 3)])
def test_the_winchs_power_is_declared_in_watts(built_fmu, backend, fmi_version):
    """P_hoist in W (kg m2 s-3), a unit of its own beside the books' rates' J/s; fmpy validates
    the model description's units."""
    path = built_fmu(CRANE, backend=backend, fmi_version=fmi_version)
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    power = next(v for v in md.modelVariables if v.name == "P_hoist0")
    watt = next(u for u in md.unitDefinitions if u.name == "W")
    assert (power.unit, power.quantity) == ("W", "Power")
    assert (watt.baseUnit.kg, watt.baseUnit.m, watt.baseUnit.s) == (1, 2, -3)


def test_the_crane_scene_is_a_rope_a_hook_and_a_load_slung_below_on_a_moving_support():
    """scenes/crane.toml, which benchmarks/crane_run.py runs in both FMUs (docs/model.md)."""
    scene = load_scene(Path(__file__).resolve().parents[1] / "scenes" / "crane.toml")
    assert scene.ropes() == [0] and scene.coupling
    assert (scene.links[0].rope_min, scene.links[0].rope_max, scene.links[0].length) == (3.0, 30.0, 12.0)
    assert [link.bob_mass for link in scene.links] == [150.0, 2000.0]
    assert not any(link.has_mass for link in scene.links)
    assert scene.input_names() == ["a_pivot_x", "a_pivot_y", "a_pivot_z", "v_hoist0"]
    assert {"l0", "W_hoist", "W_pivot"} <= set(scene.state_names())
    assert {"T_rope0", "P_hoist0", "bob1_x", "energy"} <= set(scene.output_names())
