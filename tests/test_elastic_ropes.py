"""Elastic ropes (Link.rope_stiffness): a rope that stretches, goes slack and snaps taut, its
bob's reach r<i> a state. Checked against closed forms nobody here derived for this model: a
load dropped onto a rope (the meeting time of free fall, the peak of a spring's energy
balance), a load bouncing on a rope (half a spring cycle and a ballistic flight, repeated), a
taut elastic pendulum's two frequencies; and energy less the books. The model's checks
locate the slack and taut switches by scipy's event finder on the core's right-hand side, in
both formulations; the FMUs' checks by the FMUs' own located events, read at 50 Hz."""

import re

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from conical_pendulum import Link, Scene, SceneError
from conical_pendulum.analysis.compare import compare
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.analysis.simulate import simulate
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.builder.core import dependencies
from conical_pendulum.builder.core.equations import derive
from fmu_helpers import Instance, assert_model_exchange_follows
from formulations import assert_formulations_agree

G = 9.8
FORMULATIONS = ("expanded", "recursive")


def elastic(length=10.0, stiffness=1e6, mass=100.0, zeta=None, low=1.0, high=30.0, **fields):
    """An elastic rope of EA = stiffness [N] and damping ratio zeta with a load of mass [kg] at
    its end."""
    return Link(
        has_mass=False,
        rope=True,
        rope_min=low,
        rope_max=high,
        length=length,
        bob_mass=mass,
        rope_stiffness=stiffness,
        rope_damping=zeta,
        **fields,
    )


def vertical(formulation, **fields):
    """One elastic rope and its load, hanging straight down (the joint's angles 0)."""
    scene = Scene(links=(elastic(**fields),), formulation=formulation, outputs=("energy",))
    return scene, load_core(scene)


def run(scene, core, start, stop, events=(), inputs=None):
    """The core's right-hand side by scipy's DOP853 at 1e-12, from the start values by name,
    ended and restarted wherever the rope goes taut or slack (its stretch r0 - l0 crosses 0),
    as an FMU's located events do: no step straddles the law's switch. Returns each piece's
    solution, the times of those events and of `events` (each a state_event), and p."""
    names = scene.state_names()
    x = np.array(scene.initial_state({"alpha0": 0.0, "beta0": 0.0, **start}))
    p = np.array(scene.parameters(inputs))
    taut = x[names.index("r0")] > x[names.index("l0")]
    t, pieces, found = 0.0, [], [[] for _ in range(1 + len(events))]
    while t < stop:
        # the next switch: slack if taut, taut if slack (a restart sits on the last one's root)
        switch = state_event(scene, lambda v: v["r0"] - v["l0"], -1 if taut else 1)
        switch.terminal = True
        sol = solve_ivp(
            lambda t, x: core.rhs(x, p),
            (t, stop),
            x,
            method="DOP853",
            rtol=1e-12,
            atol=1e-12,
            events=(switch, *events),
            dense_output=True,
        )
        assert sol.success, sol.message
        pieces.append(sol)
        for k, times in enumerate(sol.t_events):
            found[k] += [time for time in times if time > t]
        t, x, taut = sol.t[-1], sol.y[:, -1], taut != (sol.status == 1)
    return pieces, found, p


def state_event(scene, expression, direction):
    """A scipy event on states by name: expression(values by name) crossing 0 in direction."""
    names = scene.state_names()

    def event(t, x):
        return expression(dict(zip(names, x)))

    event.direction = direction
    return event


def books(scene, core, p, x):
    """Energy less the books at state x."""
    values = dict(zip(scene.state_names(), x))
    return core.outputs(x, p)[scene.output_names().index("energy")] - sum(
        values[name] for name in scene.work_names()
    )


def drop(formulation, m=100.0, length=10.0, h=0.5, stiffness=1e6):
    """A load dropped from rest with h of slack onto an undamped rope: the relative errors of the
    time it meets the rope against sqrt(2 h / g) and of the tension where it stops against
    m g (1 + sqrt(1 + 2 k h / (m g))), k = EA / l, and the spread of energy less the books at the
    solver's steps over 1 s, relative to m g l."""
    scene, core = vertical(formulation, mass=m, length=length, stiffness=stiffness)
    stops = state_event(scene, lambda v: v["v_r0"], -1)
    pieces, (switches, stopped), p = run(scene, core, {"r0": length - h}, 1.0, (stops,))
    x = next(piece.sol(stopped[0]) for piece in pieces if piece.t[0] <= stopped[0] <= piece.t[-1])
    peak = core.outputs(x, p)[scene.output_names().index("T_rope0")]
    k = stiffness / length
    energies = [books(scene, core, p, x) for piece in pieces for x in piece.y.T]
    return {
        "meeting": abs(switches[0] / np.sqrt(2 * h / G) - 1),
        "peak": abs(peak / (m * G * (1 + np.sqrt(1 + 2 * k * h / (m * G)))) - 1),
        "books": np.ptp(energies) / (m * G * length),
    }


@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_a_load_dropped_onto_the_rope_meets_it_and_peaks_as_the_closed_form_says(formulation):
    """100 kg dropped with 0.5 m of slack onto 10 m of EA = 1e6 N."""
    errors = drop(formulation)
    assert errors["meeting"] < 1e-12 and errors["peak"] < 1e-11 and errors["books"] < 1e-10


def bounce_period(m, length, h, stiffness):
    """A load bouncing on an undamped rope, from rest with h of slack: a spring's half cycle about
    the static stretch s_e = m g / k, entered and left at the speed v0 = sqrt(2 g h), then a
    ballistic flight up and back (2 v0 / g)."""
    k, v0 = stiffness / length, np.sqrt(2 * G * h)
    omega, s_e = np.sqrt(k / m), m * G * length / stiffness
    return (np.pi + 2 * np.arctan(omega * s_e / v0)) / omega + 2 * v0 / G


def bounce(formulation, m=100.0, length=10.0, h=0.2, stiffness=1e6, snaps=100):
    """A load bouncing on an undamped rope for `snaps` periods: the snaps counted, the largest
    error of their times against the closed form's relative to the last, and the spread of
    energy less the books at the switches relative to m g l."""
    scene, core = vertical(formulation, mass=m, length=length, stiffness=stiffness)
    period, fall = bounce_period(m, length, h, stiffness), np.sqrt(2 * h / G)
    pieces, (switches,), p = run(scene, core, {"r0": length - h}, (snaps + 0.5) * period + fall)
    found = np.array(switches[::2])  # taut, slack, taut, ...
    expected = fall + period * np.arange(len(found))
    energies = [books(scene, core, p, piece.y[:, 0]) for piece in pieces]
    return {
        "snaps": len(found),
        "times": np.abs(found - expected).max() / found[-1],
        "books": np.ptp(energies) / (m * G * length),
    }


@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_an_undamped_bounce_keeps_its_period_and_energy_over_100_snaps(formulation):
    """100 kg on 10 m of EA = 1e6 N with 0.2 m of slack: the load meets the taut rope every
    bounce_period, 101 times, and energy less the books stays what it was."""
    errors = bounce(formulation)
    assert errors["snaps"] == 101 and errors["times"] < 1e-9 and errors["books"] < 1e-10


def bounce_stretch(t, m=100.0, length=10.0, h=0.2, stiffness=1e6):
    """The stretch of bounce()'s rope at the times t, in closed form: the fall onto the rope,
    then each period a spring's half cycle about s_e (s = s_e + A sin(omega tau - phi), from
    and back to 0) and a ballistic flight (s = -v0 tau + g tau^2 / 2)."""
    k, v0 = stiffness / length, np.sqrt(2 * G * h)
    omega, s_e = np.sqrt(k / m), m * G * length / stiffness
    fall, period = np.sqrt(2 * h / G), bounce_period(m, length, h, stiffness)
    spring = (np.pi + 2 * np.arctan(omega * s_e / v0)) / omega
    tau = np.mod(t - fall, period)
    flight = tau - spring
    return np.where(
        t < fall,
        -h + G * t**2 / 2,
        np.where(
            flight < 0,
            s_e + np.hypot(s_e, v0 / omega) * np.sin(omega * tau - np.arctan(omega * s_e / v0)),
            -v0 * flight + G * flight**2 / 2,
        ),
    )


# The drop and the bounce as an FMU runs them: 100 kg under 10 m of EA = 1e6 N, a master at 50 Hz
BOUNCING = Scene(links=(elastic(),), outputs=("energy",))
AT_REST = {"alpha0": 0.0, "beta0": 0.0}
# BDF (5) is left out: at these tolerances it stalls at a snap (docs/fmu.md, its solver's entry)
CS_SOLVERS = {"rk45": 1, "dop853": 2, "radau": 3, "auto": 4}


@pytest.mark.parametrize("backend, fmi_version", [("pythonfmu", 2), ("native", 2), ("native", 3)])
@pytest.mark.parametrize("solver", CS_SOLVERS)
def test_a_50_hz_master_reads_the_snap_load_it_cannot_sample(built_fmu, backend, fmi_version, solver):
    """A load dropped with 0.5 m of slack: the steps end on the snap (located inside them), and
    T_rope_peak0 reports the closed form's peak m g (1 + sqrt(1 + 2 k h / (m g))), which the
    tension sampled at 50 Hz misses; one snap, taut at the peak."""
    fmu = built_fmu(BOUNCING, backend=backend, fmi_version=fmi_version)
    run = run_fmu(
        fmu,
        stop_time=0.4,
        output_interval=0.02,
        start_values={**AT_REST, "r0": 9.5, "solver": CS_SOLVERS[solver], "rtol": 1e-12, "atol": 1e-12},
    )
    k, h, m = 1e6 / 10.0, 0.5, 100.0
    peak = m * G * (1 + np.sqrt(1 + 2 * k * h / (m * G)))
    assert run["T_rope_peak0"].max() == pytest.approx(peak, rel=1e-10)
    assert run["T_rope0"].max() < (1 - 1e-4) * peak  # what sampling sees
    assert list(run["snaps0"][[0, -1]]) == [0, 1] and run["taut0"][-1] == 1
    assert run["taut0"][0] == 0 and run["T_rope_peak0"][0] == 0.0


@pytest.mark.parametrize("solver", CS_SOLVERS)
def test_a_bouncing_load_follows_the_closed_form_through_its_located_snaps(built_fmu, solver):
    """20 bounces at 50 Hz at 1e-12: the stretch at every point within 1e-8 m of bounce_stretch
    (RK45 2.1e-9 m, the others below 1e-9), the snaps counted as the closed form counts them,
    energy less the books held."""
    fmu = built_fmu(BOUNCING, backend="native", fmi_version=2)
    stop = 20.5 * bounce_period(100.0, 10.0, 0.2, 1e6)
    run = run_fmu(
        fmu,
        stop_time=stop,
        output_interval=0.02,
        start_values={**AT_REST, "r0": 9.8, "solver": CS_SOLVERS[solver], "rtol": 1e-12, "atol": 1e-12},
    )
    assert np.abs(run["stretch0"] - bounce_stretch(run["time"])).max() < 1e-8
    fall = np.sqrt(2 * 0.2 / G)
    meetings = np.floor((run["time"] - fall) / bounce_period(100.0, 10.0, 0.2, 1e6)) + 1
    assert np.array_equal(run["snaps0"], np.maximum(meetings, 0)) and run["snaps0"][-1] == 21
    kept = run["energy"] - run["W_hoist"]
    assert np.ptp(kept) < 1e-9 * 100.0 * G * 10.0


@pytest.mark.parametrize("backend", ["pythonfmu", "native"])
def test_an_fmu_state_holds_what_the_steps_saw_of_the_rope(built_fmu, backend):
    """Saved between the snap and the peak, the state replays the next steps bit for bit,
    the peak the watch finds inside them included."""
    fmu = Instance(built_fmu(BOUNCING, backend=backend), start_values={**AT_REST, "r0": 9.5})
    watched = ("T_rope_peak0", "snaps0", "taut0", "r0", "v_r0")
    for _ in range(17):  # to 0.34 s: taut since 0.319 s, peaking at 0.37 s
        fmu.step(0.02)
    state, t = fmu.get_state(), fmu.time
    straight = [(fmu.step(0.02), fmu.get(*watched))[1] for _ in range(3)]
    fmu.set_state(state)
    fmu.time = t
    assert [(fmu.step(0.02), fmu.get(*watched))[1] for _ in range(3)] == straight
    assert max(peak for peak, *_ in straight) > fmu.get("T_rope0")[0]
    fmu.free_state(state)
    fmu.close()


def frequencies(formulation, m=50.0, length=8.0, stiffness=2e5):
    """At rest at its static reach L = l + m g / k, the linearized motion's frequencies (the
    Jacobian's eigenvalues) against the swing's sqrt(g / L), twice (two swing planes), and the
    stretch's sqrt(k / m): the largest relative error."""
    scene, core = vertical(formulation, mass=m, length=length, stiffness=stiffness)
    k = stiffness / length
    x = np.array(scene.initial_state({"alpha0": 0.0, "beta0": 0.0, "r0": length + m * G / k}))
    p = np.array(scene.parameters())
    names = ("alpha0", "beta0", "r0", "omega0", "delta0", "v_r0")
    moving = [scene.state_names().index(name) for name in names]
    jacobian = core.jacobian(x, p)[np.ix_(moving, moving)]
    found = np.sort(np.abs(np.linalg.eigvals(jacobian).imag))[::2]
    swing = np.sqrt(G / (length + m * G / k))
    expected = np.array([swing, swing, np.sqrt(k / m)])
    return float(np.abs(found / expected - 1).max())


@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_a_taut_elastic_pendulum_swings_and_stretches_at_its_two_frequencies(formulation):
    assert frequencies(formulation) < 1e-10


@pytest.mark.parametrize(
    "links, options",
    [
        ((elastic(),), {}),
        (
            (elastic(zeta=0.3, bob_force=True), Link(length=2.0, mass=3.0, bob_mass=1.0)),
            {"coupling": True},
        ),
        ((Link(length=2.0), elastic(length=6.0, zeta=0.1), Link(has_mass=False)), {"air_drag": True}),
        (
            (elastic(zeta=0.05), Link(has_mass=False, length=3.0), elastic(length=4.0)),
            {"joint_damping": True},
        ),
    ],
    ids=["load", "hook-and-link", "below-a-link", "two-elastic"],
)
def test_the_formulations_agree(links, options):
    """M, F, x', the books' rates and every output, the ropes taut or slack."""
    assert_formulations_agree(links, options, seed=7, input_range=3)


def test_the_recursive_dependencies_are_what_the_expressions_say():
    scene = Scene(
        links=(
            elastic(zeta=0.3, bob_force=True),
            Link(length=2.0, mass=3.0, bob_mass=1.0),
            elastic(length=4.0),
        ),
        coupling=True,
        joint_damping=True,
    )
    assert dependencies._chain(scene) == dependencies._symbolic(scene, derive(scene))


def test_a_rope_recoiling_faster_than_it_can_pull_pushes_nothing():
    """Stretched 1 cm but shortening at 1 m/s, the damping would push: the tension is 0, and the
    strain energy it still holds is lost to W_rope as it recoils."""
    scene, core = vertical("expanded", stiffness=1e6, zeta=0.5)
    x = np.array(scene.initial_state({"alpha0": 0.0, "beta0": 0.0, "r0": 10.01, "v_r0": -1.0}))
    p = np.array(scene.parameters())
    outputs = dict(zip(scene.output_names(), core.outputs(x, p)))
    assert outputs["T_rope0"] == 0.0 and outputs["stretch0"] == pytest.approx(0.01)
    rates = dict(zip(scene.state_names(), core.rhs(x, p)))
    assert rates["v_r0"] == pytest.approx(G, rel=1e-12)  # falling freely along the rope
    assert rates["W_rope"] == pytest.approx(-1e6 / 10.0 * 0.01 * 1.0, rel=1e-12)


def swinging_books():
    """A damped rope (zeta 0.05) on a hook with a link below, swinging on an accelerating support
    while the winch pays out, 6 s: the run, and the spread of energy less the books relative to
    the energy's largest."""
    scene = Scene(
        links=(
            elastic(length=6.0, stiffness=2e5, zeta=0.05, mass=20.0),
            Link(length=2.0, mass=30.0, bob_mass=50.0),
        ),
        coupling=True,
    )
    times = np.linspace(0, 6, 1201)
    inputs = {"v_hoist0": 0.3, "a_pivot_x": 1.5, "a_pivot_y": 4.0}
    result = simulate(
        scene, times, parameters=inputs, state={"beta0": 0.4, "r0": 5.8, "v_r0": -1.0}, rtol=1e-12, atol=1e-12
    )
    kept = result["energy"] - sum(result[name] for name in scene.work_names())
    return result, np.abs(kept - kept[0]).max() / np.abs(result["energy"]).max()


def test_energy_less_the_books_stays_constant_through_slack_and_snaps_with_the_winch_working():
    """It goes slack and snaps taut; energy less W_hoist, W_rope and W_pivot stays constant,
    and the damping took energy."""
    result, spread = swinging_books()
    assert (result["stretch0"] < 0).any() and (result["stretch0"] > 0).any()
    assert result["W_rope"][-1] < -1.0
    assert spread < 1e-8


@pytest.mark.parametrize(
    "fields, message",
    [
        ({"rope_stiffness": -1.0}, "link[0].rope.stiffness: must be a positive finite number, got -1.0"),
        ({"rope_stiffness": 1e6, "rope_damping": -0.1}, "link[0].rope.damping: must be a finite number >= 0"),
        ({"rope_damping": 0.1}, "link[0].rope.damping: 0.1 given, but rope 0 is inextensible"),
        ({"rope_stiffness": 1e6, "has_bob": False}, "link[0].rope: an elastic rope holds a bob at its end"),
    ],
)
def test_a_bad_elastic_rope_is_refused_naming_it(fields, message):
    link = Link(has_mass=False, rope=True, rope_min=1.0, rope_max=30.0, **fields)
    with pytest.raises(SceneError, match=re.escape(message)):
        Scene(links=(link, Link()) if not fields.get("has_bob", True) else (link,))


def test_a_stiffness_given_to_a_link_that_is_no_rope_is_refused():
    with pytest.raises(
        SceneError, match=r"link\[0\]\.rope\.stiffness: 1000000\.0 given, but link 0 is no rope"
    ):
        Scene(links=(Link(rope_stiffness=1e6),))


def test_an_elastic_rope_adds_its_reach_its_numbers_its_stretch_and_what_its_steps_saw():
    scene = Scene(links=(elastic(zeta=0.2), Link()))
    assert scene.state_names()[:10] == [
        "alpha0", "alpha1", "beta0", "beta1", "r0", "omega0", "omega1", "delta0", "delta1", "v_r0",
    ]  # fmt: skip
    assert scene.work_names() == ["W_hoist", "W_rope"]
    assert {"EA0", "zeta_rope0"} <= set(scene.parameter_names())
    assert scene.output_names()[-4:] == ["T_rope0", "P_hoist0", "stretch0", "taut_margin0"]
    assert [s.name for s in scene.rope_event_scalars()] == ["T_rope_peak0", "snaps0", "taut0"]
    assert dict(zip(scene.state_names(), scene.state_defaults()))["r0"] == 10.0  # taut, unstretched
    inextensible = Scene(links=(Link(has_mass=False, rope=True, rope_min=1.0, rope_max=30.0), Link()))
    assert inextensible.key() != scene.key() and "r0" not in inextensible.state_names()


# A crane's hook on an elastic rope, a load slung below, on a moving support, the winch paying out
SWUNG = Scene(
    links=(
        elastic(length=6.0, stiffness=5e5, zeta=0.1, mass=20.0),
        Link(has_mass=False, length=2.0, bob_mass=200.0),
    ),
    coupling=True,
)
SWINGING = {"v_hoist0": 0.2, "beta0": 0.2, "alpha1": 0.3, "a_pivot_x": 0.5, "r0": 6.02}


@pytest.mark.parametrize("backend, fmi_version", [("pythonfmu", 2), ("native", 2), ("native", 3)])
def test_its_fmus_follow_the_reference_and_keep_the_books(built_fmu, backend, fmi_version):
    fmu = built_fmu(SWUNG, backend=backend, fmi_version=fmi_version)
    comparison = compare(fmu, SWUNG, start_values=SWINGING, stop_time=5.0)
    assert comparison.passed(), comparison.report()
    result = comparison.result
    kept = result["energy"] - sum(result[name] for name in SWUNG.work_names())
    assert np.abs(kept - kept[0]).max() < 1e-8 * np.abs(result["energy"]).max()


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_model_exchange_follows_the_reference(built_fmu, fmi_version):
    assert_model_exchange_follows(
        built_fmu(SWUNG, backend="native", fmi_version=fmi_version), SWUNG, SWINGING, 5.0
    )


def joint_state(position, velocity):
    """alpha0, beta0, r0 and their rates of a bob at position with velocity (relative to the
    pivot): the 'Space' 'ZXY' joint puts it at r (sin a, -cos a cos b, -cos a sin b)."""

    def place(q):
        a, b, r = q
        return r * np.array([np.sin(a), -np.cos(a) * np.cos(b), -np.cos(a) * np.sin(b)])

    r = np.linalg.norm(position)
    q = np.array([np.arcsin(position[0] / r), np.arctan2(-position[2], -position[1]), r])
    step = 1e-20  # complex step: the Jacobian exact
    jacobian = np.array([place(q + 1j * step * np.eye(3)[k]).imag / step for k in range(3)]).T
    rates = np.linalg.solve(jacobian, velocity)
    names = ("alpha0", "beta0", "r0", "omega0", "delta0", "v_r0")
    return dict(zip(names, [*q, *rates]))


def against_mujoco(formulation, stop=1.5):
    """A load swung out slack on a rope that pays out while the support accelerates, against
    MuJoCo's spatial tendon whose spring acts only beyond its length (tests/mujoco_rope.py):
    the switches found, the largest difference of the load's path [m], of the tension relative
    to its largest, and of the rope's length [m]."""
    import mujoco_rope

    m, length, stiffness = 100.0, 10.0, 1e6
    pivot, hoist = (0.8, 2.0, -0.5), 0.3
    position, velocity = np.array([1.0, -9.9, 0.5]), np.array([0.5, 0.0, -0.3])
    times = np.linspace(0.0, stop, round(20 * stop) + 1)
    reference = mujoco_rope.simulate(
        m, stiffness, G, length, position, velocity, times, lambda t: hoist, lambda t: pivot
    )
    scene = Scene(
        links=(elastic(length=length, stiffness=stiffness, mass=m),), coupling=True, formulation=formulation
    )
    core = load_core(scene)
    inputs = {"v_hoist0": hoist, **dict(zip(("a_pivot_x", "a_pivot_y", "a_pivot_z"), pivot))}
    pieces, (switches,), p = run(scene, core, joint_state(position, velocity), times[-1], inputs=inputs)
    states = np.array([next(pc.sol(t) for pc in pieces if pc.t[0] <= t <= pc.t[-1]) for t in times])
    outputs = np.array([core.outputs(x, p) for x in states])
    names = scene.output_names()
    bob = outputs[:, [names.index(f"bob0_{c}") for c in "xyz"]]
    tension = outputs[:, names.index("T_rope0")]
    return {
        "switches": len(switches),
        "path": np.abs(bob - reference["load"]).max(),
        "tension": np.abs(tension - reference["tension"]).max() / np.abs(tension).max(),
        "length": np.abs(states[:, scene.state_names().index("l0")] - reference["length"]).max(),
    }


@pytest.mark.slow  # MuJoCo's RK4 at 1e-5 s with Python callbacks: some 10 s a simulated second
@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_it_follows_mujocos_tendon_in_3d_with_a_moving_support_and_a_winch(formulation):
    """It snaps taut and goes slack again; to MuJoCo's accuracy (some 4e-9 m and 1e-7 of the
    tension at its 1e-5 s step)."""
    found = against_mujoco(formulation)
    assert found["switches"] >= 2
    assert found["path"] < 1e-7 and found["tension"] < 1e-6 and found["length"] < 1e-10
