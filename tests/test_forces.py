"""The forces a scene may add: joint damping (Scene.joint_damping, the torque -c w_rel at each
joint, c per joint a parameter), the air's drag on the bobs (Scene.air_drag, -1/2 rho C_d A |v_air|
v_air with the wind an input) and forces applied to the bobs it names (Link.bob_force, inputs
F_bob<i>_x/y/z), in both formulations and every FMU, with the energy's books (W_damping,
W_drag, W_external, W_pivot); checked against MuJoCo (hinge damping, drag in mjcb_passive,
xfrc_applied), the damped small-swing pendulum's analytic decay, a pendulum's lean in a
steady wind, and Newton's law for the force on the support."""

import hashlib
import math
from dataclasses import replace

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from conical_pendulum import Link, Scene, SceneError
from conical_pendulum.analysis.compare import compare
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.analysis.simulate import simulate
from conical_pendulum.builder.core.codegen import generate, generate_recursive
from conical_pendulum.builder.core.equations import derive, joint_damping
from conical_pendulum.runtime.rules import BadValue, check_value
from conical_pendulum.scene import load_scene
from fmu_helpers import INSTANCES
from formulations import assert_formulations_agree
from mujoco_chain import drag_callback, simulate_mujoco

ERROR = 3  # fmi2Error, fmi3Error

DAMPED = Scene(
    links=(Link(damping=4.0), Link(damping=2.0, has_bob=False), Link(damping=1.0)),
    joint_damping=True,
    coupling=True,
)
DAMPED_RECURSIVE = Scene(links=tuple(Link(damping=1.0 + i) for i in range(7)), joint_damping=True)
# every option at once, the FMUs' scene: damping, the air's drag, forces on two bobs, a moving
# support
FORCED = Scene(
    links=(
        Link(damping=4.0, bob_force=True),
        Link(damping=2.0, has_bob=False),
        Link(damping=1.0, bob_force=True, bob_area=6.0),
    ),
    joint_damping=True,
    air_drag=True,
    coupling=True,
)
FORCED_RECURSIVE = Scene(
    links=tuple(Link(damping=1.0 + i, bob_force=i in (2, 6)) for i in range(7)),
    joint_damping=True,
    air_drag=True,
    coupling=True,
)
# the wind, the support's velocity (which only the drag sees) and the applied forces
WIND = {"wind_x": 4.0, "wind_z": -2.5}
FORCES = {"F_bob0_x": 20.0, "F_bob2_y": 10.0, "F_bob2_z": -30.0, **WIND, "v_pivot_x": 1.0, "v_pivot_y": -0.5}
STATE, PARAMETERS = {"alpha0": 0.5, "beta1": 0.3, "omega2": 0.4}, {"c1": 3.0}
START = {**STATE, **PARAMETERS}

# sha256 of the generated model.h + model.c of scenes without options, as generated before
# the options existed (commit cba75c1): an option left out must change nothing. Pinned again
# for issue 46's two statistics (CP_STAT_N_JACOBIANS, CP_STAT_N_FACTORIZATIONS, CP_NSTAT 5),
# checked to be the only change: the old digests are those of today's C without them.
TODAYS_C = {
    "seed": (Scene.uniform(3), "fac194257d838ad37084e57c90aa68830ccb89149af48add295ac940d49c9f28"),
    "coupled2": (
        Scene.uniform(2, coupling=True),
        "f9185f0b726b03f855c2ea5a26906078fcb7a377a915a53e48ba241f3228ec97",
    ),
    "mixed": (
        Scene(links=(Link(), Link(has_bob=False), Link(has_mass=False)), outputs=("energy",)),
        "537bc714572a209114fc403d70126bd45fceaacfdf15ffbc55b04bddf301d380",
    ),
    "recursive4": (
        Scene.uniform(4, formulation="recursive", coupling=True),
        "9b0d288d8effbb99f6553a1fb65844ba4e63fe6c7da845fb3a7e5f8fa0f4a138",
    ),
}


def generated(scene):
    files = (
        generate_recursive(scene) if scene.resolved_formulation() == "recursive" else generate(derive(scene))
    )
    return files


@pytest.mark.parametrize("name", list(TODAYS_C))
def test_a_scene_without_options_generates_todays_c_bit_for_bit(name):
    scene, digest = TODAYS_C[name]
    files = generated(scene)
    assert hashlib.sha256("".join(files[k] for k in sorted(files)).encode()).hexdigest() == digest
    assert "damping" not in scene.cache_fields() and "W_damping" not in scene.state_names()


def test_a_negative_damping_is_refused_naming_it(tmp_path):
    with pytest.raises(SceneError, match=r"link\[1\]\.damping: must be a finite number >= 0, got -0.5"):
        Scene(links=(Link(), Link(damping=-0.5)), joint_damping=True)
    path = tmp_path / "bad.toml"
    path.write_text("[[link]]\ndamping = -2.0\n")
    with pytest.raises(
        SceneError, match=r"bad.toml'.*link\[0\]\.damping: must be a finite number >= 0, got -2.0"
    ):
        load_scene(path)
    with pytest.raises(BadValue, match=r"c1 = -0\.5: a joint damping coefficient cannot be negative"):
        check_value("c1", -0.5, "c")
    with pytest.raises(
        SceneError, match=r"link\[0\]\.damping: 2.0 given, but the scene has no joint damping"
    ):
        Scene(links=(Link(damping=2.0),))
    with pytest.raises(SceneError, match=r"joint_damping: .* needs kinematics 'consistent'"):
        Scene(joint_damping=True, kinematics="pydy-example")


def test_a_scene_file_with_a_links_damping_has_joint_damping(tmp_path):
    path = tmp_path / "damped.toml"
    path.write_text("[[link]]\ndamping = 2.0\n\n[[link]]\nbob = { mass = 1.0 }\n")
    scene = load_scene(path)
    assert scene.joint_damping and [link.damping for link in scene.links] == [2.0, 0.0]
    assert scene.parameters()[scene.core_parameter_names().index("c0")] == 2.0
    assert scene.state_names()[-1] == "W_damping"


def test_the_joint_is_orthonormal_so_its_damping_is_minus_c_times_the_rates():
    """chain.c applies -c (omega, delta) directly; the expanded equations derive it."""
    forces, power = joint_damping(Scene.uniform(2, joint_damping=True))
    c0, c1, w0, w1, d0, d1 = (sympy_symbol(n) for n in ("c0", "c1", "omega0", "omega1", "delta0", "delta1"))
    assert forces == [-c0 * w0, -c1 * w1, -c0 * d0, -c1 * d1]
    assert (power - (-c0 * (w0**2 + d0**2) - c1 * (w1**2 + d1**2))).expand() == 0


def sympy_symbol(name):
    import sympy

    return sympy.Symbol(name)


@pytest.mark.parametrize(
    "links, coupling, drag",
    [
        ((Link(damping=2.0),), False, False),
        ((Link(damping=1.0), Link(damping=3.0, has_mass=False)), True, False),
        ((Link(damping=4.0), Link(damping=2.0, has_bob=False), Link(damping=1.0)), True, False),
        (FORCED.links, True, True),
        (
            (Link(damping=1.0, bob_force=True), Link(damping=3.0, has_mass=False, bob_force=True)),
            False,
            False,
        ),
        ((Link(damping=1.0, bob_drag_coefficient=1.1), Link(damping=3.0, has_mass=False)), False, True),
    ],
)
def test_the_formulations_agree(links, coupling, drag):
    """M, F, x' (the books' rates too) and the outputs (the pivot force, F_free, M_app among
    them) at random states and inputs."""
    options = {"joint_damping": True, "coupling": coupling, "air_drag": drag}
    scene = Scene(links=links, **options)
    for x, p, de, ye in assert_formulations_agree(links, options, seed=3, input_range=20):
        rates = x[2 * scene.n : 4 * scene.n]
        c = np.tile([link.damping for link in links], 2)
        damping = 4 * scene.n + scene.work_names().index("W_damping")
        assert de[damping] == pytest.approx(-np.sum(c * rates**2), rel=1e-13)
        if scene.coupling:  # F_pivot = F_free - M_app a_pivot, the bobs' forces in F_free
            out = dict(zip(scene.output_names(), ye))
            a = p[scene.core_parameter_names().index("a_pivot_x") :][:3]
            m = np.array([[out["M_pivot_" + "".join(sorted(r + k))] for k in "xyz"] for r in "xyz"])
            free = np.array([out[f"F_free_{k}"] for k in "xyz"])
            pivot = np.array([out[f"F_pivot_{k}"] for k in "xyz"])
            np.testing.assert_allclose(pivot, free - m @ a, rtol=0, atol=1e-10 * np.abs(pivot).max())


def books(run, scene):
    """Energy less the work of every force the scene keeps books of."""
    return run["energy"] - sum(run[name] for name in scene.work_names())


@pytest.mark.parametrize(
    "scene",
    [DAMPED, DAMPED_RECURSIVE, FORCED, FORCED_RECURSIVE],
    ids=["damped", "damped-recursive", "forced", "forced-recursive"],
)
def test_energy_minus_the_forces_work_stays_constant(scene):
    inputs = {**FORCES, "a_pivot_x": 1.5, "a_pivot_z": -0.7}
    inputs = {k: v for k, v in inputs.items() if k in scene.input_names()}
    run = simulate(
        scene,
        np.linspace(0, 10, 201),
        state=STATE,
        parameters={**PARAMETERS, **inputs},
        rtol=1e-12,
        atol=1e-12,
    )
    energy, kept = run["energy"], books(run, scene)
    assert np.all(np.diff(run["W_damping"]) <= 0)
    for name in scene.work_names():  # each force did work the books must hold
        assert abs(run[name][-1]) > 1.0, name
    assert np.abs(energy - energy[0]).max() > 1.0
    assert np.abs(kept - kept[0]).max() < 1e-9 * abs(energy[0])


@pytest.mark.parametrize("formulation", ["expanded", "recursive"])
def test_the_support_force_is_newtons_law_with_the_applied_forces(formulation):
    """F_pivot = sum m (g - a) + sum F_bob + sum drag, the masses' accelerations a (the
    pivot's plus their own relative to it) from second differences of their positions (bob
    and link centre outputs) at 1 ms, the bobs' drag from first differences: an independent
    path to what the model computes."""
    scene = replace(FORCED, formulation=formulation)
    a_pivot = np.array([1.5, 0.0, -0.7])
    inputs = {**FORCES, "a_pivot_x": a_pivot[0], "a_pivot_z": a_pivot[2]}
    h, times = 1e-3, np.linspace(0, 2.0, 2001)
    run = simulate(scene, times, state=STATE, parameters=inputs, rtol=1e-13, atol=1e-13)
    air = np.array([inputs.get(f"v_pivot_{c}", 0.0) - inputs.get(f"wind_{c}", 0.0) for c in "xyz"])
    total = np.zeros((len(times) - 2, 3))
    for i, link in enumerate(scene.links):
        masses = {"link": link.mass if link.has_mass else 0.0, "bob": link.bob_mass if link.has_bob else 0.0}
        for body, mass in masses.items():
            if mass:
                r = np.column_stack([run[f"{body}{i}_{c}"] for c in "xyz"])
                acc = (r[2:] - 2 * r[1:-1] + r[:-2]) / h**2 + a_pivot
                total += mass * (np.array([0.0, -scene.gravity, 0.0]) - acc)
        if link.has_bob:
            r = np.column_stack([run[f"bob{i}_{c}"] for c in "xyz"])
            v_air = (r[2:] - r[:-2]) / (2 * h) + air
            c_d, area = link.drag()
            total -= 0.5 * 1.225 * c_d * area * np.linalg.norm(v_air, axis=1)[:, None] * v_air
    total += [FORCES.get(f"F_bob0_{c}", 0.0) + FORCES.get(f"F_bob2_{c}", 0.0) for c in "xyz"]
    pivot = np.column_stack([run[f"F_pivot_{c}"] for c in "xyz"])[1:-1]
    assert np.abs(pivot - total).max() < 1e-5 * np.abs(pivot).max()


def test_a_small_swing_decays_as_the_damped_oscillator():
    """One link swinging in its plane (beta) by 0.01 rad: I beta'' + c beta' + K beta = 0,
    I and K about the pivot; the sine's cubic term moves it less than 3e-7 rad in 10 s."""
    link = Link(damping=200.0)
    scene = Scene(links=(link,), joint_damping=True)
    beta0, times = 0.01, np.linspace(0, 10, 501)
    run = simulate(scene, times, state={"alpha0": 0.0, "beta0": beta0}, rtol=1e-12, atol=1e-12)
    ixx = link.inertia()[0]
    inertia = ixx + link.mass * link.length**2 / 4 + link.bob_mass * link.length**2
    stiffness = (link.mass / 2 + link.bob_mass) * link.length * scene.gravity
    w0 = math.sqrt(stiffness / inertia)
    zeta = link.damping / (2 * math.sqrt(stiffness * inertia))
    wd = w0 * math.sqrt(1 - zeta**2)
    analytic = beta0 * np.exp(-zeta * w0 * times) * (np.cos(wd * times) + zeta * w0 / wd * np.sin(wd * times))
    assert 0.05 < zeta < 0.5 and analytic[-1] < 0.5 * beta0  # damped enough to see
    assert np.abs(run["beta0"] - analytic).max() < 1e-6
    assert np.abs(run["alpha0"]).max() == 0.0


@pytest.mark.parametrize("scene", [DAMPED, DAMPED_RECURSIVE], ids=["expanded", "recursive"])
def test_it_agrees_with_mujocos_hinge_damping(scene):
    """MuJoCo's chain (tests/mujoco_chain.py) with damping on both hinges of each joint: its
    RK4 at 1 ms against our DOP853 at 1e-12, every angle over 10 s."""
    scene = Scene(links=scene.links, joint_damping=True, formulation=scene.formulation)  # a fixed support
    times = np.linspace(0, 10, 101)
    state = STATE
    run = simulate(scene, times, state=state, rtol=1e-12, atol=1e-12)
    ours = np.column_stack([run[f"{a}{i}"] for a in ("alpha", "beta") for i in range(scene.n)])
    theirs = simulate_mujoco(scene, state, times)
    assert np.abs(ours - theirs).max() < 1e-6
    free = simulate(scene, times, state=state, parameters={f"c{i}": 0.0 for i in range(scene.n)})
    undamped = np.column_stack([free[f"{a}{i}"] for a in ("alpha", "beta") for i in range(scene.n)])
    assert np.abs(undamped - theirs).max() > 1e-2  # what the check tells apart


@pytest.mark.parametrize("scene", [FORCED, FORCED_RECURSIVE], ids=["expanded", "recursive"])
def test_it_agrees_with_mujocos_applied_forces(scene):
    """MuJoCo's xfrc_applied on each forced bob (a body of its own there) and the wind of its
    drag (drag_callback), held over each 0.5 s and changed between, as a co-simulation master
    holds an input over its step; ours run segment by segment with the same held values.
    Hinge damping too; a fixed support."""
    scene = replace(scene, coupling=False)
    rng = np.random.default_rng(11)
    held = rng.uniform(-30, 30, (20, len(scene.input_names())))  # one row per 0.5 s
    windy = [k for k, name in enumerate(scene.input_names()) if name.startswith("wind_")]
    held[:, windy] /= 3  # winds up to 10 m/s
    wind = np.zeros(3)  # what drag_callback reads, set with the forces

    def applied(t, data, bodies):
        row = dict(zip(scene.input_names(), held[min(int(t / 0.5 + 1e-9), len(held) - 1)]))
        for i in scene.forced_bobs():
            data.xfrc_applied[bodies[i], :3] = [row[f"F_bob{i}_{c}"] for c in "xyz"]
        wind[:] = [row[f"wind_{c}"] for c in "xyz"]

    times, state, angles = np.linspace(0, 10, 201), dict(STATE), []
    names = [f"{a}{i}" for a in ("alpha", "beta") for i in range(scene.n)]
    for k, row in enumerate(held):
        segment = times[10 * k : 10 * k + 11]
        run = simulate(
            scene,
            segment,
            state=state,
            parameters=dict(zip(scene.input_names(), row)),
            rtol=1e-12,
            atol=1e-12,
        )
        angles.append(np.column_stack([run[n] for n in names])[:-1])
        state = {n: run[n][-1] for n in scene.state_names()}
    ours = np.concatenate(angles + [[[state[n] for n in names]]])
    theirs = simulate_mujoco(scene, STATE, times, applied=applied, passive=drag_callback(scene, wind))
    assert np.abs(ours - theirs).max() < 1e-6
    still = simulate_mujoco(scene, STATE, times)  # the same chain without the forces and the air
    assert np.abs(still - theirs).max() > 1e-2


# in still air, and in a wind that changes its direction (the test's wind_x/wind_z)
DRAGGED = Scene(
    links=(Link(damping=4.0), Link(damping=2.0, has_bob=False), Link(damping=1.0, bob_area=6.0)),
    joint_damping=True,
    air_drag=True,
)
DRAGGED_RECURSIVE = Scene(
    links=tuple(Link(damping=1.0 + i, bob_drag_coefficient=0.3 + 0.1 * i) for i in range(7)),
    joint_damping=True,
    air_drag=True,
)


@pytest.mark.parametrize("scene", [DRAGGED, DRAGGED_RECURSIVE], ids=["expanded", "recursive"])
def test_it_agrees_with_mujocos_chain_in_a_wind_by_mjcb_passive(scene):
    """MuJoCo's chain with the drag computed at each stage of its RK4 (mujoco_chain's
    drag_callback, from the bobs' sites' velocities) against our DOP853 at 1e-12, every angle
    over 10 s, in a wind."""
    times = np.linspace(0, 10, 101)
    wind = np.array([WIND.get(f"wind_{c}", 0.0) for c in "xyz"])
    run = simulate(scene, times, state=STATE, parameters=WIND, rtol=1e-12, atol=1e-12)
    ours = np.column_stack([run[f"{a}{i}"] for a in ("alpha", "beta") for i in range(scene.n)])
    theirs = simulate_mujoco(scene, STATE, times, passive=drag_callback(scene, wind))
    assert np.abs(ours - theirs).max() < 1e-6
    assert run["W_drag"][-1] < -1.0  # the wind did work to see, and took more than it gave
    in_still_air = simulate_mujoco(scene, STATE, times, passive=drag_callback(scene, np.zeros(3)))
    assert np.abs(in_still_air - theirs).max() > 1e-2  # what the check tells apart


def test_a_support_moving_steadily_through_still_air_is_a_wind_against_it():
    """Galileo: a pivot moving at v_pivot through a wind w drags the chain as a fixed pivot in
    the wind w - v_pivot (a_pivot = 0); the coupled scene's v_pivot inputs and the fixed one's
    wind give the same angles, both formulations."""
    moving = {"v_pivot_x": 3.0, "v_pivot_z": -2.0, "wind_x": -1.0, "wind_y": 0.5}
    relative = {"wind_x": -4.0, "wind_y": 0.5, "wind_z": 2.0}
    times = np.linspace(0, 5, 51)
    for formulation in ("expanded", "recursive"):
        fixed = Scene(links=DRAGGED.links, joint_damping=True, air_drag=True, formulation=formulation)
        runs = [
            simulate(scene, times, state=STATE, parameters=inputs, rtol=1e-12, atol=1e-12)
            for scene, inputs in ((replace(fixed, coupling=True), moving), (fixed, relative))
        ]
        for name in fixed.state_names():  # angles and rates of order one, the books in joules
            scale = max(1.0, np.abs(runs[1][name]).max())
            assert np.abs(runs[0][name] - runs[1][name]).max() < 1e-10 * scale, (formulation, name)
        assert abs(runs[1]["W_drag"][-1]) > 1.0


def test_a_pendulum_leans_into_a_steady_wind_by_drag_over_weight():
    """A bob on a massless link in a steady wind along z settles (the joint's damping takes
    the swing) where the wind's drag, 1/2 rho C_d A w^2, and the weight m g balance: at
    atan(drag / weight) from the vertical, in the wind's plane."""
    link = Link(has_mass=False, damping=1200.0)  # near critical for its lean
    scene = Scene(links=(link,), joint_damping=True, air_drag=True)
    wind = 10.0
    run = simulate(
        scene,
        np.linspace(0, 60, 61),
        state={"alpha0": 0.0, "beta0": 0.0},
        parameters={"wind_z": wind},
        rtol=1e-12,
        atol=1e-12,
    )
    c_d, area = link.drag()
    drag, weight = 0.5 * 1.225 * c_d * area * wind**2, link.bob_mass * scene.gravity
    lean = math.atan2(run["bob0_z"][-1], -run["bob0_y"][-1])
    assert drag / weight > 1.5  # leaning by some 60 degrees
    assert abs(lean - math.atan(drag / weight)) < 1e-9
    assert abs(run["bob0_x"][-1]) < 1e-12 and abs(run["omega0"][-1]) + abs(run["delta0"][-1]) < 1e-9


def test_a_bad_drag_is_refused_naming_it(tmp_path):
    with pytest.raises(SceneError, match=r"link\[1\]\.bob\.area: must be a finite number >= 0, got -1.0"):
        Scene(links=(Link(), Link(bob_area=-1.0)), air_drag=True)
    with pytest.raises(SceneError, match=r"air_density: must be a finite number >= 0, got -1.2"):
        Scene(air_drag=True, air_density=-1.2)
    with pytest.raises(
        SceneError, match=r"link\[0\]\.bob\.drag_coefficient: 1.0 given, but the scene has no air"
    ):
        Scene(links=(Link(bob_drag_coefficient=1.0),))
    with pytest.raises(SceneError, match=r"air_drag: the scene has no bob for the air to drag"):
        Scene.uniform(2, bobs=False, air_drag=True)
    with pytest.raises(SceneError, match=r"air_drag: .* needs kinematics 'consistent'"):
        Scene(air_drag=True, kinematics="pydy-example")
    with pytest.raises(BadValue, match=r"C_d1 = -0\.5: a drag coefficient cannot be negative"):
        check_value("C_d1", -0.5, "C_d")
    path = tmp_path / "windy.toml"
    path.write_text("air_density = 1.0\n[[link]]\nbob = { mass = 2.0, area = 0.5 }\n")
    scene = load_scene(path)
    assert scene.air_drag and scene.links[0].drag() == (0.47, 0.5)
    assert dict(zip(scene.parameter_names(), scene.parameter_defaults()))["rho"] == 1.0
    assert scene.input_names() == ["wind_x", "wind_y", "wind_z"] and scene.state_names()[-1] == "W_drag"
    path.write_text("air_density = true\n[[link]]\n")
    with pytest.raises(SceneError, match=r"air_density: expected a number, got True"):
        load_scene(path)


@pytest.fixture(scope="module")
def damped_fmu(built_fmu):
    return lambda backend, fmi_version=2: built_fmu(FORCED, backend=backend, fmi_version=fmi_version)


@pytest.mark.parametrize("backend, fmi_version", [("pythonfmu", 2), ("native", 2), ("native", 3)])
def test_its_fmus_follow_the_reference_and_keep_the_books(damped_fmu, backend, fmi_version):
    start = {**START, **FORCES, "a_pivot_x": 0.8}
    comparison = compare(damped_fmu(backend, fmi_version), FORCED, start_values=start, stop_time=10.0)
    assert comparison.passed(), comparison.report()
    result = comparison.result
    kept = books(result, FORCED)
    for name in FORCED.work_names():
        assert abs(result[name][-1]) > 1.0, name
    assert np.abs(kept - kept[0]).max() < 1e-8 * abs(result["energy"][0])


def test_model_exchange_follows_the_reference(damped_fmu):
    run = run_fmu(
        damped_fmu("native"),
        stop_time=10.0,
        fmi_type="ModelExchange",
        relative_tolerance=1e-10,
        start_values={**START, **FORCES, "a_pivot_x": 0.8},
    )
    inputs = {**PARAMETERS, **FORCES, "a_pivot_x": 0.8}
    reference = simulate(FORCED, run["time"], parameters=inputs, state=STATE, rtol=1e-12, atol=1e-12)
    for name in FORCED.state_names():  # angles and rates of order one, the books in joules (tens)
        scale = max(1.0, np.abs(reference[name]).max())
        assert np.abs(run[name] - reference[name]).max() < 1e-6 * scale, name


@pytest.mark.parametrize("fmi_version", [2, 3])
@pytest.mark.parametrize(
    "name, value, kept, rule",
    [("c2", -1.0, 1.0, "a joint damping coefficient"), ("rho", -1.2, 1.225, "an air density")],
)
def test_an_fmu_refuses_a_negative_damping_naming_it(damped_fmu, fmi_version, name, value, kept, rule):
    fmu = INSTANCES[fmi_version](damped_fmu("native", fmi_version), initialize=False)
    with pytest.raises(FMICallException):
        fmu.set({name: value})
    message = f"{name} = {value}: {rule} cannot be negative"
    assert any(status == ERROR and text.startswith(message) for status, text in fmu.messages), fmu.messages
    fmu.initialize()
    fmu.step(0.5)
    assert fmu.get(name) == [kept] and fmu.get("W_damping")[0] < 0  # the damping it had
    fmu.close()
