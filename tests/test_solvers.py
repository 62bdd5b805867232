"""The compiled core's solvers against scipy's implementations of the same methods."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from conical_pendulum import Scene
from conical_pendulum.builder.compiler import load_core

SCENE = Scene.uniform(3)


@pytest.fixture(scope="module")
def core():
    return load_core(SCENE)


def stepper(core, state=None):
    values = np.zeros(core.NSTATE + core.NOUTPUT)
    values[: core.NSTATE] = SCENE.initial_state(state)
    return core.Stepper(np.array(SCENE.parameters()), values), values


def reference(core, t_end, state=None):
    p = np.array(SCENE.parameters())
    sol = solve_ivp(
        lambda t, x: core.rhs(x, p),
        (0.0, t_end),
        SCENE.initial_state(state),
        method="DOP853",
        rtol=1e-13,
        atol=1e-13,
    )
    return sol.y[:, -1]


@pytest.mark.parametrize("method, scipy_name", [("rk45", "RK45"), ("dop853", "DOP853")])
@pytest.mark.parametrize("tol", [1e-5, 1e-8, 1e-11])
def test_adaptive_pairs_step_as_scipy_does(core, method, scipy_name, tol):
    """Same tableau, error norm and controller: the same steps, to rounding."""
    state = {"alpha0": 1.0, "beta2": -0.8, "omega1": 0.5}
    run, values = stepper(core, state)
    status = run.step(core.METHODS[method], 0.0, 10.0, tol, tol, 0.0, 10**7)
    assert status == 0
    p = np.array(SCENE.parameters())
    sol = solve_ivp(
        lambda t, x: core.rhs(x, p),
        (0.0, 10.0),
        SCENE.initial_state(state),
        method=scipy_name,
        rtol=tol,
        atol=tol,
    )
    assert run.naccept == len(sol.t) - 1
    assert run.nfev == sol.nfev
    assert abs(run.naccept + run.nreject - (sol.nfev - 2) / (6 if method == "rk45" else 12)) < 1e-9
    np.testing.assert_allclose(values[: core.NSTATE], sol.y[:, -1], rtol=0, atol=tol)
    # and the answer is as good as the tolerance asks, relative to a tight reference
    error = np.abs(values[: core.NSTATE] - reference(core, 10.0, state)).max()
    assert error < 2e3 * tol


def test_rk4_is_fourth_order(core):
    exact = reference(core, 2.0)
    errors = []
    for max_step in (0.02, 0.01):
        run, values = stepper(core)
        assert run.step(core.METHODS["rk4"], 0.0, 2.0, 1.0, 1.0, max_step, 10**7) == 0
        assert run.naccept == round(2.0 / max_step)
        errors.append(np.abs(values[: core.NSTATE] - exact).max())
    assert 14 < errors[0] / errors[1] < 18  # 2^4 = 16


def test_rk4_splits_the_communication_step_evenly(core):
    run, _ = stepper(core)
    run.step(core.METHODS["rk4"], 0.0, 0.1, 1.0, 1.0, 0.03, 100)  # ceil(0.1 / 0.03) = 4 steps of 0.025
    assert (run.naccept, run.nfev) == (4, 16)
    run, _ = stepper(core)
    run.step(core.METHODS["rk4"], 0.0, 0.1, 1.0, 1.0, 0.0, 100)  # no limit: one step
    assert (run.naccept, run.nfev) == (1, 4)


@pytest.mark.parametrize("method", ["rk45", "dop853"])
def test_step_size_carries_over_communication_steps(core, method):
    """Only the first call chooses an initial step; later calls resume with the last step
    size and the derivative the last step ended with (first same as last)."""
    stages = {"rk45": 6, "dop853": 12}[method]
    run, _ = stepper(core)
    run.step(core.METHODS[method], 0.0, 0.5, 1e-8, 1e-8, 0.0, 10**6)
    assert run.nfev == 2 + stages * (run.naccept + run.nreject)  # f(x0) + initial-step probe
    h = run.h
    assert h > 0
    before = (run.nfev, run.naccept, run.nreject)
    run.step(core.METHODS[method], 0.5, 0.5, 1e-8, 1e-8, 0.0, 10**6)
    attempts = run.naccept + run.nreject - before[1] - before[2]
    assert run.nfev - before[0] == stages * attempts
    # and the same trajectory as one call over the whole interval, to the tolerance
    whole, _values_whole = stepper(core)
    whole.step(core.METHODS[method], 0.0, 1.0, 1e-8, 1e-8, 0.0, 10**6)
    assert abs(run.naccept - whole.naccept) <= 2


def test_too_many_steps_and_underflow_are_reported_with_state_kept(core):
    run, values = stepper(core)
    start = values.copy()
    assert run.step(core.METHODS["dop853"], 0.0, 10.0, 1e-12, 1e-12, 0.0, 5) == core.TOO_MANY_STEPS
    np.testing.assert_array_equal(values, start)
    run, values = stepper(core)
    # at t = 1e15 time resolves only 0.125 s: no step can meet rtol = 1e-13
    assert run.step(core.METHODS["rk45"], 1e15, 1.0, 1e-13, 1e-300, 0.0, 10**6) == core.STEP_UNDERFLOW
    np.testing.assert_array_equal(values, start)


@pytest.mark.parametrize("tol", [1e-6, 1e-10])
def test_dense_output_grid_equals_scipy_dop853_with_t_eval(core, tol):
    """One DOP853 run over the grid, outputs from its dense output, as solve_ivp's t_eval (no
    interpolant where a time falls on a step's end)."""
    times = np.linspace(0.0, 10.0, 601)
    x0 = SCENE.initial_state({"alpha2": 1.2})
    p = np.array(SCENE.parameters())
    states, nfev = core.integrate_grid(x0, p, times, tol, tol)
    sol = solve_ivp(
        lambda t, x: core.rhs(x, p), (0.0, 10.0), x0, method="DOP853", t_eval=times, rtol=tol, atol=tol
    )
    # scipy computes a step's interpolant for a time on its end too; the core takes the end
    steps = solve_ivp(lambda t, x: core.rhs(x, p), (0.0, 10.0), x0, method="DOP853", rtol=tol, atol=tol).t
    last_holds_only_its_end = not np.any((times > steps[-2]) & (times < steps[-1]))
    assert nfev == sol.nfev - 3 * last_holds_only_its_end
    np.testing.assert_allclose(states, sol.y.T, rtol=0, atol=tol)
    exact = reference(core, 10.0, {"alpha2": 1.2})
    assert np.abs(states[-1] - exact).max() < 2e3 * tol
