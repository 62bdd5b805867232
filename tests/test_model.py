"""The equations: physically right, equal to sympy's KanesMethod, compiled faithfully."""

import numpy as np
import pytest
import sympy as sm

from conical_pendulum import Link, Scene, SceneError
from conical_pendulum.analysis.simulate import simulate
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.builder.core.equations import derive
from conical_pendulum.builder.core.kane import kanes_method
from conical_pendulum.runtime.rules import BadValue

SEED_TIMES = np.linspace(0.0, 10.0, 601)  # the seed's 10 s at 60 samples per second
MIXED = Scene(links=(Link(has_mass=False), Link(has_bob=False), Link()))
COUPLED = Scene.uniform(2, coupling=True)
# every force at once: damping, the air's drag (with the pivot's velocity), forces on a bob
FORCED = Scene(
    links=(Link(damping=2.0, bob_area=1.5), Link(damping=1.0, has_mass=False, bob_force=True)),
    joint_damping=True,
    air_drag=True,
    coupling=True,
)


def random_points(scene, count, seed=0):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        x = rng.uniform(-2.0, 2.0, 4 * scene.n)
        p = np.array(scene.parameter_defaults()) * rng.uniform(0.5, 2.0, len(scene.parameter_names()))
        inputs = rng.uniform(-5.0, 5.0, len(scene.input_names()))  # a moving pivot
        yield x, np.concatenate([p, inputs])


def relative_error(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.abs(a - b).max() / np.abs(b).max()


@pytest.mark.parametrize(
    "scene",
    [Scene.uniform(1), Scene.uniform(2), Scene.uniform(3), MIXED, COUPLED, FORCED],
    ids=["n1", "n2", "n3", "mixed", "moving-pivot", "forces"],
)
def test_derivation_equals_sympy_kanes_method(scene):
    eqs = derive(scene)
    mass, forcing, _ = eqs.lambdify()
    ref_mass, ref_forcing = kanes_method(scene)
    args = [eqs.states, eqs.params]
    ref_mass, ref_forcing = sm.lambdify(args, ref_mass), sm.lambdify(args, ref_forcing)
    for x, p in random_points(scene, 30):
        assert relative_error(mass(x, p), ref_mass(x, p)) < 1e-12
        assert relative_error(forcing(x, p), ref_forcing(x, p)) < 1e-12


@pytest.mark.parametrize(
    "scene",
    [Scene.uniform(3), MIXED, Scene.uniform(2, kinematics="pydy-example"), COUPLED],
    ids=["n3", "mixed", "pydy-example", "moving-pivot"],
)
def test_compiled_core_equals_lambdify(scene):
    eqs = derive(scene)
    mass, forcing, outputs = eqs.lambdify()
    core = load_core(scene)
    for x, p in random_points(scene, 50, seed=1):
        M, F = core.mass_forcing(x, p)
        assert relative_error(M, mass(x, p)) < 1e-12
        assert relative_error(F, np.ravel(forcing(x, p))) < 1e-12
        expected_accel = np.linalg.solve(np.array(mass(x, p), float), np.ravel(forcing(x, p)))
        # the symbolic outputs; the apparent mass after them is the core's (test_apparent_mass)
        assert relative_error(core.outputs(x, p)[: len(eqs.outputs)], outputs(x, p, expected_accel)) < 1e-10
        assert relative_error(core.rhs(x, p)[2 * scene.n :], expected_accel) < 1e-10
        np.testing.assert_array_equal(core.rhs(x, p)[: 2 * scene.n], x[2 * scene.n :])


def test_default_model_conserves_energy():
    result = simulate(Scene.uniform(3), SEED_TIMES, method="DOP853", rtol=1e-12, atol=1e-12)
    energy = result["energy"]
    assert np.abs(energy - energy[0]).max() / abs(energy[0]) < 1e-9
    assert np.ptp(result["alpha0"]) > 0.1  # it did swing


def test_published_model_does_not_conserve_energy():
    """The reason for the correction: the seed's kinematics gain and lose energy."""
    scene = Scene.uniform(3, kinematics="pydy-example")
    energy = simulate(scene, SEED_TIMES, rtol=1e-10, atol=1e-10)["energy"]
    swing = np.ptp(energy) / abs(energy[0])
    assert 0.1 < swing < 0.5


def test_conical_orbit_keeps_its_height():
    """n = 1, massless link with a bob: a spherical pendulum on its conical orbit."""
    scene = Scene(links=(Link(has_mass=False),))
    length, g, theta = 10.0, 9.8, np.radians(30.0)
    rate = np.sqrt(g / (length * np.cos(theta)))  # Omega^2 = g / (l cos theta)
    times = np.linspace(0.0, 10 * 2 * np.pi / rate, 2001)
    result = simulate(
        scene,
        times,
        state={"alpha0": theta, "beta0": 0.0, "omega0": 0.0, "delta0": -rate * np.tan(theta)},
        rtol=1e-12,
        atol=1e-12,
    )
    height = result["bob0_y"]
    assert height[0] == pytest.approx(-length * np.cos(theta), rel=1e-14)
    assert np.abs(height - height[0]).max() < 1e-8
    # and it went round: the bob's x changes sign ten times over
    assert np.count_nonzero(np.diff(np.sign(result["bob0_x"]))) >= 19


def test_small_planar_swing_has_the_pendulum_period():
    scene = Scene(links=(Link(has_mass=False),))
    length, g, amplitude = 10.0, 9.8, 1e-3
    period = 2 * np.pi * np.sqrt(length / g)
    times = np.linspace(0.0, 5 * period, 20001)
    result = simulate(scene, times, state={"alpha0": amplitude, "beta0": 0.0}, rtol=1e-12, atol=1e-14)
    assert np.abs(result["beta0"]).max() == 0.0  # stays in its plane
    alpha = result["alpha0"]
    down = np.flatnonzero((alpha[:-1] > 0) & (alpha[1:] <= 0))
    crossings = times[down] - alpha[down] * (times[down + 1] - times[down]) / (alpha[down + 1] - alpha[down])
    measured = np.diff(crossings).mean()
    # amplitude correction theta0^2/16 = 6e-8; linear interpolation of crossings ~1e-9
    assert measured / period - 1 == pytest.approx(amplitude**2 / 16, abs=1e-8)


def test_poses_match_bob_positions():
    scene = Scene.uniform(3)
    core = load_core(scene)
    names = scene.output_names()
    for x, p in random_points(scene, 10, seed=2):
        y = dict(zip(names, core.outputs(x, p)))
        joint = np.zeros(3)
        for i in range(3):
            q = np.array([y[f"link{i}_q{c}"] for c in "wxyz"])
            assert np.linalg.norm(q) == pytest.approx(1.0, abs=1e-14)
            w, v = q[0], q[1:]
            axis_y = np.array([0.0, 1.0, 0.0])
            rotated = axis_y + 2 * w * np.cross(v, axis_y) + 2 * np.cross(v, np.cross(v, axis_y))
            bob = np.array([y[f"bob{i}_{c}"] for c in "xyz"])
            centre = np.array([y[f"link{i}_{c}"] for c in "xyz"])
            np.testing.assert_allclose(bob, joint - p[i] * rotated, atol=1e-12)
            np.testing.assert_allclose(centre, (joint + bob) / 2, atol=1e-12)
            joint = bob


@pytest.mark.parametrize("n", range(1, 7))
@pytest.mark.parametrize("variant", ["full", "massless-links", "no-bobs"])
def test_every_chain_builds_and_conserves_energy(n, variant):
    scene = Scene.uniform(n, massless_links=variant == "massless-links", bobs=variant != "no-bobs")
    removed = {"massless-links": "M0", "no-bobs": "m0"}.get(variant)
    assert removed not in scene.parameter_names()
    result = simulate(scene, np.linspace(0.0, 2.0, 21), rtol=1e-11, atol=1e-11)
    assert np.all(np.isfinite(result.states))
    energy = result["energy"]
    assert np.abs(energy - energy[0]).max() <= 1e-8 * np.abs(energy).max()


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: Scene.uniform(0), "out of range"),
        (lambda: Scene.uniform(1000), "out of range"),
        (lambda: Scene(links=(Link(has_mass=False, has_bob=False),)), "no mass"),
        (lambda: Scene(links=(Link(), Link(has_mass=False, has_bob=False))), "links 1..1 carry no mass"),
        (lambda: Scene(kinematics="seed"), "kinematics"),
        (lambda: Scene.uniform(5, kinematics="pydy-example"), "only reproduced up to 4"),
        (lambda: Scene(links=(Link(length=-1.0),)), "length"),
        (lambda: Scene.uniform(3).parameters({"mass": 1.0}), "unknown parameter 'mass'"),
        (lambda: Scene.uniform(3, massless_links=True).parameters({"M0": 1.0}), "unknown parameter 'M0'"),
        (lambda: Scene.uniform(3).parameters({"a_pivot_x": 1.0}), "unknown parameter 'a_pivot_x'"),
        (lambda: Scene.uniform(2, kinematics="pydy-example", coupling=True), "coupling: .* 'consistent'"),
        (lambda: Scene.uniform(2, coupling="yes"), "coupling: expected true or false, got 'yes'"),
    ],
)
def test_bad_scenes_and_values_are_named(make, message):
    with pytest.raises(SceneError, match=message):
        make()


@pytest.mark.parametrize(
    "parameters, state, message",
    [
        ({"l0": 0.0}, None, "l0 = 0.0: a length must be positive"),
        ({"m2": -5.0}, None, "m2 = -5.0: a bob mass must be positive"),
        ({"Ixx1": -1.0}, None, "Ixx1 = -1.0: a moment of inertia cannot be negative"),
        ({"g": float("nan")}, None, "g = nan: must be finite"),
        ({"M0": "heavy"}, None, "M0: expected a number, got 'heavy'"),
        (None, {"alpha0": float("inf")}, "alpha0 = inf: must be finite"),
        ({"a_pivot_y": float("nan")}, None, "a_pivot_y = nan: must be finite"),
    ],
)
def test_bad_values_are_named(parameters, state, message):
    scene = Scene.uniform(3, coupling=True)
    core = load_core(scene)
    with pytest.raises(BadValue, match=message):
        simulate(scene, [0.0, 1.0], parameters=parameters, state=state, core=core)
