"""Restored FMU states are checked like values set through the API, in both FMUs.

A state that fails is refused with a message naming the field and its value (the native
FMU: fmi2Error; the pythonfmu FMU: fmi2Fatal, all that pythonfmu 0.7 returns for an
exception, after the same message as fmi2Error), and the instance stays exactly as it was
and answers fmi2Reset. Both FMUs' states hold the same ModelData (pendulum_model.c's), which
model_invalid checks. A mutation fuzz of serialized states (header intact, body
overwritten): each one is refused, or is taken and steps to finite outputs or to a
discarded step with a message; fmi2Reset works after every one.
"""

import ctypes
import math
import re
import struct
from collections import Counter

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model

from conical_pendulum.analysis.fmpy_runs import logging_callbacks
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.runtime.rules import SOLVERS, BadValue, check_value
from fmu_helpers import Instance
from test_stiff import light_chain

DISCARD, ERROR, FATAL = 2, 3, 4
STEP = 1 / 60
STEPS_BEFORE = 5  # communication steps before the state is taken: a step in flight
FUZZ_CASES = 500  # per FMU
STEP_COMPLETE = 4  # the native FMU's state word in stepComplete (fmi2_glue.c)


def real_names(instance):
    return [v.name for v in instance.md.modelVariables if v.type == "Real" and not v.name.startswith("der(")]


def integer_names(instance):
    return [v.name for v in instance.md.modelVariables if v.type in ("Integer", "Enumeration")]


def values(instance):
    """Every Real (but the native FMU's derivatives) and Integer of an instance."""
    return (
        instance.fmu.getReal([instance.vr[n] for n in real_names(instance)]),
        instance.fmu.getInteger([instance.vr[n] for n in integer_names(instance)]),
    )


def initialize(instance):
    instance.fmu.setupExperiment(startTime=0.0)
    instance.fmu.enterInitializationMode()
    instance.fmu.exitInitializationMode()
    instance.time = 0.0


def started(path, name="instance"):
    """An instance a few steps into the seed scenario (solver memory in use)."""
    instance = Instance(path, name=name, start_values={"alpha0": 0.6, "delta1": 0.4})
    for _ in range(STEPS_BEFORE):
        instance.step(STEP)
    return instance


def serialized_state(instance):
    state = instance.fmu.getFMUstate()
    data = instance.fmu.serializeFMUstate(state)
    instance.fmu.freeFMUstate(state)
    return data


# --- the two formats ----------------------------------------------------------------------


class NativeState:
    """The native FMU's serialized state: a header (magic, size, GUID), then fmi_layer.c's
    Saved as it lies in memory: the FMI layer's machine (state word, time, last successful
    time), then pendulum_model.c's ModelData, which this layout follows field by field."""

    refused_status = ERROR
    MODEL = 24  # where the ModelData begins, after the machine
    # what the state holds before the ModelData: (offset, struct format) by name
    OWN = (("state", 0, "i"), ("time", 8, "d"), ("last_successful_time", 16, "d"), ("mode", 0, "i"))
    STEPPING = STEP_COMPLETE  # the state word, or the mode, of a stepping instance

    def __init__(self, instance, data):
        reals = real_names(instance)
        n_state = sum(v.causality == "output" and v.initial == "exact" for v in instance.md.modelVariables)
        n_input = sum(v.causality == "input" for v in instance.md.modelVariables)
        self.reals = {name: k for k, name in enumerate(reals)}
        size = self.body_size(data)
        self.header = len(data) - size
        self.data = bytes(data)
        after_r = self.MODEL + 8 * len(reals)
        flight = after_r + 32  # cosim.h's cp_flight, its cp_step after live, reserved, t_point
        n_elastic = sum(v.name.startswith("taut_margin") for v in instance.md.modelVariables)
        # cosim.h's cp_jacobian_record, after the flight's rows, t_inputs, inputs and ropes' watch
        record = flight + 96 + 8 * (10 * n_state + 1 + 3 * (n_input + 1) + 3 * (n_elastic + 1))
        self.offsets = {name: at for name, at, _ in self.OWN} | {
            "solver": after_r,
            "max_steps": after_r + 4,
            "across_points": after_r + 8,
            "tolerance": after_r + 16,
            "stop_time": after_r + 24,
            "live": flight,
            "t_point": flight + 8,
            "t0": flight + 16,
            "t1": flight + 24,
            "h": flight + 32,
            "fsal": flight + 40,
            "dense": flight + 44,
            "method": flight + 48,
            "next": flight + 52,
            "stiff_steps": flight + 56,
            "h_old": flight + 64,
            "rows": flight + 96,
            "jac_valid": record,
            "lu_valid": record + 8,
            "factors_method": record + 12,
            "rho": record + 16,
            "factors_h": record + 24,
            "jacobian_x": record + 32,  # the state it was evaluated at, then the core's p
        }
        self.fields = {name: kind for name, _, kind in self.OWN} | {
            "solver": "i",
            "max_steps": "i",
            "across_points": "i",
            "tolerance": "d",
            "live": "i",
            "h": "d",
            "fsal": "i",
            "dense": "i",
            "method": "i",
            "next": "i",
            "stiff_steps": "i",
            "jac_valid": "i",
            "lu_valid": "i",
            "factors_method": "i",
        }
        # every byte means something: the solvers' matrices and scratch are the instance's own
        self.meaningful = np.arange(size)
        reals_now, integers_now = values(instance)  # taken where the state was
        assert (
            [self.get(name) for name in reals],
            [self.get(name) for name in integer_names(instance)],
            self.time(self.data),
            self.get("mode"),
        ) == (reals_now, integers_now, instance.time, self.STEPPING), "not the layout assumed"

    @staticmethod
    def body_size(data):
        return struct.unpack_from("<I", data, 4)[0]  # the header's: sizeof the Saved

    def offset(self, field):
        return self.MODEL + 8 * self.reals[field] if field in self.reals else self.offsets[field]

    def get(self, field, data=None):
        kind = self.fields.get(field, "d")
        return struct.unpack_from("<" + kind, data or self.data, self.header + self.offset(field))[0]

    def with_field(self, field, value):
        kind = self.fields.get(field, "d")
        return self.overwritten(self.offset(field), struct.pack("<" + kind, value))

    def overwritten(self, at, raw, data=None):
        """The bytes (the saved ones unless given) with raw written at body offset at."""
        data = bytearray(data or self.data)
        data[self.header + at : self.header + at + len(raw)] = raw
        return bytes(data)

    def time(self, data):
        return self.get("time", data)


class PythonState(NativeState):
    """The pythonfmu FMU's serialized state: the slave's mode (runtime/slave.py's OWN), then
    the same ModelData, no header."""

    refused_status = FATAL
    MODEL = 8
    OWN = (("mode", 0, "i"),)
    STEPPING = 2  # the slave's MODES.index("step")

    def __init__(self, instance, data):
        self.saved_time = instance.time
        super().__init__(instance, data)

    @staticmethod
    def body_size(data):
        return len(data)

    def time(self, data):
        return self.saved_time  # the pythonfmu FMU's state holds no time: doStep says it


@pytest.fixture(params=["native", "pythonfmu"])
def backend(request):
    return request.param


@pytest.fixture
def path(backend, request):
    return request.getfixturevalue("native_seed_fmu" if backend == "native" else "seed_fmu")


def codec(backend, instance, data):
    return (NativeState if backend == "native" else PythonState)(instance, data)


# --- good states -----------------------------------------------------------------------------


def restore(instance, data):
    state = instance.fmu.deSerializeFMUstate(data)
    instance.fmu.setFMUstate(state)
    instance.fmu.freeFMUstate(state)


def stepped(instance, steps=3):
    """The values after each of a few steps."""
    seen = []
    for _ in range(steps):
        instance.step(STEP)
        seen.append(values(instance))
    return seen


def test_every_state_an_instance_gives_is_taken_back(path):
    """Before initialization, after steps (replayed bit for bit) and after a discarded step."""
    fresh = Instance(path, initialize=False)
    restore(fresh, serialized_state(fresh))
    initialize(fresh)
    fresh.close()
    fmu = started(path)
    data, t = serialized_state(fmu), fmu.time
    straight = stepped(fmu)
    restore(fmu, data)
    fmu.time = t
    assert stepped(fmu) == straight
    fmu.close()
    failed = Instance(path, start_values={"max_steps": 1})
    with pytest.raises(FMICallException) as discard:
        failed.step(10.0)
    assert discard.value.status == DISCARD
    restore(failed, serialized_state(failed))
    failed.close()


# --- a bad state, field by field --------------------------------------------------------------


def rule_message(field, value):
    """What runtime.rules says of the value, as a message names it (the FMUs say the same)."""
    name, quantity = ("tolerance (from setupExperiment)", "rtol") if field == "tolerance" else (field, None)
    with pytest.raises(BadValue) as refusal:
        check_value(name, value, quantity)
    return str(refusal.value)


# (what, field, value, native value where it differs, the message after "the state's";
# None: runtime.rules' message for the value)
CASES = [
    ("NaN statistic", "n_rhs", math.nan, None, "n_rhs = nan: must be finite"),
    ("fractional statistic", "n_steps", 1.5, None, "n_steps = 1.5: a count must be a whole number"),
    ("negative statistic", "n_rejected", -1.0, None, "n_rejected = -1.0: a count must be a whole"),
    ("NaN state", "alpha0", math.nan, None, "alpha0 = nan: must be finite"),
    ("infinite state", "delta1", -math.inf, None, "delta1 = -inf: must be finite"),
    ("bad parameter", "l0", -1.0, None, "l0 = -1.0: a length must be positive"),
    ("negative step", "h", -1.0, None, "h = -1.0: the solver's carried step cannot be negative"),
    ("NaN step", "h", math.nan, None, "h = nan: must be finite"),
    ("no FMI state", "mode", 6, None, "{}"),
    ("unknown solver", "solver", 6, None, "solver = {}: choose 0 to"),
    ("unknown step method", "method", 7, None, "step in flight: method = 7: must be from 1 to 5"),
    ("a step of the automatic choice", "method", 4, None, "step in flight: method = 4: the automatic"),
    ("unknown next method", "next", 0, None, "step in flight: next = 0: must be from 2 to 3"),
    ("negative stiffness count", "stiff_steps", -1, None, "step in flight: stiff_steps = -1: must be from 0"),
    ("NaN old step", "h_old", math.nan, None, "step in flight: h_old = nan: must be finite"),
    ("Jacobian flag 2", "jac_valid", 2, None, "Jacobian: jac_valid = 2: must be 0 or 1"),
    (
        "factors without a Jacobian",
        "lu_valid",
        1,
        None,
        "Jacobian: method = 0, lu_valid = 1 with jac_valid = 0",
    ),
    (
        "NaN spectral radius",
        "rho",
        math.nan,
        None,
        "Jacobian: method = 0, lu_valid = 0 with jac_valid = 0, rho = nan",
    ),
    ("rtol 0", "rtol", 0.0, None, None),
    ("max_steps 0", "max_steps", 0, None, "max_steps = 0: must be at least 1"),
    ("fsal 2", "fsal", 2, None, "fsal = 2: must be 0 or 1"),
    ("negative tolerance", "tolerance", -1.0, None, None),
]


@pytest.mark.parametrize("what, field, value, native_value, message", CASES, ids=[c[0] for c in CASES])
def test_a_bad_state_is_refused_naming_it_and_changes_nothing(
    backend, path, what, field, value, native_value, message
):
    fmu, twin = started(path), started(path, name="twin")
    data = serialized_state(fmu)
    state = codec(backend, fmu, data)
    if backend == "native" and native_value is not None:
        value = native_value
    if message is None:
        message = rule_message(field, value)
    elif what == "no FMI state":  # a state word, or mode, that names none
        message = (
            "instance state = 6: not one state a Co-Simulation instance can be in"
            if backend == "native"
            else "mode = 6: choose one of 0 (instantiated)"
        )
    message = message.format(value)
    refused_and_unchanged(backend, fmu, twin, state, state.with_field(field, value), message)


def refused_and_unchanged(backend, fmu, twin, state, bad, message):
    """The bad state's bytes refused both ways in, naming `message`; the instance as it was
    (it steps as its twin does) and reset works."""
    before = values(fmu)
    refusals = []  # (function, status)
    if backend == "native":  # both ways in: a state in memory, and bytes
        saved = fmu.fmu.getFMUstate()
        body = bad[state.header :]
        ctypes.memmove(saved.value, body, len(body))
        with pytest.raises(FMICallException) as failure:
            fmu.fmu.setFMUstate(saved)
        refusals.append(("fmi2SetFMUstate", failure.value.status))
        fmu.fmu.freeFMUstate(saved)
        with pytest.raises(FMICallException) as failure:
            fmu.fmu.deSerializeFMUstate(bad)
        refusals.append(("fmi2DeSerializeFMUstate", failure.value.status))
    else:
        restored = fmu.fmu.deSerializeFMUstate(bad)
        with pytest.raises(FMICallException) as failure:
            fmu.fmu.setFMUstate(restored)
        refusals.append(("fmi2SetFMUstate", failure.value.status))
        fmu.fmu.freeFMUstate(restored)
    for function, status in refusals:
        assert status == state.refused_status
        wanted = f"{function}: the state's {message}"
        assert any(s == ERROR and text.startswith(wanted) for s, text in fmu.messages), (
            wanted,
            fmu.messages[-3:],
        )
    assert values(fmu) == before
    fmu.step(STEP)
    twin.step(STEP)
    assert values(fmu) == values(twin)
    fmu.fmu.reset()
    initialize(fmu)
    fmu.step(STEP)
    fmu.close()
    twin.close()


def radau_pair(path, solver="radau"):
    """Two instances a few steps of an implicit solver into the seed scenario, its factors in use."""
    start = {"alpha0": 0.6, "delta1": 0.4, "solver": SOLVERS.index(solver)}
    fmu, twin = (Instance(path, name=name, start_values=start) for name in ("instance", "twin"))
    for _ in range(STEPS_BEFORE):
        fmu.step(STEP)
        twin.step(STEP)
    return fmu, twin


RECORD_CASES = [
    ("NaN step size", "factors_h", math.nan, "Jacobian: the factors' step size is nan: must be > 0"),
    ("factors of no solver", "factors_method", 7, "Jacobian: method = 7, lu_valid = 1 with jac_valid = 1"),
    (
        "NaN where it was evaluated",
        "jacobian_x",
        math.nan,
        "Jacobian evaluated at alpha0 = nan: must be finite",
    ),
]


@pytest.mark.parametrize("what, field, value, message", RECORD_CASES, ids=[c[0] for c in RECORD_CASES])
def test_a_jacobian_record_that_cannot_be_remade_is_refused(backend, path, what, field, value, message):
    """A state holds where Radau's Jacobian was evaluated and the step size of its factors
    (cosim.h's cp_jacobian_record), from which they are made again: both must be numbers."""
    fmu, twin = radau_pair(path)
    state = codec(backend, fmu, serialized_state(fmu))
    assert state.get("lu_valid") == 1
    refused_and_unchanged(backend, fmu, twin, state, state.with_field(field, value), message)


@pytest.mark.parametrize("solver", ["radau", "bdf"])
def test_implicit_matrices_are_made_again_bit_for_bit_where_a_state_is_restored(backend, path, solver):
    """The matrices stay out of the state: a state restored in another instance, and in its
    own after it went on, steps as the instance it was taken from, statistics and all."""
    fmu, twin = radau_pair(path, solver)
    data, t = serialized_state(fmu), fmu.time
    assert codec(backend, fmu, data).get("lu_valid") == 1
    straight = stepped(fmu)
    restore(fmu, data)
    fmu.time = t
    assert stepped(fmu) == straight
    other = Instance(path, name="other", start_values={"solver": SOLVERS.index("rk4")})
    other.step(STEP)
    restore(other, data)
    other.time = t
    assert stepped(other) == straight
    for instance in (fmu, twin, other):
        instance.close()


def test_a_state_grows_with_the_chain_not_with_its_jacobian():
    """What a state holds of the model is O(n): the 20-link chain's (80 states) is smaller
    than one 80 x 80 matrix, where the Jacobian and its two factors took four (258,648 bytes)."""
    core = load_core(light_chain(20))
    states = len(core.STATE_NAMES)
    assert states >= 80
    assert len(core.Model().data) < 8 * states**2


def test_a_co_simulation_state_is_no_model_exchange_state(native_seed_fmu):
    fmu = started(native_seed_fmu)
    data = serialized_state(fmu)
    messages = []
    callbacks = logging_callbacks(lambda status, text: messages.append((status, text)))
    model = FMU2Model(
        guid=fmu.md.guid,
        unzipDirectory=fmu.unzipdir,
        modelIdentifier=fmu.md.modelExchange.modelIdentifier,
        instanceName="me",
    )
    model.instantiate(callbacks=callbacks, loggingOn=True)
    with pytest.raises(FMICallException) as failure:
        model.deSerializeFMUstate(data)
    assert failure.value.status == ERROR
    assert (
        ERROR,
        "fmi2DeSerializeFMUstate: the state's instance state = 4: not one state a "
        "Model Exchange instance can be in",
    ) in messages
    model.reset()
    model.freeInstance()
    fmu.close()


def test_reset_and_free_state_are_never_refused(native_seed_fmu):
    """Whatever the instance holds: here a state word that is no state, written in place
    (Instance begins with its Machine, which begins with the state word)."""
    fmu = started(native_seed_fmu)
    saved = fmu.fmu.getFMUstate()
    word = ctypes.c_int.from_address(fmu.fmu.component)
    assert word.value == STEP_COMPLETE
    word.value = 0
    with pytest.raises(FMICallException):
        fmu.fmu.getReal([0])
    fmu.fmu.freeFMUstate(saved)
    fmu.fmu.reset()
    initialize(fmu)
    fmu.step(STEP)
    fmu.close()


# --- the fuzz ---------------------------------------------------------------------------------

SPECIAL = [math.nan, math.inf, -math.inf, -1.0, 1e308, -1e308, 5e-324, 0.0, 0.5, 2.0**53]


def mutation(state, rng):
    """The saved bytes with one to three overwrites of the body: doubles, int32s, int64s, bytes."""
    data = state.data
    for _ in range(1 if rng.random() < 0.75 else int(rng.integers(2, 4))):
        kind = rng.integers(6)
        if kind == 0:
            raw = struct.pack("<d", SPECIAL[rng.integers(len(SPECIAL))])
        elif kind == 1:
            raw = struct.pack("<i", [-1, 2**31 - 1, -(2**31), 2, 3, 7][rng.integers(6)])
        elif kind == 2:
            raw = struct.pack("<q", [2**63 - 1, -1, 2**53 + 1][rng.integers(3)])
        elif kind == 3:
            raw = struct.pack("<d", float(rng.standard_normal()) * 10.0 ** int(rng.integers(-12, 12)))
        else:
            raw = rng.bytes(int(rng.integers(1, 9)))
        size = len(data) - state.header
        if rng.random() < 0.8:  # a field that means something
            at = int(rng.choice(state.meaningful))
            at = at - at % 8 if rng.random() < 0.75 else at  # aligned, mostly
        else:
            at = int(rng.integers(0, size))
        at = min(at, size - len(raw))
        data = state.overwritten(at, raw, data)
    return data


def outcome(fmu, state, data):
    """What restoring these bytes came to: refused, ran (finite outputs), discarded, or else."""
    fmu.messages.clear()
    restored = None
    try:
        restored = fmu.fmu.deSerializeFMUstate(data)
        fmu.fmu.setFMUstate(restored)
    except FMICallException as exc:
        said = any(s == ERROR and "the state's" in text for s, text in fmu.messages) or any(
            "not a state of this FMU" in text for s, text in fmu.messages
        )
        return "refused" if exc.status == state.refused_status and said else f"refused badly: {exc}"
    finally:
        if restored is not None:
            fmu.fmu.freeFMUstate(restored)
    try:
        fmu.fmu.doStep(currentCommunicationPoint=state.time(data), communicationStepSize=STEP)
    except FMICallException as exc:
        if exc.status == DISCARD and any(s == DISCARD and text for s, text in fmu.messages):
            return "discarded"
        return f"doStep: {exc} {fmu.messages[-1:]}"
    reals, _ = values(fmu)
    return "ran" if all(math.isfinite(v) for v in reals) else f"non-finite outputs: {reals}"


def test_mutated_states_are_refused_or_run_to_finite_outputs(backend, path):
    fmu = started(path)
    state = codec(backend, fmu, serialized_state(fmu))
    rng = np.random.default_rng(18)
    outcomes, named = Counter(), Counter()  # what came of them; what the refusals named
    for _ in range(FUZZ_CASES):
        result = outcome(fmu, state, mutation(state, rng))
        outcomes[result] += 1
        if result == "refused":
            text = next(text for s, text in fmu.messages if s == ERROR)
            found = re.search(r"the state's (.+?) = |(not a state of this FMU)|the state's (\w+)", text)
            named[re.sub(r"\d+$", "#", next(g for g in found.groups() if g))] += 1
        fmu.fmu.reset()  # every time: fmpy raises if it is not fmi2OK
        initialize(fmu)
    print(
        f"\n{backend}: {FUZZ_CASES} mutated states: {dict(outcomes)}; the refusals named "
        f"{len(named)} fields, most often {dict(named.most_common(8))}"
    )
    assert set(outcomes) <= {"refused", "ran", "discarded"}, outcomes
    assert outcomes["refused"] and outcomes["ran"]
    fmu.close()
