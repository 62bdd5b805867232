"""The solver runs across communication points (issue 37): RK45 and DOP853 take their own
steps whatever the points, answer a point inside a step from its dense output and continue
from the step's end; they restart at a point only where an input changed, and a saved state
carries the step in flight.

Compared with the compiled core's uninterrupted dense-output run (core.integrate_grid: the
same cp_cover the FMUs call), with scipy's dense output, and with the old behaviour
(across_points = 0, core.pyx's Stepper). The pythonfmu FMU holds the same model through
the compiled core, so every case runs on both kinds of FMU.
"""

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from scipy.integrate import solve_ivp

from conical_pendulum import Scene
from conical_pendulum.builder.compiler import load_core
from fmu_helpers import Instance, Instance3

SEED = Scene.uniform(3)
COUPLED = Scene.uniform(3, coupling=True)  # a_pivot inputs
START = {"alpha0": 0.6, "delta1": 0.4}
METHODS = {1: "rk45", 2: "dop853", 3: "radau", 4: "auto", 5: "bdf"}  # the FMU's solver values
FMUS = [
    pytest.param(("native", 2), id="native-fmi2"),
    pytest.param(("native", 3), id="native-fmi3"),
    pytest.param(("pythonfmu", 2), id="pythonfmu"),
]
EVERY_FMU = [  # what ending each integration on the point meets too: no mark needed
    pytest.param(("native", 2), id="native-fmi2"),
    pytest.param(("native", 3), id="native-fmi3"),
    pytest.param(("pythonfmu", 2), id="pythonfmu"),
]


def open_fmu(built_fmu, kind, scene, start, stop_time):
    backend, fmi_version = kind
    path = built_fmu(scene, backend=backend, fmi_version=fmi_version)
    cls = Instance if fmi_version == 2 else Instance3
    fmu = cls(path, start_values=start, initialize=False)
    fmu.initialize(stop_time=stop_time)
    return fmu


def points(interval, steps):
    """The communication points as a master reaches them: one addition per step."""
    times = [0.0]
    for _ in range(steps):
        times.append(times[-1] + interval)
    return np.array(times)


def run(fmu, names, interval, steps, before_step=None):
    """The values of names at every point, and n_rhs after each step."""
    seen, rhs = [fmu.get(*names)], [fmu.get("n_rhs")[0]]
    for k in range(steps):
        if before_step:
            before_step(fmu, k)
        fmu.step(interval)
        seen.append(fmu.get(*names))
        rhs.append(fmu.get("n_rhs")[0])
    return np.array(seen), np.array(rhs)


def settings(solver, tol, across=1):
    return {"solver": solver, "rtol": tol, "atol": tol, "across_points": across}


@pytest.fixture(scope="module")
def core():
    return load_core(SEED)


@pytest.fixture(scope="module")
def coupled_core():
    return load_core(COUPLED)


# --- the interpolants ----------------------------------------------------------------------


@pytest.mark.parametrize("method, scipy_name", [("rk45", "RK45"), ("dop853", "DOP853"), ("bdf", "BDF")])
@pytest.mark.parametrize("tol", [1e-5, 1e-9])
def test_the_interpolants_are_scipys_dense_output_on_the_same_steps(core, method, scipy_name, tol):
    """Many times inside each step: the core's interpolant (DOP853's order 7, RK45's
    Dormand-Prince extension, BDF's polynomial through its differences) where scipy's
    dense_output is, to rounding (BDF on the core's exact Jacobian, as the core's)."""
    x0, p = SEED.initial_state(START), np.array(SEED.parameters())
    times = np.linspace(0.0, 3.0, 3001)
    states, _ = core.integrate_grid(x0, p, times, tol, tol, method=method)
    jacobian = {"jac": lambda t, x: core.jacobian(x, p)} if method == "bdf" else {}
    sol = solve_ivp(
        lambda t, x: core.rhs(x, p),
        (0.0, 3.0),
        x0,
        method=scipy_name,
        rtol=tol,
        atol=tol,
        dense_output=True,
        **jacobian,
    )
    assert len(sol.t) < len(times) / 10  # several times in every step
    np.testing.assert_allclose(states, sol.sol(times).T, rtol=0, atol=1e-3 * tol)


# --- no input changes: the uninterrupted run -------------------------------------------------


@pytest.mark.parametrize("kind", FMUS)
@pytest.mark.parametrize("solver", [1, 2, 3, 4, 5])
@pytest.mark.parametrize("interval, steps", [(1 / 60, 300), (1e-3, 2000)])
def test_the_states_at_the_points_are_the_uninterrupted_runs(built_fmu, core, kind, solver, interval, steps):
    """Bit for bit, and at the same cost: the same steps, the points from their dense output."""
    tol = 1e-8
    times = points(interval, steps)
    fmu = open_fmu(built_fmu, kind, SEED, {**START, **settings(solver, tol)}, times[-1])
    states, rhs = run(fmu, core.STATE_NAMES, interval, steps)
    fmu.close()
    x0, p = SEED.initial_state(START), np.array(SEED.parameters())
    grid, nfev = core.integrate_grid(x0, p, times, tol, tol, method=METHODS[solver])
    np.testing.assert_array_equal(states, grid)
    assert rhs[-1] == nfev
    if METHODS[solver] not in ("radau", "bdf"):  # the implicit steps on the seed at 1e-8: about 1/60 s
        assert np.count_nonzero(np.diff(rhs) == 0) > steps / 2  # most points cost nothing


@pytest.mark.parametrize("kind", [("native", 2), ("native", 3)], ids=["native-fmi2", "native-fmi3"])
def test_across_points_off_ends_every_integration_on_the_point(built_fmu, core, kind):
    """across_points = 0: the old behaviour, step for step the core's Stepper (one RK45 step a
    point at 60 Hz: 6 right-hand sides each, x' carried)."""
    tol, steps, interval = 1e-6, 120, 1 / 60
    fmu = open_fmu(built_fmu, kind, SEED, {**START, **settings(1, tol, across=0)}, None)
    states, rhs = run(fmu, core.STATE_NAMES, interval, steps)
    fmu.close()
    assert rhs[-1] == 2 + 6 * steps
    values = np.zeros(core.NSTATE + core.NOUTPUT)
    values[: core.NSTATE] = SEED.initial_state(START)
    stepper = core.Stepper(np.array(SEED.parameters()), values)
    t = 0.0
    for k in range(steps):
        assert stepper.step(core.METHODS["rk45"], t, interval, tol, tol, 0.0, 100_000) == 0
        t += interval
        np.testing.assert_array_equal(states[k + 1], values[: core.NSTATE])


@pytest.mark.parametrize("kind", EVERY_FMU)
def test_rk4_stays_fixed_step(built_fmu, kind):
    """RK4 ends every step on the point whatever across_points says: 4 right-hand sides a point."""
    fmu = open_fmu(built_fmu, kind, SEED, {**START, "solver": 0, "across_points": 1}, 1.0)
    _, rhs = run(fmu, ["alpha0"], 1 / 60, 60)
    fmu.close()
    assert rhs[-1] == 4 * 60


# --- inputs that change ------------------------------------------------------------------------


@pytest.mark.parametrize("kind", FMUS)
def test_an_input_changed_at_one_point_restarts_the_integration_there(built_fmu, coupled_core, kind):
    """Before the change, the uninterrupted run bit for bit; after, the integration restarted
    at the point from the interpolated state with the new input, to the tolerance, far from
    the run that would have gone on with the old input."""
    tol, interval, steps, change = 1e-9, 1 / 60, 240, 100
    times = points(interval, steps)
    fmu = open_fmu(built_fmu, kind, COUPLED, {**START, **settings(2, tol)}, times[-1])

    def push(fmu, k):
        if k == change:
            fmu.set({"a_pivot_x": 2.0})
        elif k > change:
            fmu.set({"a_pivot_x": 2.0})  # the same bits: no change

    states, _ = run(fmu, coupled_core.STATE_NAMES, interval, steps, push)
    fmu.close()
    x0, p = COUPLED.initial_state(START), np.array(COUPLED.parameters())
    before, _ = coupled_core.integrate_grid(x0, p, times, tol, tol)
    np.testing.assert_array_equal(states[: change + 1], before[: change + 1])
    pushed = p.copy()
    pushed[list(coupled_core.PARAMETER_NAMES).index("a_pivot_x")] = 2.0
    after, _ = coupled_core.integrate_grid(states[change], pushed, times[change:], tol, tol)
    np.testing.assert_allclose(states[change:], after, rtol=0, atol=1e3 * tol)
    assert np.abs(states[-1] - before[-1]).max() > 1e-2


@pytest.mark.parametrize("kind", EVERY_FMU)
@pytest.mark.parametrize("interval", [1 / 60, 1e-3])
def test_inputs_changed_at_every_point_cost_one_step_a_point(built_fmu, coupled_core, kind, interval):
    """The natural step is longer than the points: a restart for new inputs ends its first
    integration on the next point, so inputs new at every point cost one step a point (x' at
    the new input and the step, no interpolant), what ending every integration on the point
    costs, but for the first step, which starts the integration across the points."""
    steps, found = 120, {}
    for across in (1, 0):
        fmu = open_fmu(built_fmu, kind, COUPLED, {**START, **settings(2, 1e-8, across)}, None)
        found[across] = run(
            fmu,
            [*coupled_core.STATE_NAMES, "n_steps", "n_rejected"],
            interval,
            steps,
            lambda f, k: f.set({"a_pivot_x": 0.01 * (k % 7 + 1)}),
        )
        fmu.close()
    (values, rhs), (on_points, on_points_rhs) = found[1], found[0]
    accepted, rejected = values[-1, -2:]
    assert accepted + rejected <= steps + 1
    assert np.all(np.diff(rhs)[1:] == 1 + 12)
    assert np.all(np.diff(on_points_rhs)[1:] == 1 + 12)
    states = len(coupled_core.STATE_NAMES)
    np.testing.assert_allclose(values[:, :states], on_points[:, :states], rtol=0, atol=1e-6)


@pytest.mark.parametrize("kind", [FMUS[0]])  # FMI 3.0 has none, the pythonfmu FMU holds inputs
def test_input_derivatives_of_the_same_bits_continue_the_integration(built_fmu, kind):
    """An input moving as its derivatives say, set again at each point as the model left it:
    one integration along the polynomial, the uninterrupted run's cost."""
    steps, interval = 240, 1 / 60
    fmu = open_fmu(built_fmu, kind, COUPLED, {**START, **settings(2, 1e-8)}, None)
    vr = fmu.vr["a_pivot_x"]
    fmu.fmu.setRealInputDerivatives([vr], [1], [0.5])
    fmu.fmu.setRealInputDerivatives([vr], [2], [-0.25])

    def again(fmu, k):  # what the model says the input is now, set back
        fmu.fmu.setReal([vr], fmu.fmu.getReal([vr]))

    _, rhs = run(fmu, ["alpha0"], interval, steps, again)
    u = fmu.get("a_pivot_x")[0]
    fmu.close()
    t = points(interval, steps)[-1]
    assert u == pytest.approx(0.5 * t - 0.125 * t * t, rel=1e-12)
    assert np.count_nonzero(np.diff(rhs) == 0) > steps / 2


# --- the FMU state -----------------------------------------------------------------------------

REPLAY = """
import json, sys
from fmu_helpers import Instance, Instance3
path, fmi_version, state_file, interval, steps, start = sys.argv[1:]
cls = Instance if fmi_version == "2" else Instance3
fmu = cls(path, initialize=False)
fmu.initialize(stop_time=10.0)
with open(state_file, "rb") as f:
    state = fmu.deserialize(f.read())
fmu.set_state(state)
fmu.free_state(state)
names = json.loads(sys.stdin.read())
seen = []
fmu.time = float.fromhex(start)
for _ in range(int(steps)):
    fmu.step(float.fromhex(interval))
    seen.append([v.hex() for v in fmu.get(*names)])
fmu.close()
print(json.dumps(seen))
"""


@pytest.mark.parametrize("kind", EVERY_FMU)
@pytest.mark.parametrize("solver", [0, 1, 2, 3, 4, 5])
def test_a_state_saved_inside_a_step_continues_bit_for_bit_in_another_process(
    built_fmu, core, kind, solver, tmp_path
):
    interval, before, after = 1e-3, 777, 400
    fmu = open_fmu(built_fmu, kind, SEED, {**START, **settings(solver, 1e-8)}, 10.0)
    names = [*core.STATE_NAMES, "energy", "n_rhs", "n_steps"]
    run(fmu, names, interval, before)
    state = fmu.get_state()
    (tmp_path / "state").write_bytes(bytes(fmu.serialize(state)))
    fmu.free_state(state)
    t = fmu.time
    straight, _ = run(fmu, names, interval, after)
    fmu.close()
    backend, fmi_version = kind
    path = built_fmu(SEED, backend=backend, fmi_version=fmi_version)
    replay = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(REPLAY), str(path), str(fmi_version), str(tmp_path / "state")]
        + [interval.hex(), str(after), t.hex()],
        input=json.dumps(names),
        capture_output=True,
        text=True,
        timeout=300,
        cwd=str(tmp_path),
        env={**os.environ, "PYTHONPATH": os.path.dirname(__file__)},
        check=True,
    )
    replayed = np.array([[float.fromhex(v) for v in row] for row in json.loads(replay.stdout)])
    np.testing.assert_array_equal(replayed, straight[1:])


@pytest.mark.parametrize("kind", EVERY_FMU)
def test_a_master_counting_its_points_as_k_h_continues_the_integration(built_fmu, core, kind):
    """Points k h differ from the FMU's t + h in the last bits at some k: within
    CP_SAME_POINT_ULPS units in the last place they are the same point, so the run costs
    what one of t + h points costs (issue 46 measured 2.4 times as much before) and answers
    the uninterrupted run at the master's times."""
    interval, steps, tol = 1 / 60, 600, 1e-10
    times = interval * np.arange(steps + 1)
    assert np.count_nonzero(times != points(interval, steps)) > steps / 10  # the two differ
    fmu = open_fmu(built_fmu, kind, SEED, {**START, **settings(2, tol)}, times[-1])
    seen = [fmu.get(*core.STATE_NAMES)]
    for t in times[:-1]:
        fmu.fmu.doStep(t, interval)
        seen.append(fmu.get(*core.STATE_NAMES))
    (rhs,) = fmu.get("n_rhs")
    fmu.close()
    x0, p = SEED.initial_state(START), np.array(SEED.parameters())
    grid, nfev = core.integrate_grid(x0, p, times, tol, tol, method="dop853")
    assert rhs == nfev
    np.testing.assert_allclose(seen, grid, rtol=0, atol=1e-13)


@pytest.mark.parametrize("kind", EVERY_FMU)
def test_a_state_restored_a_few_bits_off_the_masters_point_replays_the_same(built_fmu, core, kind):
    """Saved at t = 0.1 + 0.2 (0.30000000000000004) and stepped again from 0.3, as a master
    that counts its own time says it: the same integration as the step taken from the saved
    time (the same right-hand sides), answered at the master's time, a unit in the last place
    from the other's."""
    fmu = open_fmu(built_fmu, kind, SEED, {**START, **settings(2, 1e-10)}, 10.0)
    fmu.fmu.doStep(0.0, 0.1)
    fmu.fmu.doStep(0.1, 0.2)
    state = fmu.get_state()
    fmu.fmu.doStep(0.1 + 0.2, 0.25)
    straight = fmu.get(*core.STATE_NAMES, "n_rhs")
    fmu.set_state(state)
    fmu.fmu.doStep(0.3, 0.25)
    again = fmu.get(*core.STATE_NAMES, "n_rhs")
    fmu.free_state(state)
    fmu.close()
    assert again[-1] == straight[-1]
    np.testing.assert_allclose(again[:-1], straight[:-1], rtol=0, atol=1e-15)


@pytest.mark.parametrize("backend", ["native", "pythonfmu"])
def test_a_stop_time_before_the_start_is_refused(built_fmu, backend):
    """Both FMUs by the one rule (fmu_model.h's experiment_times_refusal)."""
    path = built_fmu(SEED, backend=backend)
    fmu = Instance(path, initialize=False)
    with pytest.raises(FMICallException):
        fmu.fmu.setupExperiment(startTime=1.0, stopTime=0.5)
    assert "stopTime = 0.5: must be finite and not before startTime = 1" in fmu.texts()
    fmu.close(after_fatal=True)  # never initialized: only freed
