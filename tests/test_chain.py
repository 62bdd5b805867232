"""Long chains: the recursive formulation (articulated bodies, runtime/csrc/core/chain.c) against the
expanded equations (themselves checked against sympy's KanesMethod), and at 20 to 100 links."""

import numpy as np
import pytest

from conical_pendulum import Link, Scene, SceneError
from conical_pendulum.analysis.compare import compare
from conical_pendulum.analysis.simulate import simulate
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.scene import MAX_LINKS, RECURSIVE_FROM

VARIANTS = {
    "links and bobs": lambda n: Scene.uniform(n),
    "massless links": lambda n: Scene.uniform(n, massless_links=True),
    "no bobs": lambda n: Scene.uniform(n, bobs=False),
    "coupling": lambda n: Scene.uniform(n, coupling=True),
    "state only": lambda n: Scene.uniform(n, outputs=()),
    "mixed": lambda n: Scene(
        links=tuple(
            [Link(has_mass=False), Link(has_bob=False, moments=(2.0, 0.3, 1.5)), Link(length=3.0)][k % 3]
            for k in range(n - 1)
        )
        + (Link(),),
        coupling=n % 2 == 0,
    ),
}


def both(scene):
    """The scene in each formulation."""
    fields = {**scene.__dict__, "links": scene.links}
    return (Scene(**{**fields, "formulation": "expanded"}), Scene(**{**fields, "formulation": "recursive"}))


@pytest.mark.parametrize("variant", list(VARIANTS))
@pytest.mark.parametrize("n", range(1, 7))
def test_the_recursive_formulation_equals_the_expanded_one(variant, n):
    expanded, recursive = both(VARIANTS[variant](n))
    cores = load_core(expanded), load_core(recursive)
    rng = np.random.default_rng(n)
    for _ in range(5):
        x = rng.uniform(-1.5, 1.5, 4 * n)
        p = np.array(expanded.parameters()) * rng.uniform(0.5, 2.0, len(expanded.core_parameter_names()))
        if expanded.coupling:
            p[-3:] = rng.uniform(-5.0, 5.0, 3)
        (M1, F1), (M2, F2) = (core.mass_forcing(x, p) for core in cores)
        np.testing.assert_allclose(M2, M1, rtol=0, atol=1e-12 * np.abs(M1).max())
        np.testing.assert_allclose(F2, F1, rtol=0, atol=1e-12 * np.abs(F1).max())
        # x' (and the pivot force, from it) solve M u' = F: no method can agree on them to
        # better than cond(M) times the rounding, and massless links give cond(M) ~ 1e6
        solved = max(1e-12, 1e-16 * np.linalg.cond(M1))
        rates = [core.rhs(x, p) for core in cores]
        np.testing.assert_allclose(rates[1], rates[0], rtol=0, atol=solved * np.abs(rates[0]).max())
        outputs = [core.outputs(x, p) for core in cores]
        if outputs[0].size:
            np.testing.assert_allclose(
                outputs[1], outputs[0], rtol=0, atol=solved * max(1.0, np.abs(outputs[0]).max())
            )


def test_auto_chooses_by_the_measured_crossover():
    assert Scene.uniform(RECURSIVE_FROM - 1).resolved_formulation() == "expanded"
    assert Scene.uniform(RECURSIVE_FROM).resolved_formulation() == "recursive"
    assert Scene.uniform(4, kinematics="pydy-example").resolved_formulation() == "expanded"
    assert Scene.uniform(MAX_LINKS).n == 100


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: Scene.uniform(MAX_LINKS + 1), "out of range"),
        (lambda: Scene.uniform(21, formulation="expanded"), "offered up to 20 links"),
        (lambda: Scene.uniform(2, formulation="fast"), "formulation: 'fast' is not one of"),
        (
            lambda: Scene.uniform(2, kinematics="pydy-example", formulation="recursive"),
            "published equations exist only expanded",
        ),
    ],
)
def test_bad_formulations_are_named(make, message):
    with pytest.raises(SceneError, match=message):
        make()


def test_energy_is_conserved_at_50_links():
    scene = Scene.uniform(50, outputs=("energy",))
    state = {f"alpha{i}": 0.3 * np.sin(i) for i in range(50)} | {f"delta{i}": 0.1 for i in range(0, 50, 7)}
    result = simulate(scene, np.linspace(0.0, 2.0, 21), state=state, method="core", rtol=1e-11, atol=1e-11)
    energy = result["energy"]
    assert np.all(np.isfinite(result.states))
    assert np.abs(energy - energy[0]).max() <= 1e-8 * np.abs(energy).max()


@pytest.mark.parametrize("n", [20, 50])
def test_long_chain_fmus_match_the_native_reference(n, built_fmu):
    scene = Scene.uniform(n, outputs=("bobs", "energy"))
    path = built_fmu(scene)
    comparison = compare(path, scene, stop_time=1.0, start_values={"alpha0": 0.3, "delta3": 0.2})
    assert comparison.angle_error() < 1e-8
    energy = comparison.result["energy"]
    assert np.abs(energy - energy[0]).max() <= 1e-9 * np.abs(energy).max()
