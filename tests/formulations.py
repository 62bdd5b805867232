"""The expanded and the recursive formulations of one scene compared at random points, as PyDy's
codegen compares its backends: the forces' scenes (test_forces.py) and the ropes' (test_ropes.py)."""

import numpy as np

from conical_pendulum import Scene
from conical_pendulum.builder.compiler import load_core


def assert_formulations_agree(links, options: dict, seed: int, input_range: float) -> list[tuple]:
    """M, F, x' (the books' and the ropes' lengths' rates too) and every output of both cores at
    five random states (the ropes' lengths 1 to 20 m, an elastic one's reach within 20 cm of its
    length), inputs in +-input_range and the ropes'
    accelerations in +-2 m/s2. Returns each point as (x, p, x', outputs) for the caller's checks."""
    cores = [load_core(Scene(links=links, formulation=f, **options)) for f in ("expanded", "recursive")]
    scene = Scene(links=links, **options)
    rng = np.random.default_rng(seed)
    points = []
    for _ in range(5):
        x = rng.uniform(-1, 1, len(scene.state_names()))
        for i in scene.ropes():
            x[scene.state_names().index(f"l{i}")] = rng.uniform(1.0, 20.0)
        names = scene.state_names()
        for i in scene.elastic_ropes():  # taut or slack by up to 20 cm
            x[names.index(f"r{i}")] = x[names.index(f"l{i}")] + rng.uniform(-0.2, 0.2)
        p = np.array(scene.parameters())
        p[len(scene.parameter_names()) :] = rng.uniform(-input_range, input_range, len(scene.input_names()))
        acc = rng.uniform(-2, 2, len(scene.ropes()))
        (me, fe), (mr, fr) = (core.mass_forcing(x, p, acc) for core in cores)
        np.testing.assert_allclose(mr, me, rtol=0, atol=1e-12 * np.abs(me).max())
        np.testing.assert_allclose(fr, fe, rtol=0, atol=1e-12 * np.abs(fe).max())
        de, dr = (core.rhs(x, p, acc) for core in cores)
        np.testing.assert_allclose(dr, de, rtol=1e-9, atol=1e-9)
        ye, yr = (core.outputs(x, p, acc) for core in cores)
        np.testing.assert_allclose(yr, ye, rtol=0, atol=1e-10 * np.abs(ye).max())
        points.append((x, p, de, ye))
    return points
