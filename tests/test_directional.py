"""fmi2GetDirectionalDerivative of the native FMU (complex step of the model's own C) against
finite differences, at random states, in Model Exchange and Co-Simulation."""

import ctypes
import shutil

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model

from conftest import HOISTED_LINKS
from conical_pendulum import Link, Scene
from conical_pendulum.analysis.fmpy_runs import logging_callbacks
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.runtime.rules import STATISTICS
from differences import bad_reference_cases, richardson, ridders
from fmu_helpers import Instance

SCENES = {
    "seed": Scene.uniform(3),  # expanded, no inputs
    "coupled": Scene.uniform(3, coupling=True),  # expanded, a_pivot inputs
    "recursive": Scene.uniform(7, coupling=True),  # chain.c, with inputs
    # the joints' damping, the air's drag (inputs wind and v_pivot), forces on bobs, and the
    # energy's books (states after the rates), in both formulations
    "damped": Scene(
        links=(Link(damping=4.0, bob_force=True), Link(damping=2.0), Link(damping=1.0, bob_force=True)),
        joint_damping=True,
        air_drag=True,
        coupling=True,
    ),
    "damped_recursive": Scene(
        links=tuple(Link(damping=1.0, bob_force=i == 4) for i in range(7)),
        joint_damping=True,
        air_drag=True,
        coupling=True,
    ),
    "rope": Scene(links=HOISTED_LINKS, coupling=True),
    "rope_recursive": Scene(links=HOISTED_LINKS, coupling=True, formulation="recursive"),
}
SEEDS = range(5)


@pytest.fixture(scope="module")
def native(built_fmu):
    return lambda name: built_fmu(SCENES[name], backend="native")


def doubles(values):
    return (ctypes.c_double * len(values))(*values)


class Model:
    """A Model Exchange instance in continuous-time mode, with the ModelStructure's names."""

    def __init__(self, path, scene):
        self.md = read_model_description(str(path))
        self.scene = scene
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages = []
        self._callbacks = logging_callbacks(lambda status, text: self.messages.append((status, text)))
        self.unzipdir = extract(str(path))
        self.fmu = FMU2Model(
            guid=self.md.guid,
            unzipDirectory=self.unzipdir,
            modelIdentifier=self.md.modelExchange.modelIdentifier,
            instanceName="me",
        )
        self.fmu.instantiate(callbacks=self._callbacks, loggingOn=True)
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self.fmu.enterContinuousTimeMode()
        self.states = [self.vr[n] for n in scene.state_names()]
        self.inputs = [self.vr[n] for n in scene.input_names()]
        self.knowns = self.states + self.inputs
        # the unknowns: every state derivative and every output, with what the ModelStructure
        # says each depends on
        structure = list(self.md.derivatives) + list(self.md.outputs)
        self.unknowns = [u.variable.valueReference for u in structure]
        self.depends = np.array(
            [[k in {d.valueReference for d in u.dependencies} for k in self.knowns] for u in structure]
        )

    def set(self, x, a=()):
        self.fmu.setContinuousStates(doubles(x), len(x))
        if len(a):
            self.fmu.setReal(self.inputs, list(a))

    def values(self):
        """The unknowns' values: fmi2GetDerivatives, then fmi2GetReal of the outputs."""
        n = len(self.states)
        dx = doubles(np.zeros(n))
        self.fmu.getDerivatives(dx, n)
        return np.concatenate([np.array(dx[:]), self.fmu.getReal(self.unknowns[n:])])

    def jacobian(self):
        """Every column by fmi2GetDirectionalDerivative along a unit known."""
        return np.array([self.fmu.getDirectionalDerivative(self.unknowns, [k], [1.0]) for k in self.knowns]).T

    def central(self, x, a, h):
        """Central differences of values() with the absolute step h in each known."""
        point = np.concatenate([x, a])
        columns = []
        for k in range(len(point)):
            plus, minus = point.copy(), point.copy()
            plus[k] += h
            minus[k] -= h
            self.set(plus[: len(x)], plus[len(x) :])
            f_plus = self.values()
            self.set(minus[: len(x)], minus[len(x) :])
            columns.append((f_plus - self.values()) / (2 * h))
        self.set(x, a)
        return np.array(columns).T

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.unzipdir, ignore_errors=True)


def random_point(scene, seed):
    """Angles within +-1 rad, rates within +-2 rad/s, support accelerations within +-3 m/s^2,
    ropes' lengths within their ranges."""
    rng = np.random.default_rng(seed)
    n = 2 * scene.n
    x = np.concatenate([rng.uniform(-1, 1, n), rng.uniform(-2, 2, n)])
    inputs = rng.uniform(-3, 3, len(scene.input_names()))
    lengths = [rng.uniform(scene.links[i].rope_min, scene.links[i].rope_max) for i in scene.ropes()]
    return np.concatenate([x, rng.uniform(-5, 0, len(scene.work_names())), lengths]), inputs


@pytest.fixture(scope="module")
def models(native):
    made = {}

    def get(name):
        if name not in made:
            made[name] = Model(native(name), SCENES[name])
        return made[name]

    yield get
    for model in made.values():
        model.close()


@pytest.mark.parametrize("scene", list(SCENES))
@pytest.mark.parametrize("seed", SEEDS)
def test_every_listed_pair_matches_finite_differences(models, scene, seed):
    """The central difference D(h) = J + c h^2 + O(h^4) + rounding: at h = 4e-3 and 2e-3 its
    error must fall by 4 (the derivative is the limit D tends to, not something near it),
    and J must agree with the Richardson extrapolation (4 D(h) - D(2h)) / 3 = J + O(h^4)
    to its error, here about 1e-9 of the largest entry of the column (h^4 f^(5) ~ 1e-10,
    rounding 1e-16 |f| / h ~ 1e-13 relative). Pairs the ModelStructure does not list are
    exactly zero."""
    model = models(scene)
    x, a = random_point(SCENES[scene], seed)
    model.set(x, a)
    J = model.jacobian()
    assert np.isfinite(J).all()
    np.testing.assert_array_equal(J[~model.depends], 0.0)
    D1, D2 = model.central(x, a, 2e-3), model.central(x, a, 4e-3)
    scale = np.abs(J).max(axis=0)  # per known: the column's largest entry
    e1, e2 = np.abs(D1 - J).max(), np.abs(D2 - J).max()
    assert 3.5 < e2 / e1 < 4.5, (e1, e2)
    richardson = (4 * D1 - D2) / 3
    assert (np.abs(richardson - J) / scale).max() < 1e-8
    assert (np.abs(richardson - J) / scale).max() < 1e-3 * (np.abs(D1 - J) / scale).max()


@pytest.mark.parametrize("scene", list(SCENES))
def test_it_is_exact_where_finite_differences_are_not(models, scene):
    """Linearity: J v along a random direction of all knowns at once equals the sum of the
    single columns to 1e-13 of sum_k |J_ik v_k| (exact in the complex step up to rounding:
    measured up to 2e-14; the best central difference of the same values is some 1e-9 off)."""
    model = models(scene)
    for seed in SEEDS:
        x, a = random_point(SCENES[scene], seed)
        model.set(x, a)
        J = model.jacobian()
        v = np.random.default_rng(100 + seed).standard_normal(len(model.knowns))
        along = np.array(model.fmu.getDirectionalDerivative(model.unknowns, model.knowns, list(v)))
        bound = np.abs(J) @ np.abs(v)
        assert (np.abs(along - J @ v) <= 1e-13 * bound).all()


@pytest.mark.parametrize("scene", ["coupled", "recursive", "damped"])
def test_it_agrees_with_differences_of_the_compiled_core(models, scene):
    """An independent path: Richardson-extrapolated central differences of the Cython core's
    rhs and outputs (no FMI glue, parameters and inputs in p as the core orders them)."""
    model = models(scene)
    core = load_core(SCENES[scene])
    names = SCENES[scene].core_parameter_names()
    x, a = random_point(SCENES[scene], 7)
    model.set(x, a)
    p = np.array(model.fmu.getReal([model.vr[n] for n in names]))
    J = model.jacobian()
    n, k_input = len(x), len(names) - len(a)

    def f(point):
        q = p.copy()
        q[k_input:] = point[n:]
        return np.concatenate([core.rhs(point[:n], q), core.outputs(point[:n], q)])

    point = np.concatenate([x, a])
    n_unknown = len(model.unknowns)
    columns = []
    for k in range(len(point)):

        def central(h):
            e = np.zeros_like(point)
            e[k] = h
            return (f(point + e) - f(point - e)) / (2 * h)

        columns.append((4 * central(1e-3) - central(2e-3)) / 3)
    FD = np.array(columns).T
    # the FMU's unknowns: derivatives, then states (their own values), the calculated outputs
    # and the statistics; the core gives the derivatives and the calculated outputs
    rows = list(range(n)) + list(range(2 * n, 2 * n + core.NOUTPUT))
    assert len(rows) == len(FD) and n_unknown == 2 * n + core.NOUTPUT + len(STATISTICS)
    scale = np.abs(J).max(axis=0)
    assert (np.abs(J[rows] - FD) / scale).max() < 1e-8


@pytest.mark.parametrize("scene", list(SCENES))
def test_parameters_are_knowns_of_the_initial_unknowns(native, scene):
    """FMI 2.0's knowns in initialization mode (OMSimulator asks for them there, to start an
    algebraic loop between FMUs): every Real parameter, the settings too. Where a parameter
    may still be set, its column equals Richardson differences of the FMU's own values with
    it moved by 2e-2 to 1e-3 of itself (differences.ridders), to 1e-8 of the column's largest entry; the pairs the
    InitialUnknowns leave out are exactly zero (a setting's whole column), each listed pair
    nonzero at this point. Parameters 20 % off their equal starts: no partial vanishes by
    symmetry."""
    chosen = SCENES[scene]
    fmu = Instance(native(scene), name="init", initialize=False)
    fmu.fmu.setupExperiment(startTime=0.0)
    fmu.fmu.enterInitializationMode()
    x, a = random_point(chosen, 2)
    rng = np.random.default_rng(3)
    fmu.set(dict(zip(chosen.parameter_names(), np.array(chosen.parameters()) * rng.uniform(0.8, 1.2))))
    fmu.set(dict(zip(chosen.state_names() + chosen.input_names(), np.concatenate([x, a]))))
    md = fmu.md
    parameters = [v.name for v in md.modelVariables if v.causality == "parameter" and v.type == "Real"]
    assert {"g", chosen.parameter_names()[0], "rtol"} <= set(parameters)  # l0 (a rope's: m0)
    unknowns = [u.variable.valueReference for u in md.initialUnknowns]
    listed = np.array(
        [
            [fmu.vr[p] in {d.valueReference for d in u.dependencies} for p in parameters]
            for u in md.initialUnknowns
        ]
    )
    J = np.array([fmu.fmu.getDirectionalDerivative(unknowns, [fmu.vr[p]], [1.0]) for p in parameters]).T
    np.testing.assert_array_equal(J[~listed], 0.0)
    assert (np.abs(J[listed]) > 0).all()
    for k, name in enumerate(parameters):
        if not listed[:, k].any():
            continue  # a setting: its column is all zero (above)
        (start,) = fmu.get(name)

        def values(p, name=name):
            fmu.set({name: p[0]})
            return np.array(fmu.fmu.getReal(unknowns))

        # the step by Ridders' choice: a column as small as Iyy0's (a link's inertia about its
        # own axis) beside forces of a thousand newtons needs a step whose rounding is small,
        # C_d0's one whose truncation is
        derivative = ridders(values, np.array([start]), np.array([start])) / start
        values([start])
        assert np.abs(derivative - J[:, k]).max() < 1e-8 * np.abs(J[:, k]).max(), name
    fmu.fmu.exitInitializationMode()
    fmu.close()


def test_co_simulation_gives_them_too(native, models):
    """In a Co-Simulation instance: outputs with respect to states (set in initialization
    mode, where a Co-Simulation state may be set) and inputs by central differences; after
    steps, the same numbers as a Model Exchange instance at the same state and inputs."""
    path, scene = native("coupled"), SCENES["coupled"]
    fmu = Instance(path, name="cs", initialize=False)
    x, a = random_point(scene, 3)
    states, inputs = scene.state_names(), scene.input_names()
    fmu.fmu.setupExperiment(startTime=0.0)
    fmu.fmu.enterInitializationMode()
    fmu.set(dict(zip(states + inputs, np.concatenate([x, a]))))
    outputs = [fmu.vr[n] for n in scene.output_names()]
    knowns = [fmu.vr[n] for n in states + inputs]
    J = np.array([fmu.fmu.getDirectionalDerivative(outputs, [k], [1.0]) for k in knowns]).T
    point = np.concatenate([x, a])

    def outputs_at(p):
        fmu.fmu.setReal(knowns, list(p))
        return np.array(fmu.fmu.getReal(outputs))

    for k, direction in enumerate(np.eye(len(point))):
        derivative = richardson(outputs_at, point, direction)
        assert np.abs(derivative - J[:, k]).max() < 1e-8 * max(np.abs(J[:, k]).max(), 1.0), k
    outputs_at(point)
    fmu.fmu.exitInitializationMode()
    for _ in range(30):
        fmu.step(1 / 60)
    x_now = np.array(fmu.get(*states))
    J_cs = np.array([fmu.fmu.getDirectionalDerivative(outputs, [k], [1.0]) for k in knowns]).T
    model = models("coupled")
    model.set(x_now, a)
    J_me = np.array(
        [model.fmu.getDirectionalDerivative(outputs, [model.vr[n]], [1.0]) for n in states + inputs]
    ).T
    np.testing.assert_array_equal(J_cs, J_me)
    fmu.close()


def test_bad_references_are_errors_naming_them_and_the_instance_goes_on(native, models):
    model = models("coupled")
    vr = model.vr
    der = model.unknowns[0]
    cases = [
        *bad_reference_cases(vr, der),
        ([der], [vr["alpha0"]], [float("nan")], "dvKnown of alpha0 = nan: must be finite"),
    ]
    for unknowns, knowns, seed, message in cases:
        model.messages.clear()
        with pytest.raises(FMICallException) as failure:
            model.fmu.getDirectionalDerivative(unknowns, knowns, seed)
        assert failure.value.status == 3  # fmi2Error
        assert model.messages == [(3, "fmi2GetDirectionalDerivative: " + message)]
    # a parameter is a known: at rest and with the support still, x' is g times what it would
    # be at g = 1 (the forcing is gravity alone), so its partial along g is x' / g exactly
    x, a = random_point(SCENES["coupled"], 0)
    n = len(x) // 2
    model.set(np.concatenate([x[:n], np.zeros(n)]), np.zeros(len(a)))
    derivatives = model.unknowns[: len(x)]
    along_g = np.array(model.fmu.getDirectionalDerivative(derivatives, [vr["g"]], [1.0]))
    at_rest = model.values()[: len(x)] / model.fmu.getReal([vr["g"]])[0]
    assert np.abs(at_rest[n:]).min() > 1e-3
    np.testing.assert_allclose(along_g, at_rest, rtol=1e-14, atol=0)
    model.set(x, a)
    assert np.isfinite(model.jacobian()).all()
    # a state as unknown is its own value: the identity; a statistic depends on nothing
    n_rhs = vr["n_rhs"]
    assert model.fmu.getDirectionalDerivative(
        [vr["alpha1"], vr["alpha0"], n_rhs], [vr["alpha0"], vr["a_pivot_x"]], [2.0, 5.0]
    ) == [0.0, 2.0, 0.0]


def test_a_singular_mass_matrix_is_discarded_with_the_diagnosis_never_nan(built_fmu):
    """The singular joint of test_native: a massless link along its parent's x axis."""
    scene = Scene(links=(Link(), Link(has_mass=False)))
    path = built_fmu(scene, backend="native")
    model = Model(path, scene)
    x = np.zeros(len(scene.state_names()))
    x[scene.state_names().index("alpha1")] = np.pi / 2
    model.set(x)
    with pytest.raises(FMICallException) as failure:
        model.fmu.getDirectionalDerivative(model.unknowns[: len(x)], [model.states[0]], [1.0])
    assert failure.value.status == 2  # fmi2Discard, as fmi2GetDerivatives
    assert any(status == 2 and "singular mass matrix" in text for status, text in model.messages)
    # what does not need the accelerations is still defined there
    bob = [model.vr[n] for n in scene.output_names() if n.startswith("bob")]
    assert np.isfinite(model.fmu.getDirectionalDerivative(bob, [model.states[0]], [1.0])).all()
    model.close()


def test_the_model_description_promises_them(native):
    md = read_model_description(str(native("recursive")))
    assert md.modelExchange.providesDirectionalDerivative
    assert md.coSimulation.providesDirectionalDerivative
    n = len(md.derivatives) // 2
    for k, unknown in enumerate(md.derivatives):  # an angle's derivative is its rate
        names = [d.name for d in unknown.dependencies]
        if k < n:
            assert names == [md.derivatives[n + k].variable.derivative.name]
        else:
            assert len(names) == 2 * n + 3
