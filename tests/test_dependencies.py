"""Every ModelStructure list names its dependencies, read from the model (builder.core.dependencies),
and they are the model's: a pair not listed has a zero derivative (the native FMU's exact
directional derivatives; differences of what initialization computes for the parameters),
and a listed pair is not zero at some random point."""

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from conftest import HOISTED_LINKS
from conical_pendulum import Link, Scene
from conical_pendulum.builder.core import dependencies
from conical_pendulum.builder.core.equations import derive
from fmu_helpers import INSTANCES, fmi3_names
from test_directional import Model, random_point

SCENES = {
    "seed": Scene.uniform(3),
    "coupled": Scene.uniform(3, coupling=True),
    "mixed": Scene(links=(Link(), Link(has_mass=False), Link(has_bob=False)), coupling=True),
    "recursive": Scene.uniform(7, coupling=True),
    # joint damping, the air's drag and a force on the middle bob: the energy's books as states
    "forced": Scene(
        links=(Link(damping=0.3), Link(damping=0.2, bob_force=True), Link(damping=0.1)),
        joint_damping=True,
        air_drag=True,
        coupling=True,
    ),
    "forced_recursive": Scene(
        links=(Link(damping=0.3),) * 3 + (Link(damping=0.1, bob_force=True),) + (Link(damping=0.2),) * 3,
        joint_damping=True,
        air_drag=True,
        coupling=True,
    ),
    "rope": Scene(links=HOISTED_LINKS, coupling=True),
    "rope_recursive": Scene(links=HOISTED_LINKS, coupling=True, formulation="recursive"),
}

# Listed pairs that are zero anyway: not by the expressions' structure but by the physics.
# The apparent mass along x does not change when the chain turns about the pivot's x axis.
CANCELLED = {
    "seed": [],
    "coupled": [("M_pivot_xx", "beta0")],
    "mixed": [("M_pivot_xx", "beta0")],
    "recursive": [("M_pivot_xx", "beta0")],
    "forced": [("M_pivot_xx", "beta0")],
    "forced_recursive": [("M_pivot_xx", "beta0")],
    "rope": [("M_pivot_xx", "beta0")],
    "rope_recursive": [("M_pivot_xx", "beta0")],
}


@pytest.mark.parametrize("name", ["seed", "coupled", "mixed", "forced"])
def test_the_chains_rule_is_what_the_expressions_say(name):
    """The recursive formulation's dependencies (no expressions to read) equal the expanded
    equations' free symbols wherever both formulations exist."""
    scene = SCENES[name]
    assert dependencies._chain(scene) == dependencies._symbolic(scene, derive(scene))


@pytest.mark.parametrize(
    "name", ["seed", "mixed", "recursive", "forced", "forced_recursive", "rope", "rope_recursive"]
)
def test_listed_pairs_are_not_zero_and_the_rest_are(built_fmu, name):
    """fmi2GetDirectionalDerivative at five random points: every pair the Outputs and
    Derivatives lists leave out is exactly zero at each, every listed pair nonzero at one."""
    scene = SCENES[name]
    model = Model(built_fmu(scene, backend="native"), scene)
    try:
        seen = np.zeros_like(model.depends)
        for seed in range(5):
            x, a = random_point(scene, seed)
            model.set(x, a)
            J = model.jacobian()
            np.testing.assert_array_equal(J[~model.depends], 0.0)
            seen |= np.abs(J) > 1e-12 * np.abs(J).max(axis=1, keepdims=True)  # beyond rounding
        names = {v.valueReference: v.name for v in model.md.modelVariables}
        never = [
            (names[model.unknowns[i]], names[model.knowns[k]])
            for i, k in zip(*np.nonzero(model.depends & ~seen))
        ]
        assert set(never) == set(CANCELLED[name]), never
    finally:
        model.close()


def _initial_values(path, version, values, unknowns):
    instance = INSTANCES[version](path, start_values=values)
    try:
        return np.array(instance.get(*unknowns), dtype=float)
    finally:
        instance.close()


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("name", ["coupled", "recursive"])
def test_initial_unknowns_answer_the_parameters_they_list(built_fmu, name, version):
    """What initialization computes, with each parameter and state start moved in turn: an
    initial unknown not listed as depending on it does not move at all (bit for bit), one
    listed does. Starts at a random point, where no dependency vanishes by symmetry."""
    scene = SCENES[name]
    path = built_fmu(scene, backend="native", fmi_version=version)
    md2 = read_model_description(str(built_fmu(scene, backend="native")))
    x, a = random_point(scene, 3)
    base = dict(zip(scene.state_names(), x)) | dict(zip(scene.input_names(), a))
    listed = {u.variable.name: {d.name for d in u.dependencies} for u in md2.initialUnknowns}
    unknowns = [n for n in listed if not n.startswith("n_")]  # the statistics: zero, of nothing
    assert not any(listed[n] for n in listed if n.startswith("n_"))
    start = _initial_values(path, version, base, unknowns)
    unmoved = []
    parameters = dict(zip(scene.parameter_names(), scene.parameter_defaults()))
    for known, value in (parameters | base).items():
        moved = _initial_values(path, version, base | {known: value * 1.1 + 0.1}, unknowns)
        for name_, before, after in zip(unknowns, start, moved):
            assert before == after or known in listed[name_], (name_, known)
            still = abs(after - before) <= 1e-12 * abs(before)  # rounding at most
            unmoved += [(name_, known)] if still and known in listed[name_] else []
    assert set(unmoved) == set(CANCELLED[name]), unmoved


@pytest.mark.parametrize("version", [2, 3])
def test_every_list_of_every_fmu_names_its_dependencies(built_fmu, built_cart, version):
    """No Unknown without its dependencies, in any list, and fmpy finds nothing wrong; the
    FMI 3.0 lists give an array the union of its elements' dependencies."""
    paths = [built_fmu(SCENES["coupled"], backend="native", fmi_version=version), built_cart(version)]
    fmi2_twin = built_fmu(SCENES["coupled"], backend="native")
    if version == 2:
        paths.append(built_fmu(SCENES["coupled"]))
    for path in paths:
        assert validate_fmu(str(path)) == []
        md = read_model_description(str(path))
        lists = [md.outputs, md.derivatives, md.initialUnknowns]
        assert all(u.dependencies is not None for unknowns in lists for u in unknowns), path
        assert md.initialUnknowns, path
    if version == 3:  # each array: the union of its elements' (the FMI 2.0 FMU's) dependencies
        elements, _ = fmi3_names(paths[0])
        whole = lambda name: elements[name][0] if name in elements else name  # noqa: E731
        for tag in ("outputs", "derivatives", "initialUnknowns"):
            union = {}
            for u in getattr(read_model_description(str(fmi2_twin)), tag):
                union.setdefault(whole(u.variable.name), set()).update(whole(d.name) for d in u.dependencies)
            listed = {
                u.variable.name: {d.name for d in u.dependencies}
                for u in getattr(read_model_description(str(paths[0])), tag)
            }
            assert listed == union, tag
