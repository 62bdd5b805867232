"""Stiff scenes (issue 46): the core's Radau IIA and BDF against scipy's on the same exact
Jacobian, the automatic choice, explicit solvers at the extremes, and the FMUs on the damped
light chain.

The damped light chain: three links of 1 m and 0.1 kg (Ixx = Izz = 0.1/12, Iyy = 1e-5) with
bobs of 0.1 kg and joint damping c; its Jacobian has eigenvalues down to about -6.9 c, so
c = 1e2 to 1e6 is a stiff scene, and c = 1 is not.
"""

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from scipy.integrate import solve_ivp

from conical_pendulum import Scene
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.scene import Link
from fmu_helpers import Instance, Instance3

SEED = Scene.uniform(3)
START = {"alpha0": 1.0, "beta2": -0.8, "omega1": 0.5}


def light_chain(links=3, c=1.0, coupling=False):
    link = Link(length=1.0, mass=0.1, bob_mass=0.1, damping=c, moments=(0.1 / 12, 1e-5, 0.1 / 12))
    return Scene(links=(link,) * links, joint_damping=True, coupling=coupling)


DAMPINGS = (1.0, 1e2, 1e4, 1e6)
LIGHT = light_chain()  # c is a parameter: one core for every rung


@pytest.fixture(scope="module")
def seed_core():
    return load_core(SEED)


@pytest.fixture(scope="module")
def light_core():
    return load_core(LIGHT)


def light_parameters(c):
    return np.array(LIGHT.parameters({f"c{i}": c for i in range(3)}))


def scipy_solve(core, x0, p, times, tol, method="Radau"):
    """scipy's implicit solver on the core's right-hand side and exact Jacobian."""
    return solve_ivp(
        lambda t, x: core.rhs(x, p),
        (times[0], times[-1]),
        x0,
        method=method,
        t_eval=times,
        rtol=tol,
        atol=tol,
        jac=lambda t, x: core.jacobian(x, p),
    )


REFERENCE_TOL = 1e-12


def reference(core, x0, p, times):
    """scipy's Radau at rtol 1e-12: the answer the tolerances are measured against."""
    return scipy_solve(core, x0, p, times, REFERENCE_TOL).y.T


# --- the implicit solver ---------------------------------------------------------------------


def test_the_jacobian_is_the_derivative_of_the_right_hand_side(light_core):
    """Complex step, exact to rounding: central differences agree to their own error."""
    p, x = light_parameters(1e2), np.array(LIGHT.initial_state({"alpha1": 0.4, "omega2": 0.3}))
    J = light_core.jacobian(x, p)
    h = 1e-6
    for j in range(light_core.NSTATE):
        e = np.zeros_like(x)
        e[j] = h
        column = (light_core.rhs(x + e, p) - light_core.rhs(x - e, p)) / (2 * h)
        np.testing.assert_allclose(J[:, j], column, rtol=1e-6, atol=1e-6 * np.abs(J).max())


EPS = np.finfo(float).eps


def newton_stops_out_of_roundings_reach(tol):
    """Whether rounding cannot decide when a Newton iteration stops. scipy's Radau (and the
    core's) stops it once rate / (1 - rate) ||dW / scale|| < newton_tol, newton_tol = max(10
    eps / tol, min(0.03, sqrt(tol))); an increment's rounding, eps |x| on a scale of tol |x|,
    is eps / tol in that norm. At tol = 1e-6 the threshold (1e-3) is 4.5e6 times that floor;
    at 1e-10 (1e-5 against 2.2e-6) the last bits of the LU's solves decide, and those are
    the machine's: scipy's LAPACK picks its kernels by CPU."""
    newton_tol = max(10 * EPS / tol, min(0.03, tol**0.5))
    return newton_tol > 1e3 * EPS / tol


@pytest.mark.parametrize("c", [None, *DAMPINGS], ids=["seed", *(f"c={c:g}" for c in DAMPINGS)])
@pytest.mark.parametrize("tol", [1e-6, 1e-10])
def test_radau_steps_as_scipys_radau_does(seed_core, light_core, c, tol):
    """The same algorithm on the same exact Jacobian. Where rounding cannot stop a Newton
    iteration (newton_stops_out_of_roundings_reach): the Jacobians and factorizations scipy
    makes, its right-hand sides to 0.5 % (a rate test landing within rounding of its
    threshold), and its answer to far below the tolerance. Where it can (tol = 1e-10): an
    iteration more or less now and then, each moving the next step sizes, so the counts within
    10 % (measured on the seed: 58 factorizations against scipy's 54 on one CPU, against 58 on
    another) and an answer as accurate as scipy's against the reference at 1e-12: within
    twice scipy's error and the reference's own tolerance (measured: within 0.4 % of it)."""
    core, scene = (seed_core, SEED) if c is None else (light_core, LIGHT)
    p = np.array(SEED.parameters()) if c is None else light_parameters(c)
    x0, times = np.array(scene.initial_state(START)), np.linspace(0.0, 5.0, 101)
    counts = {}
    states, _ = core.integrate_grid(x0, p, times, tol, tol, method="radau", counts=counts)
    sol = scipy_solve(core, x0, p, times, tol)
    if newton_stops_out_of_roundings_reach(tol):
        assert (counts["njev"], counts["nlu"]) == (sol.njev, sol.nlu)
        assert abs(counts["nfev"] - sol.nfev) <= 0.005 * sol.nfev
        # the same iterations: the same answer to rounding; an iteration more or less: two
        # answers of the same tolerance (measured: 0.11 tol apart)
        bound = 1e-3 * tol if counts["nfev"] == sol.nfev else 0.2 * tol
        np.testing.assert_allclose(states, sol.y.T, rtol=0, atol=bound)
        return
    for name, theirs in (("njev", sol.njev), ("nlu", sol.nlu), ("nfev", sol.nfev)):
        assert abs(counts[name] - theirs) <= 1 + 0.1 * theirs, (name, counts[name], theirs)
    exact = reference(core, x0, p, times)
    ours, scipys = np.abs(states - exact).max(), np.abs(sol.y.T - exact).max()
    assert ours <= 2 * scipys + REFERENCE_TOL, (ours, scipys)


@pytest.mark.parametrize("c", DAMPINGS)
def test_radau_meets_its_tolerance_on_every_rung(light_core, c):
    p, x0, times = light_parameters(c), np.array(LIGHT.initial_state()), np.linspace(0.0, 10.0, 101)
    states, _ = light_core.integrate_grid(x0, p, times, 1e-6, 1e-6, method="radau")
    assert np.abs(states - reference(light_core, x0, p, times)).max() < 1e-5


# --- the BDF ------------------------------------------------------------------------------------


@pytest.mark.parametrize("c", [None, *DAMPINGS], ids=["seed", *(f"c={c:g}" for c in DAMPINGS)])
def test_bdf_steps_as_scipys_bdf_does(seed_core, light_core, c):
    """The same formulas, order and step-size choices and Newton iteration on the same exact
    Jacobian, at a tolerance whose Newton stops rounding cannot move: scipy's Jacobians and
    factorizations, its right-hand sides and one more a step (x' at each step's end, which
    every core solver leaves for the next step and the ropes' watch), its answer (the dense
    output at the points) to far below the tolerance."""
    core, scene = (seed_core, SEED) if c is None else (light_core, LIGHT)
    p = np.array(SEED.parameters()) if c is None else light_parameters(c)
    x0, times, tol = np.array(scene.initial_state(START)), np.linspace(0.0, 5.0, 101), 1e-6
    assert newton_stops_out_of_roundings_reach(tol)
    counts = {}
    states, _ = core.integrate_grid(x0, p, times, tol, tol, method="bdf", counts=counts)
    sol = scipy_solve(core, x0, p, times, tol, method="BDF")
    assert (counts["njev"], counts["nlu"]) == (sol.njev, sol.nlu)
    assert counts["nfev"] == sol.nfev + counts["naccept"]
    np.testing.assert_allclose(states, sol.y.T, rtol=0, atol=1e-3 * tol)


@pytest.mark.parametrize("c", DAMPINGS)
def test_bdf_keeps_its_global_error_within_tens_of_tolerances_on_every_rung(light_core, c):
    """BDF controls each step's error as Radau does, but its lower order lets more of it
    through in 10 s: at rtol = atol = 1e-6 measured 18, 7.1, 0.23 and 0.01 tolerances from
    c = 1 to 1e6, where Radau's are 0.5, 0.6, 7e-5 and 2e-5."""
    p, x0, times = light_parameters(c), np.array(LIGHT.initial_state()), np.linspace(0.0, 10.0, 101)
    states, _ = light_core.integrate_grid(x0, p, times, 1e-6, 1e-6, method="bdf")
    assert np.abs(states - reference(light_core, x0, p, times)).max() < 30e-6


@pytest.mark.parametrize("c", [1e2, 1e4])
def test_bdf_past_20_states_iterates_longer_for_fewer_jacobians(c):
    """Past 20 states (here 10 links, 40) the Newton iteration may take ten iterations to 0.03
    before asking for a new Jacobian: no more Jacobians than scipy's BDF takes (measured 4
    against 10 at c = 1e2, 3 against 3 at c = 1e4, rtol 1e-6, 5 s), for an error as small
    (measured 0.74 and 0.62 of scipy's against the reference)."""
    scene = light_chain(10)
    core = load_core(scene)
    p = np.array(scene.parameters({f"c{i}": c for i in range(10)}))
    x0, times = np.array(scene.initial_state({"alpha0": 0.5, "beta1": -0.3})), np.linspace(0.0, 5.0, 101)
    counts = {}
    states, _ = core.integrate_grid(x0, p, times, 1e-6, 1e-6, method="bdf", counts=counts)
    sol = scipy_solve(core, x0, p, times, 1e-6, method="BDF")
    exact = reference(core, x0, p, times)
    assert counts["njev"] <= sol.njev
    assert np.abs(states - exact).max() <= np.abs(sol.y.T - exact).max()


# --- the automatic choice ----------------------------------------------------------------------


@pytest.mark.parametrize("start", [{}, START], ids=["seed", "violent"])
def test_auto_on_the_seed_is_dop853_bit_for_bit(seed_core, start):
    """The seed is never stiff: the automatic choice never switches, and costs nothing (from
    its start at rtol 1e-3 too; started violently at 1e-3 its long steps retake points)."""
    x0, p, times = SEED.initial_state(start), np.array(SEED.parameters()), np.linspace(0, 10, 601)
    for tol in (1e-3, 1e-6, 1e-11)[0 if not start else 1 :]:
        auto, dop = {}, {}
        by_auto, _ = seed_core.integrate_grid(x0, p, times, tol, tol, method="auto", counts=auto)
        by_dop853, _ = seed_core.integrate_grid(x0, p, times, tol, tol, method="dop853", counts=dop)
        np.testing.assert_array_equal(by_auto, by_dop853)
        assert auto == dop and auto["nswitch"] == 0


@pytest.mark.parametrize("c", DAMPINGS[1:])
def test_auto_switches_to_radau_on_a_stiff_scene(light_core, c):
    p, x0, times = light_parameters(c), np.array(LIGHT.initial_state()), np.linspace(0.0, 10.0, 101)
    auto = {}
    states, _ = light_core.integrate_grid(x0, p, times, 1e-6, 1e-6, method="auto", counts=auto)
    assert auto["nswitch"] >= 1 and auto["njev"] >= 1
    assert np.abs(states - reference(light_core, x0, p, times)).max() < 1e-5
    radau = {}
    light_core.integrate_grid(x0, p, times, 1e-6, 1e-6, method="radau", counts=radau)
    assert auto["nfev"] + auto["njev"] * light_core.NSTATE < 10 * (
        radau["nfev"] + radau["njev"] * light_core.NSTATE
    )


# --- explicit solvers at the extremes ----------------------------------------------------------


@pytest.mark.parametrize("method", ["rk45", "dop853"])
def test_an_explicit_pair_finishes_a_stiff_scene_at_its_stability_bound(light_core, method):
    """c = 100: the first trial stages blow up (the scene's fastest mode at -6.9e3 1/s); those
    steps are rejected and shrunk, never reported as the model's non-finite acceleration (as
    scipy's DOP853 reports them). Checked at the run's end, a step's end: inside its steps,
    at its stability bound, DOP853's interpolant is 40 times the tolerance off (docs/limits.md)."""
    p, x0, times = light_parameters(1e2), np.array(LIGHT.initial_state()), np.array([0.0, 1.0])
    states, _ = light_core.integrate_grid(x0, p, times, 1e-6, 1e-6, method=method)
    assert np.abs(states - reference(light_core, x0, p, times)).max() < 1e-5


@pytest.mark.parametrize("method", ["rk45", "dop853"])
def test_an_explicit_pair_out_of_steps_on_a_stiff_scene_says_so(light_core, method):
    p, x0 = light_parameters(1e6), np.array(LIGHT.initial_state())
    with pytest.raises(RuntimeError, match="too many steps: the scene is stiff"):
        light_core.integrate_grid(x0, p, [0.0, 1.0], 1e-6, 1e-6, method=method, max_steps=1000)


# --- the FMUs ------------------------------------------------------------------------------------

FMUS = [
    pytest.param(("native", 2), id="native-fmi2"),
    pytest.param(("native", 3), id="native-fmi3"),
    pytest.param(("pythonfmu", 2), id="pythonfmu"),
]


def open_fmu(built_fmu, kind, start, stop_time=10.0):
    backend, fmi_version = kind
    path = built_fmu(LIGHT, backend=backend, fmi_version=fmi_version)
    fmu = (Instance if fmi_version == 2 else Instance3)(path, start_values=start, initialize=False)
    fmu.initialize(stop_time=stop_time)
    return fmu


def damping(c):
    return {f"c{i}": c for i in range(3)}


@pytest.mark.parametrize("kind", FMUS)
@pytest.mark.parametrize("c", DAMPINGS)
def test_the_ladder_finishes_with_the_default_solver_in_every_fmu(built_fmu, light_core, kind, c):
    """10 s at 100 Hz, rtol = atol = 1e-6 and every other setting at its default: within 10 rtol
    of the reference, at a cost far from an explicit solver's at the stability bound."""
    fmu = open_fmu(built_fmu, kind, {**damping(c), "rtol": 1e-6, "atol": 1e-6})
    seen = [fmu.get(*light_core.STATE_NAMES)]
    for _ in range(1000):
        fmu.step(0.01)
        seen.append(fmu.get(*light_core.STATE_NAMES))
    (rhs,) = fmu.get("n_rhs")
    fmu.close()
    p, x0, times = light_parameters(c), np.array(LIGHT.initial_state()), np.linspace(0.0, 10.0, 1001)
    assert np.abs(np.array(seen) - reference(light_core, x0, p, times)).max() < 1e-5
    assert rhs < 5000


def test_dop853_in_an_fmu_says_the_scene_is_stiff_and_what_to_choose(built_fmu):
    fmu = open_fmu(built_fmu, ("native", 2), {**damping(1e6), "solver": 2, "max_steps": 1000})
    with pytest.raises(FMICallException):
        fmu.step(0.01)
    message = fmu.texts()
    assert "the scene is stiff" in message and "|lambda| = 6.89e+07 1/s" in message
    assert "choose solver = 3 (radau) or 4 (auto)" in message
    assert "non-finite acceleration" not in message
    fmu.close()


@pytest.mark.parametrize("kind", FMUS)
@pytest.mark.parametrize("solver", [3, 4, 5])
def test_a_stiff_state_saved_inside_a_step_continues_bit_for_bit(built_fmu, light_core, kind, solver):
    """The step in flight and the Jacobian with its factors live in the FMU state: a restored
    state replays the same bits, the same right-hand sides, Jacobians and factorizations."""
    fmu = open_fmu(built_fmu, kind, {**damping(1e4), "solver": solver, "rtol": 1e-6, "atol": 1e-6})
    names = [*light_core.STATE_NAMES, "n_rhs", "n_jacobians", "n_factorizations"]
    for _ in range(37):
        fmu.step(0.013)
    state, t = fmu.get_state(), fmu.time
    straight = []
    for _ in range(50):
        fmu.step(0.013)
        straight.append(fmu.get(*names))
    fmu.set_state(state)
    fmu.free_state(state)
    fmu.time = t
    replayed = []
    for _ in range(50):
        fmu.step(0.013)
        replayed.append(fmu.get(*names))
    fmu.close()
    np.testing.assert_array_equal(np.array(replayed)[:, :-3], np.array(straight)[:, :-3])
    assert straight[-1][-2] >= 1  # a Jacobian was used


def test_auto_goes_back_to_dop853_when_the_scene_calls_for_short_steps(built_fmu):
    """c = 1: once the swing has decayed, DOP853's steps grow to its stability bound and the
    automatic choice takes Radau (Jacobians and factorizations appear). A master then shakes
    the support, setting the pivot's acceleration at every point of 0.01 s: each integration
    ends on its point, Radau's steps fit inside DOP853's stability bound, and the explicit pair
    takes over again (no more factorizations), the motion as an explicit run has it."""
    path = built_fmu(light_chain(coupling=True), backend="native")
    runs = []
    for solver in (4, 2):
        fmu = Instance(path, start_values={"solver": solver, "rtol": 1e-6, "atol": 1e-6}, initialize=False)
        fmu.initialize(stop_time=20.0)
        for _ in range(1000):
            fmu.step(0.01)
        settled = fmu.get("n_jacobians", "n_factorizations")
        for k in range(1000):
            fmu.set({"a_pivot_x": 5.0 * np.sin(2 * np.pi * 0.01 * k)})
            fmu.step(0.01)
            if k == 200:
                switched_back = fmu.get("n_factorizations")
        runs.append((settled, switched_back, fmu.get("n_factorizations", "alpha0", "beta0", "alpha2")))
        fmu.close()
    (settled, switched_back, (lu, *auto_end)), (_, _, (_, *dop853_end)) = runs
    assert settled[0] >= 1 and settled[1] >= 2  # Radau after the swing decayed
    assert lu == switched_back[0]  # DOP853 alone for the last 8 s of shaking
    np.testing.assert_allclose(auto_end, dop853_end, rtol=0, atol=1e-5)
