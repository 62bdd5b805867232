"""fmi3GetAdjointDerivative and early return from fmi3DoStep (issue 20, items 3 and 4) through
fmpy's FMI 3.0 low-level API, on the native FMI 3.0 FMU (runtime/csrc/fmi/fmi3_glue.c, on the model
contract's model_adjoint_derivative and model_do_step_early; tests/test_adjoint_and_early_return.py
tests those at the model level).

An array variable (alpha, der(alpha), bob_x, ...) stands for its n_links values, link by link."""

import math
from ctypes import byref, c_double

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import fmi3Boolean, fmi3Float64

from conical_pendulum import Link, Scene
from conical_pendulum.analysis.fmpy_runs import simulate_fmu
from conical_pendulum.runtime.rules import STATISTICS
from differences import assert_adjoint_and_directional_match_differences, bisection
from fmu_helpers import Instance3

OK, DISCARD, ERROR = 0, 2, 3
SCENES = {
    "coupled": Scene.uniform(3, coupling=True),  # a_pivot inputs, F_pivot outputs
    "singular": Scene(links=(Link(), Link(has_mass=False))),  # a massless link with a bob
}
STATE_ARRAYS = ("alpha", "beta", "omega", "delta")


@pytest.fixture(scope="module")
def fmus(built_fmu):
    return lambda name: built_fmu(SCENES[name], backend="native", fmi_version=3)


class Fmi3(Instance3):
    """One FMI 3.0 instance, initialized (in Model Exchange: in continuous-time mode); values set
    before initialization by the FMI 2.0 FMU's scalar names (alpha1: element 1 of the array alpha)."""

    def __init__(self, path, interface="CoSimulation", start=None, early_return_allowed=False):
        options = {"earlyReturnAllowed": early_return_allowed} if interface == "CoSimulation" else {}
        super().__init__(path, interface, start_values=start, **options)
        md = self.md
        self.n_links = int(next(v.start for v in md.modelVariables if v.name == "n_links"))
        self.size = {v.valueReference: self.n_links if v.dimensions else 1 for v in md.modelVariables}
        if interface == "ModelExchange":
            self.fmu.enterContinuousTimeMode()
        structure = list(md.derivatives) + list(md.outputs)
        self.unknowns = [u.variable.valueReference for u in structure]
        self.states = [self.vr[name] for name in STATE_ARRAYS]
        self.inputs = [v.valueReference for v in md.modelVariables if v.causality == "input"]
        self.knowns = self.states + self.inputs
        self.listed = {
            (u.variable.valueReference, d.valueReference) for u in structure for d in u.dependencies
        }

    def values(self, vrs):
        return np.array(self.fmu.getFloat64(vrs, nValues=sum(self.size[v] for v in vrs)))

    def count(self, vrs):
        return sum(self.size.get(v, 1) for v in vrs)

    def blocks(self, vrs):
        """Each value of vrs as (value reference, element index)."""
        return [(v, e) for v in vrs for e in range(self.size[v])]

    def directional(self, unknowns, knowns, seed):
        return np.array(
            self.fmu.getDirectionalDerivative(unknowns, knowns, list(seed), nSensitivity=self.count(unknowns))
        )

    def adjoint(self, unknowns, knowns, seed):
        return np.array(
            self.fmu.getAdjointDerivative(unknowns, knowns, list(seed), nSensitivity=self.count(knowns))
        )

    def jacobians(self):
        """J by columns (directional derivatives, a unit seed per known value) and by rows
        (adjoints, a unit seed per unknown value)."""
        columns = []
        for vr, e in self.blocks(self.knowns):
            columns.append(self.directional(self.unknowns, [vr], np.eye(self.size[vr])[e]))
        rows = []
        for vr, e in self.blocks(self.unknowns):
            rows.append(self.adjoint([vr], self.knowns, np.eye(self.size[vr])[e]))
        return np.array(columns).T, np.array(rows)

    def unlisted(self):
        """A mask of J's entries whose (unknown, known) pair the ModelStructure does not list."""
        return np.array(
            [
                [(u, k) not in self.listed for k, _ in self.blocks(self.knowns)]
                for u, _ in self.blocks(self.unknowns)
            ]
        )

    def set_point(self, x, a):
        n = len(x)
        self.fmu.setContinuousStates((c_double * n)(*x), n)
        if len(a):
            self.fmu.setFloat64(self.inputs, list(a))

    def unknown_values(self):
        n = self.count(self.states)
        dx = (c_double * n)()
        self.fmu.getContinuousStateDerivatives(dx, n)
        return np.concatenate([np.array(dx[:]), self.values(self.unknowns[len(self.states) :])])

    def state(self):
        return self.values(self.states)

    def do_step(self, t, dt):
        """The raw fmi3DoStep: (status, earlyReturn, lastSuccessfulTime); fmpy's doStep raises
        on fmi3Discard and loses the outputs."""
        event, terminate, early, last = fmi3Boolean(), fmi3Boolean(), fmi3Boolean(), fmi3Float64(-1.0)
        status = self.fmu.dll.fmi3DoStep(
            self.fmu.component,
            fmi3Float64(t),
            fmi3Float64(dt),
            fmi3Boolean(True),
            byref(event),
            byref(terminate),
            byref(early),
            byref(last),
        )
        assert not event.value and not terminate.value
        return status, bool(early.value), last.value

    def close(self):
        self.fmu.terminate()
        super().close()


def random_point(fmu, seed):
    """Angles within +-1 rad, rates within +-2 rad/s, support accelerations within +-3 m/s^2."""
    rng = np.random.default_rng(seed)
    n = fmu.count(fmu.states) // 2
    return np.concatenate([rng.uniform(-1, 1, n), rng.uniform(-2, 2, n)]), rng.uniform(-3, 3, len(fmu.inputs))


def test_the_model_description_says_it(fmus):
    md = read_model_description(str(fmus("coupled")))
    assert md.modelExchange.providesAdjointDerivatives and md.coSimulation.providesAdjointDerivatives
    assert md.coSimulation.mightReturnEarlyFromDoStep


@pytest.mark.parametrize("seed", range(3))
def test_the_adjoint_is_the_transpose_of_the_directional_derivative_in_model_exchange(fmus, seed):
    """Every pair the ModelStructure lists: the adjoint's rows are the directional derivatives'
    rows bit for bit (the same complex evaluations); a random seed over every unknown gives
    seed^T J to 1e-14 of |seed|^T |J|; what the ModelStructure leaves out is zero in both."""
    fmu = Fmi3(fmus("coupled"), "ModelExchange")
    fmu.set_point(*random_point(fmu, seed))
    J, rows = fmu.jacobians()
    assert np.isfinite(J).all()
    np.testing.assert_array_equal(rows, J)
    np.testing.assert_array_equal(J[fmu.unlisted()], 0.0)
    w = np.random.default_rng(50 + seed).standard_normal(fmu.count(fmu.unknowns))
    sensitivity = fmu.adjoint(fmu.unknowns, fmu.knowns, w)
    assert (np.abs(sensitivity - w @ J) <= 1e-14 * (np.abs(w) @ np.abs(J))).all()
    fmu.close()


def test_both_agree_with_central_differences(fmus):
    """seed^T J by the adjoint and J v by the directional derivative against Richardson-
    extrapolated central differences of fmi3GetContinuousStateDerivatives and fmi3GetFloat64."""
    fmu = Fmi3(fmus("coupled"), "ModelExchange")
    x, a = random_point(fmu, 7)
    n = len(x)

    def values(p):
        fmu.set_point(p[:n], p[n:])
        return fmu.unknown_values()

    fmu.set_point(x, a)
    assert_adjoint_and_directional_match_differences(
        values,
        lambda w: fmu.adjoint(fmu.unknowns, fmu.knowns, w),
        lambda v: fmu.directional(fmu.unknowns, fmu.knowns, v),
        np.concatenate([x, a]),
        fmu.count(fmu.unknowns),
    )
    fmu.close()


def test_co_simulation_in_step_mode_gives_the_same_numbers(fmus):
    """After steps (Step Mode), the Co-Simulation instance's J and J^T are the Model Exchange
    instance's at the same state and inputs, bit for bit."""
    cs = Fmi3(fmus("coupled"), start={"a_pivot_x": 1.5, "alpha1": 0.4})
    for _ in range(30):
        cs.fmu.doStep(currentCommunicationPoint=cs.time, communicationStepSize=1 / 60)
        cs.time += 1 / 60
    J_cs, rows_cs = cs.jacobians()
    me = Fmi3(fmus("coupled"), "ModelExchange")
    me.set_point(cs.state(), cs.values(cs.inputs))
    J_me, rows_me = me.jacobians()
    np.testing.assert_array_equal(J_cs, J_me)
    np.testing.assert_array_equal(rows_cs, rows_me)
    np.testing.assert_array_equal(rows_cs, J_cs)
    cs.close()
    me.close()


def test_bad_references_and_seeds_are_refused_and_the_instance_goes_on(fmus):
    fmu = Fmi3(fmus("coupled"), "ModelExchange")
    fmu.set_point(*random_point(fmu, 0))
    vr, der = fmu.vr, fmu.vr["der(alpha)"]
    w = np.ones(fmu.count(fmu.unknowns))
    expected = fmu.adjoint(fmu.unknowns, fmu.knowns, w)
    prefix = "fmi3GetAdjointDerivative: "
    unknown, known = (
        ": only outputs and state derivatives are",
        ": only states, inputs and Real parameters are",
    )
    cases = [
        ([vr["l"]], [vr["alpha"]], [1.0] * 3, f"value reference {vr['l']} (l0) as an unknown{unknown}"),
        ([vr["rtol"]], [vr["alpha"]], [1.0], f"value reference {vr['rtol']} (rtol) as an unknown{unknown}"),
        ([der], [vr["energy"]], [1.0] * 3, f"value reference {vr['energy']} (energy) as a known{known}"),
        ([der], [vr["bob_x"]], [1.0] * 3, f"value reference {vr['bob_x']} (bob0_x) as a known{known}"),
        ([10_000], [vr["alpha"]], [1.0], f"value reference 10000 (?) as an unknown{unknown}"),
        ([der], [10_000], [1.0] * 3, f"value reference 10000 (?) as a known{known}"),
        ([der], [vr["alpha"] + 1], [1.0] * 3, f"value reference {vr['alpha'] + 1} is not a variable"),
        ([der], [vr["alpha"]], [0.0, math.nan, 0.0], "seed of der(alpha1) = nan: must be finite"),
        ([der], [vr["alpha"]], [1.0], "nSeed = 1 and nSensitivity = 3, but the unknowns have 3 values"),
    ]
    for unknowns, knowns, seed, message in cases:
        fmu.messages.clear()
        with pytest.raises(FMICallException) as failure:
            fmu.fmu.getAdjointDerivative(unknowns, knowns, seed, nSensitivity=fmu.count(knowns))
        assert failure.value.status == ERROR
        assert fmu.texts(ERROR).startswith(prefix + message), fmu.messages
    np.testing.assert_array_equal(fmu.adjoint(fmu.unknowns, fmu.knowns, w), expected)
    # a parameter is a known: at rest and with the support still, x' is g times what it would
    # be at g = 1 (the forcing is gravity alone), so its partial along g is x' / g exactly,
    # directional and adjoint alike
    x, a = random_point(fmu, 0)
    n = len(x) // 2
    fmu.set_point(np.concatenate([x[:n], np.zeros(n)]), np.zeros(len(a)))
    derivatives = [vr[f"der({name})"] for name in STATE_ARRAYS]
    at_rest = fmu.values(derivatives) / fmu.values([vr["g"]])[0]
    np.testing.assert_allclose(fmu.directional(derivatives, [vr["g"]], [1.0]), at_rest, rtol=1e-14, atol=0)
    seed = np.random.default_rng(9).standard_normal(len(at_rest))
    (along_g,) = fmu.adjoint(derivatives, [vr["g"]], seed)
    assert abs(along_g - seed @ at_rest) <= 1e-14 * (np.abs(seed) @ np.abs(at_rest))
    fmu.close()


def test_a_singular_mass_matrix_is_discarded_never_nan(fmus):
    fmu = Fmi3(fmus("singular"), "ModelExchange", start={"alpha1": math.pi / 2, "beta1": 0.0})
    derivatives = [fmu.vr[f"der({name})"] for name in STATE_ARRAYS]
    with pytest.raises(FMICallException) as failure:
        fmu.adjoint(derivatives, fmu.knowns, np.ones(fmu.count(derivatives)))
    assert failure.value.status == DISCARD
    assert "singular mass matrix" in fmu.texts(DISCARD)
    bob = [fmu.vr[name] for name in ("bob_x", "bob_y", "bob_z")]
    assert np.isfinite(fmu.adjoint(bob, fmu.knowns, np.ones(fmu.count(bob)))).all()
    fmu.close()


# ---- early return -------------------------------------------------------------------------


def test_the_singular_start_is_discarded_at_once_and_a_shorter_step_too(fmus):
    """Nothing can be integrated: no early return (no point was reached), fmi3Discard with the
    instance at its start, lastSuccessfulTime = 0; a shorter step is discarded the same way and
    the instance goes on."""
    fmu = Fmi3(fmus("singular"), start={"alpha1": math.pi / 2, "beta1": 0.0}, early_return_allowed=True)
    x0 = fmu.state()
    for dt in (0.01, 1e-4):
        assert fmu.do_step(0.0, dt) == (DISCARD, False, 0.0)
        assert "singular mass matrix" in fmu.texts(DISCARD)
        np.testing.assert_array_equal(fmu.state(), x0)
        assert fmu.values([fmu.vr["time"]])[0] == 0.0
    fmu.close()


@pytest.mark.parametrize("solver", [1, 2])
def test_too_many_steps_return_early_at_the_last_accepted_step(fmus, solver):
    """max_steps = 10 over 100 s: fmi3OK with earlyReturn, lastSuccessfulTime the last accepted
    internal step, the state there what the solver gives over that interval without the limit,
    the diagnosis logged; a shorter step from there completes. Without earlyReturnAllowed the
    same step is fmi3Discard at the start, as FMI 2.0's fmi2Discard."""
    start = {"solver": solver, "max_steps": 10}
    fmu = Fmi3(fmus("coupled"), start=start, early_return_allowed=True)
    status, early, last = fmu.do_step(0.0, 100.0)
    assert (status, early) == (OK, True) and 0.0 < last < 100.0
    assert fmu.values([fmu.vr["time"]])[0] == last
    assert "fmi3DoStep returns early" in fmu.texts(OK) and "too many steps" in fmu.texts(OK)
    assert f"The state is kept at t = {last:.9g} s." in fmu.texts(OK)
    x = fmu.state()
    assert np.isfinite(x).all()
    free = Fmi3(fmus("coupled"), start={"solver": solver, "max_steps": 10**6})
    assert free.do_step(0.0, last) == (OK, False, last)
    x_free = free.state()
    assert (np.abs(x - x_free) <= 100 * (1e-8 + 1e-8 * np.abs(x_free))).all()
    assert fmu.do_step(last, last / 2) == (OK, False, last + last / 2)
    fmi2_like = Fmi3(fmus("coupled"), start=start)
    x0 = fmi2_like.state()
    assert fmi2_like.do_step(0.0, 100.0) == (DISCARD, False, 0.0)
    np.testing.assert_array_equal(fmi2_like.state(), x0)
    for instance in (fmu, free, fmi2_like):
        instance.close()


def test_fmpy_goes_on_from_each_early_return_to_the_end(fmus):
    """fmpy's simulate_fmu with early_return_allowed and max_steps = 10: every communication
    step of 1 s returns early and fmpy goes on from lastSuccessfulTime; the end state is that of
    a run without the limit, to the tolerance."""
    path, stop = fmus("coupled"), 3.0
    common = {"fmi_type": "CoSimulation", "stop_time": stop, "output_interval": 1.0, "output": ["alpha"]}
    limited = simulate_fmu(path, early_return_allowed=True, start_values={"max_steps": 10}, **common)
    free = simulate_fmu(path, **common)
    assert limited["time"][-1] == pytest.approx(stop) and free["time"][-1] == pytest.approx(stop)
    np.testing.assert_allclose(limited["alpha"][-1], free["alpha"][-1], rtol=0, atol=1e-6)


def rk4_step_onto_the_pole(fmus, start):
    """The RK4 step h from start after which the next step's second stage, y + h/2 x'(y), lies
    on alpha1 = pi/2 (the massless link along its parent's x axis), by bisection."""

    def miss(h):
        fmu = Fmi3(fmus("singular"), start={**start, "max_step": 0.0, "solver": 0})
        assert fmu.do_step(0.0, h)[0] == OK
        alpha, rate = fmu.values([fmu.vr["alpha"]])[1], fmu.values([fmu.vr["der(alpha)"]])[1]
        fmu.close()
        return alpha + 0.5 * h * rate - math.pi / 2

    return bisection(miss, 0.01, 0.06)


def test_a_state_leaving_the_model_mid_step_returns_early_at_the_last_good_substep(fmus):
    """RK4 in two substeps of h, the second's second stage on the joint singularity: fmi3OK with
    earlyReturn at t + h, the state that of one step of h bit for bit; a shorter step from there
    completes. Without earlyReturnAllowed: fmi3Discard at the start."""
    start = {"alpha1": math.pi / 2 - 0.1, "omega1": 2.0}
    h = rk4_step_onto_the_pole(fmus, start)
    one = Fmi3(fmus("singular"), start={**start, "max_step": 0.0, "solver": 0})
    assert one.do_step(0.0, h) == (OK, False, h)
    fmu = Fmi3(fmus("singular"), start={**start, "max_step": h, "solver": 0}, early_return_allowed=True)
    assert fmu.do_step(0.0, 2 * h) == (OK, True, h)
    assert "singular mass matrix" in fmu.texts(OK) and "link 1" in fmu.texts(OK)
    np.testing.assert_array_equal(fmu.state(), one.state())
    outputs = [u.variable.valueReference for u in fmu.md.outputs]
    counts = len(STATISTICS)
    np.testing.assert_array_equal(fmu.values(outputs)[:-counts], one.values(outputs)[:-counts])
    assert fmu.do_step(h, h / 4) == (OK, False, h + h / 4)
    assert np.isfinite(fmu.state()).all()
    fmi2_like = Fmi3(fmus("singular"), start={**start, "max_step": h, "solver": 0})
    x0 = fmi2_like.state()
    assert fmi2_like.do_step(0.0, 2 * h) == (DISCARD, False, 0.0)
    np.testing.assert_array_equal(fmi2_like.state(), x0)
    for instance in (one, fmu, fmi2_like):
        instance.close()
