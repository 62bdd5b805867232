"""kinematics="pydy-example" reproduces the seed's own pipeline, number for number."""

import numpy as np

from conical_pendulum import Scene
from conical_pendulum.builder.compiler import load_core
from references.seed_pipeline import seed_right_hand_side


def test_pydy_example_equals_the_seed_pipeline():
    scene = Scene.uniform(3, kinematics="pydy-example")
    assert scene.parameter_names()[:3] == ["l0", "l1", "l2"]  # the seed's parameter order
    core = load_core(scene)
    seed_rhs, _ = seed_right_hand_side()
    rng = np.random.default_rng(42)
    defaults = np.array(scene.parameter_defaults())
    for _ in range(100):
        x = rng.uniform(-1.5, 1.5, 12)
        p = defaults * rng.uniform(0.5, 2.0, defaults.size)
        expected = seed_rhs(x, 0.0, p)
        got = core.rhs(x, p)
        assert np.abs(got - expected).max() <= 1e-10 * np.abs(expected).max()
