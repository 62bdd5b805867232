"""The pivot force's split, F_pivot = F_free - M_app a_pivot: the chain's apparent mass at the
pivot and the force at rest (issue 14)."""

import numpy as np
import pytest

from conical_pendulum import Link, Scene
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.builder.core.equations import joint_kinematics
from conical_pendulum.scene import APPARENT_MASS, FREE_FORCE, PIVOT_OUTPUTS
from fmu_helpers import Instance

AXES = "xyz"


def matrix(values: dict) -> np.ndarray:
    """The symmetric 3x3 M_app from the six M_pivot_ij outputs."""
    M = np.zeros((3, 3))
    for name in APPARENT_MASS:
        r, c = (AXES.index(axis) for axis in name[-2:])
        M[r, c] = M[c, r] = values[name]
    return M


@pytest.mark.parametrize("formulation", ["expanded", "recursive"])
def test_one_rigid_link_by_hand(formulation):
    """m I - m^2 [c]x E (E^T I_O E)^-1 E^T [c]x^T: the link's mass, its inertia about the
    pivot I_O, its centre c, and E, the joint's two axes (it cannot spin about a third)."""
    scene = Scene(links=(Link(has_bob=False),), coupling=True, formulation=formulation)
    core = load_core(scene)
    a, b, dcm, jac = joint_kinematics()
    rng = np.random.default_rng(3)
    for _ in range(5):
        x = rng.uniform(-1.2, 1.2, 4)
        p = scene.parameters({"a_pivot_x": 0.3, "a_pivot_z": -2.0})
        M = matrix(dict(zip(scene.output_names(), core.outputs(x, p))))
        link = scene.links[0]
        R = np.array(dcm.subs({a: x[0], b: x[1]}), float)
        E = np.array(jac.subs({a: x[0], b: x[1]}), float)
        c = -link.length / 2 * R[:, 1]
        inertia = R @ np.diag(link.inertia()) @ R.T + link.mass * (c @ c * np.eye(3) - np.outer(c, c))
        cx = np.array([[0, -c[2], c[1]], [c[2], 0, -c[0]], [-c[1], c[0], 0]])
        by_hand = link.mass * np.eye(3) - link.mass**2 * cx @ E @ np.linalg.solve(
            E.T @ inertia @ E, E.T @ cx.T
        )
        np.testing.assert_allclose(M, by_hand, rtol=0, atol=1e-12 * link.mass)


@pytest.mark.parametrize("backend", ["pythonfmu", "native"])
def test_it_is_the_pivot_forces_answer_to_the_inputs_through_fmpy(backend, built_fmu):
    """Finite differences of F_pivot over the inputs, through fmpy: exact, F_pivot being
    affine; F_free is the force at a_pivot = 0, the same whatever the inputs. M_app is
    computed without differences (m I - P M^-1 P^T, or the articulated inertia at the
    pivot), so this checks it independently."""
    path = built_fmu(Scene.uniform(3, coupling=True), backend=backend)
    fmu = Instance(path, start_values={"alpha1": 0.7, "delta2": 1.5, "omega0": -0.4})
    for _ in range(30):
        fmu.step(1 / 60)
    base = {"a_pivot_x": 0.2, "a_pivot_y": -1.0, "a_pivot_z": 0.5}
    fmu.set(base)
    force, free = np.array(fmu.get(*PIVOT_OUTPUTS)), np.array(fmu.get(*FREE_FORCE))
    M = matrix(dict(zip(APPARENT_MASS, fmu.get(*APPARENT_MASS))))
    a = np.array(list(base.values()))
    np.testing.assert_allclose(force, free - M @ a, rtol=0, atol=1e-10 * np.abs(force).max())
    for j, axis in enumerate(AXES):
        fmu.set({**base, f"a_pivot_{axis}": base[f"a_pivot_{axis}"] + 0.5})
        column = (force - np.array(fmu.get(*PIVOT_OUTPUTS))) / 0.5
        np.testing.assert_allclose(column, M[:, j], rtol=1e-10, atol=1e-10 * np.abs(M).max())
        assert fmu.get(*FREE_FORCE) == list(free)  # not a function of the inputs
    fmu.close()


def test_symmetric_and_positive_semidefinite_along_a_tumbling_trajectory(coupled_fmu):
    run = run_fmu(
        coupled_fmu,
        stop_time=5.0,
        output_interval=0.1,
        start_values={
            "alpha0": 1.2,
            "beta1": -1.0,
            "omega2": 3.0,
            "delta0": 2.0,
            "a_pivot_x": 1.5,
            "solver": 2,
        },
    )
    scene = Scene.uniform(3, coupling=True)
    core = load_core(scene)
    total = 3 * (10.0 + 5.0)
    for k in range(len(run)):
        M = matrix({name: run[name][k] for name in APPARENT_MASS})
        eigenvalues = np.linalg.eigvalsh(M)
        assert eigenvalues.min() >= -1e-9 * total and eigenvalues.max() <= total * (1 + 1e-12)
        # the unsymmetrized differences of the core's own pivot force are symmetric too
        x = [run[name][k] for name in scene.state_names()]
        forces = [
            core.outputs(x, scene.parameters({f"a_pivot_{axis}": 1.0} if axis else {}))[
                [scene.output_names().index(name) for name in PIVOT_OUTPUTS]
            ]
            for axis in ("",) + tuple(AXES)
        ]
        full = np.column_stack([forces[0] - f for f in forces[1:]])
        np.testing.assert_allclose(full, full.T, rtol=0, atol=1e-10 * total)
        np.testing.assert_allclose(full, M, rtol=0, atol=1e-10 * total)
