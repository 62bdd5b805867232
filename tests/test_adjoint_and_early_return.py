"""The model side of two FMI 3.0 features (issue 20, items 3 and 4), through the model contract
itself (tests/model_host.py: the native FMU's sources but its FMI glue, called by ctypes):

- model_adjoint_derivative: seed^T J for every pair the ModelStructure lists, the transpose of
  model_directional_derivative's J to rounding, both against central differences; unknown
  references and non-finite seeds refused, and the model goes on.
- model_do_step_early: a step that cannot complete keeps the state at the last good internal
  step and says its time, on the singular start, the too-many-steps case and a state that
  leaves what the model can represent mid-step (an RK4 stage on the joint singularity)."""

import math

import numpy as np
import pytest

from conical_pendulum import Link, Scene
from differences import assert_adjoint_and_directional_match_differences, bad_reference_cases, bisection
from model_host import MODEL_DISCARD, MODEL_OK, MODEL_REFUSED, Model, compile_model

SCENES = {
    "seed": Scene.uniform(3),  # expanded, no inputs
    "coupled": Scene.uniform(3, coupling=True),  # expanded, a_pivot inputs, F_pivot outputs
    "recursive": Scene.uniform(7, coupling=True),  # chain.c, with inputs
    "singular": Scene(links=(Link(), Link(has_mass=False))),  # a massless link with a bob
}


@pytest.fixture(scope="module")
def built(built_fmu, tmp_path_factory):
    """(FMU, model library) of a scene, built once."""
    folder, made = tmp_path_factory.mktemp("contract"), {}

    def get(name):
        if name not in made:
            fmu = built_fmu(SCENES[name], backend="native")
            made[name] = fmu, compile_model(fmu, folder / name)
        return made[name]

    return get


def model(built, name, start=None, integers=None):
    fmu, library = built(name)
    return Model(library, fmu, start, integers)


def random_point(m, seed):
    """Angles within +-1 rad, rates within +-2 rad/s, support accelerations within +-3 m/s^2."""
    rng = np.random.default_rng(seed)
    n = len(m.states) // 2
    return np.concatenate([rng.uniform(-1, 1, n), rng.uniform(-2, 2, n)]), rng.uniform(-3, 3, len(m.inputs))


def jacobians(m):
    """J by columns (a directional derivative per known) and J^T by rows (an adjoint per unknown)."""
    columns, rows = [], []
    for k in m.knowns:
        status, column = m.directional(m.unknowns, [k], [1.0])
        assert status == MODEL_OK
        columns.append(column)
    for u in m.unknowns:
        status, row = m.adjoint([u], m.knowns, [1.0])
        assert status == MODEL_OK
        rows.append(row)
    return np.array(columns).T, np.array(rows)


# ---- the adjoint ----------------------------------------------------------------------------


@pytest.mark.parametrize("scene", ["seed", "coupled", "recursive"])
@pytest.mark.parametrize("seed", range(3))
def test_the_adjoint_is_the_transpose_of_the_directional_derivative(built, scene, seed):
    """Row by row, the adjoint of a unit seed is the directional derivatives' row: the same
    complex evaluations, so equal bit for bit; for a random seed over every unknown and every
    known at once, seed^T J to 1e-14 of |seed|^T |J|. Pairs the ModelStructure leaves out are
    exactly zero in both."""
    m = model(built, scene)
    m.set_point(*random_point(m, seed))
    J, rows = jacobians(m)
    assert np.isfinite(J).all()
    np.testing.assert_array_equal(rows, J)
    np.testing.assert_array_equal(J[~m.depends], 0.0)
    w = np.random.default_rng(50 + seed).standard_normal(len(m.unknowns))
    status, sensitivity = m.adjoint(m.unknowns, m.knowns, w)
    assert status == MODEL_OK
    assert (np.abs(sensitivity - w @ J) <= 1e-14 * (np.abs(w) @ np.abs(J))).all()


@pytest.mark.parametrize("scene", ["coupled", "recursive"])
def test_both_agree_with_central_differences(built, scene):
    """seed^T J by the adjoint, and J v by the directional derivative, against Richardson-
    extrapolated central differences of the values (fmi2's test bound: 1e-8 of the largest
    entry), at a random state, inputs, seed and direction, along the states, the inputs and
    the parameters."""
    m = model(built, scene)
    x, a = random_point(m, 7)
    n, n_input = len(x), len(a)
    parameters = [m.vr[name] for name in SCENES[scene].parameter_names()]
    knowns = m.knowns + parameters  # a parameter is a known too
    p = np.array(m.get(*parameters))

    def values(point):
        m.set_point(point[:n], point[n : n + n_input])
        for vr, value in zip(parameters, point[n + n_input :]):
            m.set(vr, value, initialized=0)
        return m.values()

    m.set_point(x, a)
    assert_adjoint_and_directional_match_differences(
        values,
        lambda w: m.adjoint(m.unknowns, knowns, w)[1],
        lambda v: m.directional(m.unknowns, knowns, v)[1],
        np.concatenate([x, a, p]),
        len(m.unknowns),
    )


def test_bad_references_and_seeds_are_refused_and_the_model_goes_on(built):
    m = model(built, "coupled")
    x, a = random_point(m, 0)
    m.set_point(x, a)
    vr, der = m.vr, m.unknowns[0]
    before = bytes(m.data)
    _, expected = m.adjoint(m.unknowns, m.knowns, np.ones(len(m.unknowns)))
    cases = [
        *bad_reference_cases(vr, der),
        ([der], [vr["alpha0"]], [math.nan], "seed of der(alpha0) = nan: must be finite"),
        ([vr["energy"], der], [vr["alpha0"]], [0.0, -math.inf], "seed of der(alpha0) = -inf: must be finite"),
    ]
    for unknowns, knowns, seed, message in cases:
        assert m.adjoint(unknowns, knowns, seed)[0] == MODEL_REFUSED
        assert m.message.value.decode() == message
    assert bytes(m.data) == before
    status, again = m.adjoint(m.unknowns, m.knowns, np.ones(len(m.unknowns)))
    assert status == MODEL_OK
    np.testing.assert_array_equal(again, expected)
    # a state as unknown is its own value, a statistic depends on nothing
    n_rhs = vr["n_rhs"]
    status, sensitivity = m.adjoint(
        [vr["alpha1"], vr["alpha0"], n_rhs], [vr["alpha0"], vr["a_pivot_x"], vr["alpha1"]], [2.0, 5.0, 7.0]
    )
    assert status == MODEL_OK and list(sensitivity) == [5.0, 0.0, 2.0]
    # a parameter is a known: at rest and with the support still, x' is g times what it would
    # be at g = 1 (the forcing is gravity alone), so seed^T dx'/dg is seed^T x' / g exactly
    n = len(x) // 2
    m.set_point(np.concatenate([x[:n], np.zeros(n)]), np.zeros(len(a)))
    derivatives = [u for u in m.unknowns if m.name[u].startswith("der(")]
    w = np.random.default_rng(9).standard_normal(len(derivatives))
    status, (along_g,) = m.adjoint(derivatives, [vr["g"]], w)
    at_rest = m.values(derivatives) / m.get("g")[0]
    assert status == MODEL_OK
    assert abs(along_g - w @ at_rest) <= 1e-14 * (np.abs(w) @ np.abs(at_rest))


def test_a_singular_mass_matrix_is_discarded_never_nan(built):
    m = model(built, "singular", start={"alpha1": math.pi / 2, "beta1": 0.0})
    der = [u for u in m.unknowns if m.name[u].startswith("der(")]
    status, _ = m.adjoint(der, m.knowns, np.ones(len(der)))
    assert status == MODEL_DISCARD
    assert "singular mass matrix" in m.message.value.decode()
    # what does not need the accelerations is still defined there
    bob = [m.vr[n] for n in SCENES["singular"].output_names() if n.startswith("bob")]
    status, sensitivity = m.adjoint(bob, m.knowns, np.ones(len(bob)))
    assert status == MODEL_OK and np.isfinite(sensitivity).all()


# ---- early return ---------------------------------------------------------------------------


@pytest.mark.parametrize("solver", [0, 1, 2])
def test_the_singular_start_returns_at_once_and_a_shorter_step_fails_cleanly(built, solver):
    """Nothing can be integrated: the last successful time is the start, the state kept."""
    m = model(built, "singular", start={"alpha1": math.pi / 2, "beta1": 0.0}, integers={"solver": solver})
    x0 = m.state()
    for dt in (0.01, 1e-4):  # the master's shorter step from there
        status, reached, message = m.step(0.0, dt)
        assert (status, reached) == (MODEL_DISCARD, 0.0)
        assert "singular mass matrix" in message and message.endswith("The state is kept at t = 0 s.")
        np.testing.assert_array_equal(m.state(), x0)


@pytest.mark.parametrize("solver", [1, 2])
def test_too_many_steps_return_at_the_last_accepted_step(built, solver):
    """RK45 and DOP853 with max_steps = 10 over 100 s: the step stops after ten attempts, at
    the last accepted one; the state there is what the same solver gives over that interval
    without the limit (to its tolerance), the outputs are the state's, and a shorter step from
    there completes."""
    integers = {"solver": solver, "max_steps": 10}
    m = model(built, "seed", integers=integers)
    status, reached, message = m.step(0.0, 100.0)
    assert status == MODEL_DISCARD and "too many steps" in message
    assert 0.0 < reached < 100.0
    assert message.endswith(f"The state is kept at t = {reached:.9g} s.")
    n_steps, n_rejected = m.get("n_steps", "n_rejected")
    assert n_steps + n_rejected == 10 and n_steps >= 1
    x = m.state()
    assert np.isfinite(x).all()
    free = model(built, "seed", integers={"solver": solver, "max_steps": 10**6})
    assert free.step(0.0, reached)[0] == MODEL_OK
    x_free = free.state()
    assert (np.abs(x - x_free) <= 100 * (1e-8 + 1e-8 * np.abs(x_free))).all()
    outputs = [
        o.variable.valueReference
        for o in m.md.outputs
        if o.variable.name not in ("n_rhs", "n_steps", "n_rejected")
    ]
    check = model(built, "seed")
    check.set_point(x)
    np.testing.assert_array_equal(m.values(outputs), check.values(outputs))
    status, after, _ = m.step(reached, reached / 2)
    assert (status, after) == (MODEL_OK, reached + reached / 2)
    assert np.isfinite(m.state()).all()


def test_too_many_fixed_steps_are_refused_before_any_work(built):
    m = model(built, "seed", start={"max_step": 1e-3}, integers={"solver": 0, "max_steps": 10})
    x0 = m.state()
    status, reached, message = m.step(0.0, 1.0)
    assert (status, reached) == (MODEL_DISCARD, 0.0)
    assert "nothing was integrated" in message
    np.testing.assert_array_equal(m.state(), x0)
    assert m.get("n_rhs") == [0.0]
    assert m.step(0.0, 1e-2)[:2] == (MODEL_OK, 1e-2)  # ten steps of max_step


def rk4_step_onto_the_pole(built, start):
    """The RK4 step h from start after which the next step's second stage, y + h/2 x'(y),
    lies on alpha1 = pi/2 (the massless link along its parent's x axis), by bisection."""

    def miss(h):
        m = model(built, "singular", start={**start, "max_step": 0.0}, integers={"solver": 0})
        assert m.step(0.0, h)[0] == MODEL_OK
        alpha, rate = m.get("alpha1", "der(alpha1)")
        return alpha + 0.5 * h * rate - math.pi / 2

    return bisection(miss, 0.01, 0.06)


def test_a_state_leaving_the_model_mid_step_returns_at_the_last_good_substep(built):
    """RK4 in two substeps of h, the second's second stage on the joint singularity (a singular
    mass matrix: the two-angle joint cannot represent that orientation): the step returns at
    t + h with the state of the first substep, bit for bit that of a step of h alone, and a
    shorter step from there completes. Without early return, the state stays at t (FMI 2.0)."""
    start = {"alpha1": math.pi / 2 - 0.1, "omega1": 2.0}
    h = rk4_step_onto_the_pole(built, start)
    one = model(built, "singular", start={**start, "max_step": 0.0}, integers={"solver": 0})
    assert one.step(0.0, h)[0] == MODEL_OK
    m = model(built, "singular", start={**start, "max_step": h}, integers={"solver": 0})
    x0 = m.state()
    status, reached, message = m.step(0.0, 2 * h)
    assert (status, reached) == (MODEL_DISCARD, h)
    assert "singular mass matrix" in message and "link 1" in message
    assert message.endswith(f"The state is kept at t = {h:.9g} s.")
    np.testing.assert_array_equal(m.state(), one.state())
    assert m.get("n_steps", "n_rhs") == [1.0, 6.0]  # one substep, and two stages of the next
    outputs = [m.vr[n] for n in SCENES["singular"].output_names()]
    np.testing.assert_array_equal(m.values(outputs), one.values(outputs))
    status, after, _ = m.step(h, h / 4)
    assert (status, after) == (MODEL_OK, h + h / 4)
    assert np.isfinite(m.state()).all()
    fmi2 = model(built, "singular", start={**start, "max_step": h}, integers={"solver": 0})
    status, reached, message = fmi2.step(0.0, 2 * h, early=False)
    assert (status, reached) == (MODEL_DISCARD, 0.0)
    np.testing.assert_array_equal(fmi2.state(), x0)
    assert message.endswith("The state is kept at t = 0 s.")
