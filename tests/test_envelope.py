"""The envelope: extreme motion, parameters, steps and loads, through fmpy against the native
reference. Each case either matches the reference or ends in a discarded step with a
message that says what happened; never NaN reported as success."""

import math
import os

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from conical_pendulum import Link, Scene
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.analysis.simulate import simulate
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.scene import load_scene
from fmu_helpers import Instance
from test_stiff import light_chain

SEED = Scene.uniform(3)
TIGHT = {"solver": 2, "rtol": 1e-11, "atol": 1e-11}
DEG = math.pi / 180


def scaled_link_mass(i, factor):
    """Link i's mass and inertias scaled together (a lighter or heavier cylinder)."""
    ixx, iyy, izz = Link().inertia()
    return {f"M{i}": 10.0 * factor, f"Ixx{i}": ixx * factor, f"Iyy{i}": iyy * factor, f"Izz{i}": izz * factor}


CASES = {
    "angles +-170 deg": {"alpha0": 170 * DEG, "alpha1": -170 * DEG, "beta2": 170 * DEG},
    "whipping chain": {"omega2": 30.0, "delta1": -20.0, "omega0": 5.0},
    "upside down": {"alpha0": math.pi, "beta0": 1e-3, "alpha1": 0.0, "beta1": 0.0},
    "thin links": {f"Iyy{i}": 10.0 * 1e-4**2 for i in range(3)},
    "mass ratio 1e6": {"m0": 5e6, **scaled_link_mass(0, 1e6)},
    "mass ratio 1e-6": {"m2": 5e-6, **scaled_link_mass(2, 1e-6)},
    "lengths 1e-3 m": {
        **{f"l{i}": 1e-3 for i in range(3)},
        **{f"Ixx{i}": 10 * (3 * 0.25 + 1e-6) / 12 for i in range(3)},
    },
    "lengths 1e3 m": {f"l{i}": 1e3 for i in range(3)},
    "g = 0, spinning": {"g": 0.0, "omega0": 1.0, "delta1": -2.0, "omega2": 0.5},
    "g = 1e4": {"g": 1e4},
}


@pytest.mark.parametrize("case", CASES, ids=list(CASES))
def test_extreme_cases_match_the_native_reference(seed_fmu, case):
    start = CASES[case]
    result = run_fmu(seed_fmu, stop_time=2.0, output_interval=0.05, start_values={**TIGHT, **start})
    assert result["time"][-1] == pytest.approx(2.0)
    params = {k: v for k, v in start.items() if k in SEED.parameter_names()}
    state = {k: v for k, v in start.items() if k in SEED.state_names()}
    native = simulate(SEED, result["time"], parameters=params, state=state, rtol=1e-13, atol=1e-13)
    for name in SEED.state_names() + ["energy"]:
        assert np.all(np.isfinite(result[name])), name
    angles = max(np.abs(result[n] - native[n]).max() for n in SEED.state_names()[:6])
    assert angles < 1e-6
    energy = native["energy"]
    scale = max(np.abs(energy).max(), 1e-300)
    assert np.abs(result["energy"] - energy).max() <= 1e-6 * scale


def test_ten_links(built_fmu):
    scene = Scene.uniform(10)
    path = built_fmu(scene)
    start = {**TIGHT, "alpha4": 0.8, "delta9": 1.0}
    result = run_fmu(path, stop_time=2.0, output_interval=0.05, start_values=start)
    native = simulate(scene, result["time"], state={"alpha4": 0.8, "delta9": 1.0}, rtol=1e-13, atol=1e-13)
    assert max(np.abs(result[n] - native[n]).max() for n in scene.state_names()[:20]) < 1e-6


def test_communication_steps_from_1e9_to_100_s(seed_fmu):
    steps = [1e-9, 1e-9, 1e-6, 1e-3, 0.1, 1.0, 10.0, 100.0, 0.25, 3e-7]
    fmu = Instance(seed_fmu, start_values={"rtol": 1e-10, "atol": 1e-10})
    times, states = [0.0], [fmu.get(*SEED.state_names())]
    for dt in steps:
        fmu.step(dt)
        times.append(fmu.time)
        states.append(fmu.get(*SEED.state_names()))
    fmu.close()
    native = simulate(SEED, times, rtol=1e-13, atol=1e-13)
    for k, t in enumerate(times):
        # errors grow with the 111 s simulated: 1e-10 per unit time is the tolerance asked
        np.testing.assert_allclose(
            states[k][:6], native.states[k, :6], rtol=0, atol=1e-10 * max(t, 1.0) * 100, err_msg=f"t = {t}"
        )


def test_a_tolerance_time_cannot_resolve_is_discarded_with_a_message(seed_fmu):
    fmu = Instance(seed_fmu, start_values={"rtol": 1e-13, "atol": 1e-300}, initialize=False)
    fmu.fmu.setupExperiment(startTime=1e15)
    fmu.fmu.enterInitializationMode()
    fmu.fmu.exitInitializationMode()
    fmu.time = 1e15
    before = fmu.get(*SEED.state_names())
    with pytest.raises(FMICallException) as failure:
        fmu.step(1.0)
    assert failure.value.status == 2
    assert any("step size underflow" in text and "loosen them" in text for _, text in fmu.messages)
    assert fmu.get(*SEED.state_names()) == before
    fmu.close()


def test_a_step_never_hangs(seed_fmu):
    """max_steps bounds each doStep: a year in one step is refused quickly, not computed."""
    fmu = Instance(seed_fmu, start_values={"max_steps": 1000})
    with pytest.raises(FMICallException) as failure:
        fmu.step(3.15e7)
    assert failure.value.status == 2
    assert fmu.get("n_rhs")[0] < 1000 * 12 + 20
    fmu.close()


def test_approaching_the_joint_singularity(built_fmu):
    """A massless link with a bob near its parent's x axis: fine up to the singular point."""
    scene = Scene(links=(Link(), Link(has_mass=False)))
    path = built_fmu(scene)
    for alpha1 in (math.pi / 2 - 1e-3, math.pi / 2 - 1e-6):
        start = {"alpha1": alpha1, "beta1": 0.3}
        result = run_fmu(path, stop_time=2.0, output_interval=0.05, start_values={**TIGHT, **start})
        native = simulate(scene, result["time"], state=start, rtol=1e-13, atol=1e-13)
        assert np.abs(result["alpha1"] - native["alpha1"]).max() < 1e-6
        assert np.abs(result["bob1_y"] - native["bob1_y"]).max() < 1e-6


@pytest.mark.slow
@pytest.mark.parametrize(
    "solver, settings, bound",
    [
        ("rk4", {"solver": 0, "max_step": 0.01}, 1e-6),
        ("rk45", {"solver": 1, "rtol": 1e-8, "atol": 1e-8}, 1e-5),
        ("dop853", {"solver": 2, "rtol": 1e-8, "atol": 1e-8}, 1e-6),
    ],
)
def test_energy_drift_over_1e4_s(seed_fmu, solver, settings, bound):
    result = run_fmu(seed_fmu, stop_time=1e4, output_interval=1.0, start_values=settings, output=["energy"])
    energy = result["energy"]
    drift = np.abs(energy - energy[0]).max() / abs(energy[0])
    print(f"{solver}: relative energy drift over 1e4 s = {drift:.2e}")
    assert drift < bound


@pytest.mark.slow
def test_a_thousand_cycles_in_one_process(seed_fmu, tmp_path):
    """Instantiate, simulate, free 1000 times: the same numbers, and memory flat.

    pythonfmu 0.7 re-executes the slave module per instantiation and keeps what that
    execution defines; the slave defines nothing new then (0.3 MiB over 1000 cycles here,
    where a trivial pythonfmu FMU grows 9 MiB).
    """
    import sys

    from fmpy import extract

    unzipped = extract(str(seed_fmu), unzipdir=str(tmp_path / "fmu"))

    def rss_mib():
        with open(f"/proc/{os.getpid()}/status") as status:
            return next(int(line.split()[1]) for line in status if line.startswith("VmRSS")) / 1024

    def cycle():
        return run_fmu(unzipped, stop_time=0.2, output_interval=0.05)["bob2_x"][-1]

    first = [cycle() for _ in range(20)][-1]
    baseline, path_entries = rss_mib(), len(sys.path)
    results = {cycle() for _ in range(1000)}
    growth = rss_mib() - baseline
    print(f"RSS growth over 1000 cycles: {growth:.1f} MiB")
    assert results == {first}
    assert growth < 5.0
    assert len(sys.path) == path_entries


@pytest.mark.parametrize("radius, outcome", [(0.5, "matches"), (1e-3, "matches"), (1e-9, "singular")])
def test_a_massive_link_on_its_parents_x_axis(built_fmu, radius, outcome):
    """On the joint singularity a link's beta turns it about its own axis: only Iyy = M r^2
    resists, so the mass matrix is regular for a real cylinder and singular as r -> 0."""
    scene = Scene.uniform(2)
    path = built_fmu(scene)
    start = {"alpha1": math.pi / 2, "beta1": 0.0, "omega0": 0.3, "Iyy1": 10.0 * radius**2}
    if outcome == "matches":
        result = run_fmu(path, stop_time=2.0, output_interval=0.05, start_values={**TIGHT, **start})
        native = simulate(
            scene,
            result["time"],
            parameters={"Iyy1": start["Iyy1"]},
            state={k: v for k, v in start.items() if k != "Iyy1"},
            rtol=1e-13,
            atol=1e-13,
        )
        assert np.abs(result["alpha1"] - native["alpha1"]).max() < 1e-6
        assert result["alpha1"][-1] != pytest.approx(math.pi / 2)  # it moved off the axis
        return
    fmu = Instance(path, start_values=start)
    with pytest.raises(FMICallException) as failure:
        fmu.step(0.05)
    assert failure.value.status == 2
    text = " ".join(t for _, t in fmu.messages)
    assert "singular mass matrix" in text and "link 1" in text and "too little inertia" in text
    assert fmu.get("alpha1") == [math.pi / 2]
    fmu.close()


@pytest.mark.parametrize("dt", [-0.1, float("inf"), float("nan")])
def test_an_invalid_communication_step_is_discarded(seed_fmu, dt):
    fmu = Instance(seed_fmu)
    before = fmu.get(*SEED.state_names())
    with pytest.raises(FMICallException) as failure:
        fmu.step(dt)
    assert failure.value.status == 2
    assert any("invalid communication step" in text for _, text in fmu.messages)
    assert fmu.get(*SEED.state_names()) == before
    fmu.time = 0.0
    fmu.step(0.1)
    fmu.close()


# Stiff scenes (issue 46): (scene, start values)
STIFF = {
    "damped light chain, c = 1e4": (light_chain(3), {f"c{i}": 1e4 for i in range(3)}),
    "heavy damping, the seed's links, c = 1e5": (
        Scene(links=(Link(damping=1e5),) * 3, joint_damping=True),
        {"alpha0": 0.5},
    ),
    "20-link damped light chain, c = 1e2": (light_chain(20), {f"c{i}": 1e2 for i in range(20)}),
}
CRANE = load_scene(os.path.join(os.path.dirname(__file__), "..", "scenes", "crane.toml"))


@pytest.mark.parametrize("case", STIFF, ids=list(STIFF))
def test_stiff_scenes_finish_with_the_default_solver_at_their_tolerance(built_fmu, case):
    """The default solver (auto) at rtol = atol = 1e-6, 2 s at 100 Hz: within 10 tolerances
    of the core's Radau at 1e-12, every state scaled by its largest size."""
    scene, start = STIFF[case]
    path = built_fmu(scene, backend="native")
    result = run_fmu(
        path, stop_time=2.0, output_interval=0.01, start_values={**start, "rtol": 1e-6, "atol": 1e-6}
    )
    found = np.column_stack([result[n] for n in scene.state_names()])
    parameters, states = scene.split_start(start)
    p, x0 = np.array(scene.parameters(parameters)), np.array(scene.initial_state(states))
    reference, _ = load_core(scene).integrate_grid(x0, p, result["time"], 1e-12, 1e-12, method="radau")
    assert np.all(np.isfinite(found)) and result["time"][-1] == pytest.approx(2.0)
    scale = np.maximum(1.0, np.abs(reference).max(axis=0))
    assert (np.abs(found - reference) / scale).max() < 1e-5


def test_a_light_hook_under_a_heavy_load_stays_with_dop853(built_fmu):
    """The crane's 1 kg hook under a 20 t load oscillates at about 250 rad/s between rope and
    sling: fast, but no decay, so the automatic choice never takes Radau (which would damp
    it): its run is DOP853's bit for bit, the same right-hand sides."""
    path = built_fmu(CRANE, backend="native")
    start = {"m0": 1.0, "m1": 2e4, "alpha0": 0.05, "alpha1": 0.1, "rtol": 1e-6, "atol": 1e-6}
    runs = [
        run_fmu(path, stop_time=2.0, output_interval=0.01, start_values={**start, **solver})
        for solver in ({}, {"solver": 2})
    ]
    for name in (*CRANE.state_names(), "n_rhs"):
        np.testing.assert_array_equal(runs[0][name], runs[1][name], err_msg=name)
    assert runs[0]["n_jacobians"][-1] == 0
