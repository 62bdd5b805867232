"""Loads (a bob's `load = true`, Link.bob_load): the bob's mass m<i> is a tunable parameter that
a host changes at a communication point (Model Exchange: in event mode), as when a load is set
down, picked up or released; the state keeps its angles and rates, and the energy's jump goes
into the book W_load, so that energy less the books stays constant. The crane scene's load is
one (scenes/crane.toml)."""

import shutil
from pathlib import Path

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model

from conical_pendulum import Link, Scene, SceneError
from conical_pendulum.analysis.fmpy_runs import logging_callbacks
from conical_pendulum.builder.core import dependencies
from conical_pendulum.builder.core.equations import derive
from conical_pendulum.builder.fmi.variables import variables
from conical_pendulum.builder.models.pendulum import DEFAULT_SETTINGS
from conical_pendulum.scene import load_scene, scene_from_dict
from fmu_helpers import INSTANCES, Instance3

G = 9.8
ROOT = Path(__file__).resolve().parents[1]
CRANE = load_scene(ROOT / "scenes" / "crane.toml")
# swinging, hoisted and on an accelerating trolley when the load is set down
START = {"beta0": 0.2, "beta1": 0.1, "omega1": 0.3, "v_hoist0": -0.5, "a_pivot_x": 0.3}
# what the change keeps: the angles, their rates, the rope's length (the books aside)
MOTION = [name for name in CRANE.state_names() if name not in CRANE.work_names()]
KINDS = [("pythonfmu", 2), ("native", 2), ("native", 3)]


def values(fmu) -> dict:
    names = ["energy", "m1", *CRANE.state_names()]
    return dict(zip(names, fmu.get(*names)))


def kept(found: dict) -> float:
    """Energy less the books."""
    return found["energy"] - sum(found[name] for name in CRANE.work_names())


def test_the_crane_scenes_load_is_a_load_and_adds_its_book():
    assert CRANE.loads() == [1]
    assert CRANE.work_names() == ["W_pivot", "W_hoist", "W_load"]
    found = {v.name: v for v in variables(CRANE, DEFAULT_SETTINGS, "native")}
    assert (found["m1"].causality, found["m1"].variability) == ("parameter", "tunable")
    assert found["m0"].variability == "fixed"
    assert "a load: tunable" in found["m1"].description
    assert found["W_load"].initial == "exact" and found["der(W_load)"].depends_on == ()
    assert found["m1"].array is None  # an FMI 3.0 array has one variability: m0 is fixed


@pytest.mark.parametrize(
    "bob, kinematics, message",
    [
        ({"mass": 5.0, "load": 1}, "consistent", "link[0].bob.load: expected true or false, got 1"),
        ({"mass": 5.0, "load": True}, "pydy-example", "link[0].bob.load: loads need kinematics 'consistent'"),
    ],
)
def test_a_bad_load_is_refused_naming_it(bob, kinematics, message):
    with pytest.raises(SceneError) as refused:
        scene_from_dict({"kinematics": kinematics, "link": [{"bob": bob}]})
    assert message in str(refused.value)


def test_a_load_needs_a_bob():
    with pytest.raises(SceneError, match=r"link\[1\].bob.load: link 1 has no bob to be a load"):
        Scene(links=(Link(), Link(has_bob=False, bob_load=True)))


@pytest.mark.parametrize("backend, fmi_version", KINDS)
def test_a_load_set_down_keeps_the_velocities_and_books_the_energys_jump(built_fmu, backend, fmi_version):
    """The load (2000 kg, some 16 m below the trolley) set down to 50 kg at 2 s while it swings
    and is hoisted: the state but the books as it was, the energy's jump (mostly the weight's
    potential) in W_load, and energy less the books constant before, across and after."""
    fmu = INSTANCES[fmi_version](
        built_fmu(CRANE, backend=backend, fmi_version=fmi_version), start_values=START
    )
    start = kept(values(fmu))
    for _ in range(4):
        fmu.step(0.5)
    before = values(fmu)
    fmu.set({"m1": 50.0})
    after = values(fmu)
    assert after["m1"] == 50.0
    assert [after[name] for name in MOTION] == [before[name] for name in MOTION]
    jump = after["energy"] - before["energy"]
    assert jump > 1e5  # 1950 kg less at Y = -16 m: 3e5 J of potential energy
    assert after["W_load"] - before["W_load"] == pytest.approx(jump, rel=1e-12)
    assert [after[name] for name in ("W_pivot", "W_hoist")] == [
        before[name] for name in ("W_pivot", "W_hoist")
    ]
    for _ in range(4):  # the integration restarts at the point, with the new mass
        fmu.step(0.5)
    final = values(fmu)
    assert final["l0"] == pytest.approx(12.0 - 0.5 * 4.0, abs=1e-12)
    energy = max(abs(before["energy"]), abs(final["energy"]))
    assert max(abs(kept(v) - start) for v in (before, after, final)) < 1e-11 * energy
    fmu.close()


@pytest.mark.parametrize("backend, fmi_version", KINDS)
@pytest.mark.parametrize(
    "mass, message",
    [
        (0.0, "m1 = 0.0: a bob mass must be positive"),
        (-50.0, "m1 = -50.0: a bob mass must be positive"),
        (float("nan"), "m1 = nan: must be finite"),
    ],
)
def test_a_refused_mass_is_named_and_leaves_everything_as_it_was(
    built_fmu, backend, fmi_version, mass, message
):
    fmu = INSTANCES[fmi_version](
        built_fmu(CRANE, backend=backend, fmi_version=fmi_version), start_values=START
    )
    fmu.step(0.5)
    before = values(fmu)
    with pytest.raises(FMICallException):
        fmu.set({"m1": mass})
    assert message in fmu.texts(), fmu.messages
    assert values(fmu) == before
    if backend == "pythonfmu":  # fmi2Fatal: FMI 2.0 allows no other call
        fmu.close(after_fatal=True)
        return
    fmu.step(0.5)  # as if nothing had been set
    fmu.close()


@pytest.mark.parametrize("backend, fmi_version", KINDS)
def test_fmu_states_carry_the_masses_and_the_books(built_fmu, backend, fmi_version):
    """A state saved before the load is set down goes back to the load and its book; one saved
    after it, serialized and restored, to the new mass, its book and the same continuation."""
    fmu = INSTANCES[fmi_version](
        built_fmu(CRANE, backend=backend, fmi_version=fmi_version), start_values=START
    )
    fmu.step(1.0)
    loaded = fmu.get_state()
    fmu.set({"m1": 50.0})
    set_down = fmu.serialize(fmu.get_state())
    fmu.step(1.0)
    continued = values(fmu)
    fmu.set_state(loaded)
    fmu.time = 1.0
    assert values(fmu)["m1"] == 2000.0 and values(fmu)["W_load"] == 0.0
    fmu.set_state(fmu.deserialize(set_down))
    restored = values(fmu)
    assert restored["m1"] == 50.0 and restored["W_load"] > 1e5
    fmu.step(1.0)
    assert values(fmu) == continued
    fmu.close()


def me_fmi2(path):
    """An FMI 2.0 Model Exchange instance in event mode after initialization, with an fmpy-like
    face: set, get, event mode, discrete states, its messages' texts; close removes what it
    extracted."""
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    messages = []
    unzipped = extract(str(path))
    fmu = FMU2Model(
        guid=md.guid,
        unzipDirectory=unzipped,
        modelIdentifier=md.modelExchange.modelIdentifier,
        instanceName="me",
    )
    fmu.instantiate(callbacks=logging_callbacks(lambda status, text: messages.append(text)), loggingOn=True)
    fmu.setupExperiment(startTime=0.0)
    fmu.setReal([vr[name] for name in START], list(START.values()))
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    return {
        "set": lambda name, value: fmu.setReal([vr[name]], [value]),
        "get": lambda *names: fmu.getReal([vr[name] for name in names]),
        "events": fmu.enterEventMode,
        "continuous": fmu.enterContinuousTimeMode,
        "update": lambda: fmu.newDiscreteStates()[3],  # valuesOfContinuousStatesChanged
        "texts": lambda: " ".join(messages),
        "close": lambda: (fmu.terminate(), fmu.freeInstance(), shutil.rmtree(unzipped, ignore_errors=True)),
    }


def me_fmi3(path):
    """The same of an FMI 3.0 Model Exchange instance."""
    fmu = Instance3(path, interface="ModelExchange", start_values=START)
    return {
        "set": lambda name, value: fmu.fmu.setFloat64([fmu.vr[name]], [value]),
        "get": fmu.get,
        "events": fmu.fmu.enterEventMode,
        "continuous": fmu.fmu.enterContinuousTimeMode,
        "update": lambda: fmu.fmu.updateDiscreteStates()[3],
        "texts": fmu.texts,
        "close": fmu.close,
    }


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_model_exchange_takes_a_load_in_event_mode_and_says_the_states_changed(built_fmu, fmi_version):
    """In event mode the change books W_load and the next fmi2NewDiscreteStates
    (fmi3UpdateDiscreteStates) says valuesOfContinuousStatesChanged, once; in continuous-time
    mode a tunable parameter is refused, naming it, and nothing changes."""
    path = built_fmu(CRANE, backend="native", fmi_version=fmi_version)
    fmu = (me_fmi2 if fmi_version == 2 else me_fmi3)(path)
    assert not fmu["update"]()
    fmu["continuous"]()
    names = ("energy", "W_load", "m1", "omega1")
    before = fmu["get"](*names)
    with pytest.raises(FMICallException):
        fmu["set"]("m1", 50.0)
    assert (
        "m1 is a tunable parameter: it may be set in event mode, not in continuous-time mode"
        in fmu["texts"]()
    )
    assert fmu["get"](*names) == before
    fmu["events"]()
    fmu["set"]("m1", 50.0)
    assert fmu["update"]() and not fmu["update"]()
    energy, book, mass, rate = fmu["get"](*names)
    assert (mass, rate) == (50.0, before[3])
    assert book - before[1] == pytest.approx(energy - before[0], rel=1e-12) and book > 1e5
    fmu["continuous"]()
    fmu["close"]()


# six links on a rope, every bob a load: the recursive formulation (chain.c's energy and books)
LONG = Scene(
    links=(Link(has_mass=False, rope=True, rope_min=1.0, rope_max=30.0, length=6.0, bob_load=True),)
    + (Link(length=2.0, mass=3.0, bob_mass=10.0, bob_load=True),) * 5,
    coupling=True,
)


def test_the_recursive_formulation_books_a_loads_change(built_fmu):
    """Native FMI 2.0, a chain long enough for the recursive formulation: the lowest load set
    down to 1 kg while the chain swings on a hoisted rope and an accelerating support."""
    assert LONG.resolved_formulation() == "recursive" and LONG.loads() == list(range(6))
    fmu = INSTANCES[2](
        built_fmu(LONG, backend="native"), start_values={"beta0": 0.3, "alpha3": 0.2, "v_hoist0": -0.3}
    )
    fmu.set({"a_pivot_x": 0.5})
    names = ["energy", *LONG.state_names()]

    def found():
        got = dict(zip(names, fmu.get(*names)))
        return got, got["energy"] - sum(got[name] for name in LONG.work_names())

    fmu.step(1.0)
    before, start = found()
    fmu.set({"m5": 1.0})
    after, kept = found()
    assert after["W_load"] - before["W_load"] == pytest.approx(after["energy"] - before["energy"], rel=1e-12)
    assert abs(after["W_load"]) > 100.0 and kept == pytest.approx(start, rel=1e-14)
    fmu.step(1.0)
    assert found()[1] == pytest.approx(start, rel=1e-10)
    fmu.close()


def test_the_dependencies_of_a_loads_book_are_none_in_both_formulations():
    scene = Scene(links=LONG.links[:3], coupling=True)
    chain, symbolic = dependencies._chain(scene), dependencies._symbolic(scene, derive(scene))
    assert chain == symbolic and chain["der(W_load)"] == frozenset()
