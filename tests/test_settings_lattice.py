"""Every solver setting honoured or the step discarded: a lattice of settings, both backends.

Each case instantiates the seed FMU with one solver, `max_step` and `max_steps`, and takes
two communication steps of one size (one of the longest, 100 s). Either a step completes, and the state is where the
solver's own accuracy puts it (RK4: RK4 itself with the same substeps, to rounding; the
adaptive solvers: the native reference, within an error that grows linearly with time
from the tolerance), or it is discarded with a diagnosis and the state kept. Never
success with a state that did not move, never more internal steps in one doStep than
`max_steps`, and every case within a time bound.
"""

import math
import shutil
import time
from collections import Counter

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave, fmi2Discard

from conical_pendulum import Scene
from conical_pendulum.analysis.fmpy_runs import logging_callbacks
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.runtime.rules import SOLVERS

SEED = Scene.uniform(3)
STEPS = (1e-9, 1e-6, 0.01, 1.0, 100.0)  # communication steps [s]
MAX_STEPS = (1, 10, 10**6)
DIAGNOSES = (
    "too many steps",
    "step size underflow",
    "max_step below the resolution of time",
    "non-finite acceleration",
    "singular mass matrix",
)


def steps_per_case(h):
    return 1 if h == max(STEPS) else 2


def max_step_values(h):
    return (0.0, 1e-300, 1e-20, 1e-9, 1e-3, h / 3, h, 10 * h)


CASES = [
    (solver, max_step, max_steps, h)
    for solver in range(len(SOLVERS))
    for h in STEPS
    for max_step in max_step_values(h)
    for max_steps in MAX_STEPS
]


@pytest.fixture(scope="module")
def core():
    return load_core(SEED)


class Lattice:
    """One FMU's binary loaded once; each case a fresh instance of it."""

    def __init__(self, path):
        md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.states = [self.vr[name] for name in SEED.state_names()]
        self.counters = [self.vr["n_steps"], self.vr["n_rejected"]]
        self.messages = []
        self._callbacks = logging_callbacks(lambda status, text: self.messages.append(text))
        self.unzipdir = extract(str(path))
        self.fmu = FMU2Slave(
            guid=md.guid,
            unzipDirectory=self.unzipdir,
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName="case",
        )

    def run(self, solver, max_step, max_steps, h, rtol=1e-8, atol=1e-8):
        """(outcome, state at the last good point, its time, the message, attempts per step)."""
        fmu, self.messages[:], outcome = self.fmu, [], "refused"
        fmu.instantiate(callbacks=self._callbacks, loggingOn=True)  # pythonfmu logs only then
        try:
            fmu.setInteger([self.vr["solver"], self.vr["max_steps"]], [solver, max_steps])
            fmu.setReal([self.vr[name] for name in ("max_step", "rtol", "atol")], [max_step, rtol, atol])
            fmu.setupExperiment(startTime=0.0)
            fmu.enterInitializationMode()
            fmu.exitInitializationMode()
            t, outcome, attempts = 0.0, "completed", []
            for _ in range(steps_per_case(h)):
                state, counted = fmu.getReal(self.states), sum(fmu.getReal(self.counters))
                try:
                    fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
                except FMICallException as exc:
                    assert exc.status == fmi2Discard, exc
                    outcome = "discarded"
                else:
                    t += h
                    state = fmu.getReal(self.states)
                attempts.append(sum(fmu.getReal(self.counters)) - counted)
                if outcome == "discarded":
                    assert fmu.getReal(self.states) == state, "a discarded step kept the state"
                    break
            return outcome, np.array(state), t, " ".join(self.messages), attempts
        finally:
            if outcome == "completed":
                fmu.terminate()
            fmu.fmi2FreeInstance(fmu.component)  # fmpy's freeInstance unloads the library too

    def close(self):
        self.fmu.freeLibrary()
        shutil.rmtree(self.unzipdir, ignore_errors=True)


def rk4(core, x, p, dt, max_step):
    """RK4 as the solvers' contract says: ceil(dt / max_step) equal steps (one if 0)."""
    steps = math.ceil(dt / max_step) if max_step > 0 and dt > max_step else 1
    h = dt / steps
    y = x.copy()
    for _ in range(steps):
        k1 = core.rhs(y, p)
        k2 = core.rhs(y + 0.5 * h * k1, p)
        k3 = core.rhs(y + 0.5 * h * k2, p)
        k4 = core.rhs(y + h * k3, p)
        y += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return y


def check_completed(core, solver, max_step, h, t, state, rtol=1e-8, atol=1e-8):
    """The state the solver's own accuracy promises at t: for the adaptive solvers, a global
    error that grows at most linearly with time from the tolerances (and the reference's).
    The relative tolerance scales each component's largest size on the way to t: the solvers
    step across the points, a point inside a step is answered by the step's interpolant, and
    the error control weighs the state where its steps start and end, not at the point. BDF's
    lets more through (order 5 at most, one stage): three times the others' growth, as
    scipy's BDF on the same seed gives (32.8 and 24.3 tolerances at 2 s at rtol 2.3e-14 and
    1e-9, atol 1e-9; the core's BDF the same to three digits, Radau 0.007)."""
    p, x0 = np.array(SEED.parameters()), np.array(SEED.initial_state())
    if SOLVERS[solver] == "rk4":
        expected = x0
        for _ in range(steps_per_case(h)):
            expected = rk4(core, expected, p, h, max_step)
        assert np.allclose(state, expected, rtol=1e-12, atol=1e-14), (state, expected)
        return
    reference, _ = core.integrate_grid(x0, p, np.linspace(0.0, t, 201), 1e-13, 1e-13, 0.0, 10**8)
    size = np.abs(reference).max(axis=0)
    tolerance = atol + rtol * size + 1e-13 * (1 + size)
    error = np.abs(state - reference[-1]) / tolerance
    growth = 30 if SOLVERS[solver] == "bdf" else 10
    assert error.max() <= growth * (1 + t), f"{error.max():.3g} tolerances from the reference at {t} s"


def check_case(case, outcome, message, attempts, max_steps):
    """What every case must show, whatever its settings: the work is bounded by max_steps (the
    time it takes depends on the machine's load: printed, not checked)."""
    assert max(attempts) <= max_steps, (case, attempts)
    if outcome == "discarded":
        assert "failed" in message and any(d in message for d in DIAGNOSES), (case, message)


@pytest.mark.parametrize("backend", ["pythonfmu", "native"])
def test_every_setting_is_honoured_or_the_step_discarded(request, core, backend):
    path = request.getfixturevalue("seed_fmu" if backend == "pythonfmu" else "native_seed_fmu")
    lattice = Lattice(path)
    counts, slowest = Counter(), (0.0, None)
    for solver, max_step, max_steps, h in CASES:
        case = (SOLVERS[solver], max_step, max_steps, h)
        started = time.perf_counter()
        outcome, state, t, message, attempts = lattice.run(solver, max_step, max_steps, h)
        seconds = time.perf_counter() - started
        slowest = max(slowest, (seconds, case))
        check_case(case, outcome, message, attempts, max_steps)
        fewest = math.ceil(h / max_step) if max_step > 0 and h > max_step else 1
        if fewest > max_steps:  # more steps than allowed: discarded before any work
            assert outcome == "discarded" and attempts == [0], case
        elif SOLVERS[solver] == "rk4":  # fixed steps: they fail only where the motion blows up
            assert outcome == "completed" or "non-finite" in message, (case, message)
        if outcome == "completed":
            assert t == pytest.approx(steps_per_case(h) * h)
            check_completed(core, solver, max_step, h, t, state)
        counts[outcome] += 1
    lattice.close()
    print(
        f"\n{backend}: {sum(counts.values())} cases, {dict(counts)}; slowest {slowest[0]:.2f} s {slowest[1]}"
    )
    assert counts["completed"] and counts["discarded"]


@pytest.mark.parametrize("backend", ["pythonfmu", "native"])
def test_every_tolerance_is_met_or_the_step_discarded(request, core, backend):
    """rtol from its floor (100 machine epsilons; below, it is refused) to 10, atol from 1e-300
    to 10: the adaptive solvers meet them, or discard the step with the diagnosis."""
    path = request.getfixturevalue("seed_fmu" if backend == "pythonfmu" else "native_seed_fmu")
    lattice = Lattice(path)
    adaptive = [k for k, name in enumerate(SOLVERS) if name != "rk4"]
    counts = Counter()
    for solver in adaptive:
        for rtol in (2.3e-14, 1e-9, 1e-3, 10.0):
            for atol in (1e-300, 1e-9, 10.0):
                for h in (1e-9, 0.01, 1.0):
                    for max_steps in (10, 10**6):
                        case = (SOLVERS[solver], rtol, atol, h, max_steps)
                        outcome, state, t, message, attempts = lattice.run(
                            solver, 0.0, max_steps, h, rtol, atol
                        )
                        check_case(case, outcome, message, attempts, max_steps)
                        if outcome == "completed":
                            check_completed(core, solver, 0.0, h, t, state, rtol, atol)
                        counts[outcome] += 1
    lattice.close()
    print(f"\n{backend}: {sum(counts.values())} cases, {dict(counts)}")
    assert counts["completed"] and counts["discarded"]
