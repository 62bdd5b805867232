"""The implicit solver's Jacobian (directional.h's cp_jacobian) against complex steps of the whole
right-hand side (cp_directional, what the FMUs' directional derivatives take), column by column.

The recursive formulation computes its columns otherwise (chain.c's chain_jacobian: inverse
dynamics from the link a state moves, then M^-1 through the articulated-body factorization), so
every option that formulation has is here: the joints' damping, the air's drag with wind and a
moving support, forces on bobs, the energy's books, hoisted ropes and their winches, an elastic
rope (slack and taut) under a load on a sling; and a chain of light links, the long stiff
chains' case. Both paths are exact but for rounding, and both end in a solve with the mass
matrix M, whose rounding a backward-stable solve amplifies up to cond(M): at random states they
agree to eps cond_2(M) of each column's largest entry (measured: 0.03 to 0.18 of it where M is
as ill-conditioned as the light chain's, 1e5; some 2e-16 of the column elsewhere).
"""

import dataclasses
import os

import numpy as np
import pytest

from conftest import HOISTED_LINKS
from conical_pendulum import Link, Scene
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.scene import load_scene
from test_stiff import light_chain

CRANE_ELASTIC = load_scene(os.path.join(os.path.dirname(__file__), "..", "scenes", "crane_elastic.toml"))
SCENES = {
    "damping, drag, wind, forces, moving support, books": Scene(
        links=tuple(Link(damping=1.0, bob_force=i == 4) for i in range(7)),
        joint_damping=True,
        air_drag=True,
        coupling=True,
    ),
    "hoisted rope, winch": Scene(links=HOISTED_LINKS, coupling=True, formulation="recursive"),
    "elastic rope, load": dataclasses.replace(CRANE_ELASTIC, formulation="recursive"),
    "expanded (its own columns)": Scene.uniform(3, coupling=True),
    "light chain, 12 links": light_chain(12),
}
SEEDS = range(3)


def random_state(scene, core, rng, taut):
    """Angles within +-1 rad, rates within +-2 rad/s, books within -5..0, ropes' lengths in their
    ranges; an elastic rope's reach past its length (taut) or short of it (slack)."""
    x = np.concatenate([rng.uniform(-1, 1, core.NDOF), rng.uniform(-2, 2, core.NDOF)])
    x = np.concatenate([x, rng.uniform(-5, 0, len(scene.work_names()))])
    names = list(core.STATE_NAMES)
    for i in scene.ropes():
        link = scene.links[i]
        length = rng.uniform(link.rope_min, link.rope_max)
        x = np.append(x, length)
        if f"r{i}" in names:
            x[names.index(f"r{i}")] = length * (1.01 if taut else 0.99)
    assert len(x) == core.NSTATE
    return x


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("name", SCENES)
def test_the_jacobian_is_the_complex_step_of_the_right_hand_side(name, seed):
    scene = SCENES[name]
    core = load_core(scene)
    rng = np.random.default_rng(seed)
    x = random_state(scene, core, rng, taut=seed % 2 == 0)
    p = np.array(scene.parameters({}))
    p[core.NPARAM - core.NINPUT :] = rng.uniform(-3, 3, core.NINPUT)
    J = core.jacobian(x, p)
    columns = np.array([core.directional(x, p, seed) for seed in np.eye(core.NSTATE)]).T
    assert np.isfinite(J).all()
    scale = np.abs(columns).max(axis=0)
    zero = scale == 0  # the books' columns: nothing depends on them
    np.testing.assert_array_equal(J[:, zero], 0.0)
    M, _ = core.mass_forcing(x, p)
    assert (np.abs(J - columns)[:, ~zero] / scale[~zero]).max() <= np.finfo(float).eps * np.linalg.cond(M)


def test_a_singular_mass_matrix_is_refused_as_the_right_hand_side_refuses_it():
    """Where cp_rhs finds M singular (test_directional's joint: a massless link along its
    parent's x axis), so does the Jacobian, with the same diagnosis."""
    scene = Scene(links=(Link(), Link(has_mass=False)), formulation="recursive")
    core = load_core(scene)
    p = np.array(scene.parameters({}))
    x = np.zeros(core.NSTATE)
    x[list(core.STATE_NAMES).index("alpha1")] = np.pi / 2
    with pytest.raises(core.CoreError) as rhs:
        core.rhs(x, p)
    with pytest.raises(core.CoreError) as jacobian:
        core.jacobian(x, p)
    assert (jacobian.value.status, jacobian.value.dof) == (rhs.value.status, rhs.value.dof)
    assert jacobian.value.status == core.SINGULAR
