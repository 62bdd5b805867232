"""The native FMU's FMI 2.0 state machine: every function called in every state an instance can
be in, for Co-Simulation and Model Exchange, against the standard's tables written out below
(independently of fmi2_glue.c's); and fmi2SetDebugLogging with the model description's log
categories."""

import shutil
import xml.etree.ElementTree as ET
import zipfile
from ctypes import (
    CDLL,
    POINTER,
    byref,
    c_char,
    c_char_p,
    c_double,
    c_int,
    c_size_t,
    c_uint,
    c_void_p,
    create_string_buffer,
)

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException, calloc, free
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2EventInfo,
)

from conical_pendulum import Scene
from conical_pendulum.builder.fmi.contract import LOG_CATEGORIES

OK, DISCARD, ERROR = 0, 2, 3
CO_SIMULATION, MODEL_EXCHANGE = 1, 0  # fmi2Type

# FMI 2.0, section 4.2.4 (Co-Simulation) and section 3.2.3 (Model Exchange), "State Machine of
# Calling Sequence": the standard's tables of the states each function may be called in (the
# text of the 2.0.x releases), in the columns of the states an instance of this FMU can be in.
# Not entered, so not columns: start/end (no instance); stepInProgress and stepCanceled (an
# asynchronous fmi2DoStep: this one never returns fmi2Pending); error and fatal (a refused call
# leaves the instance in its state; fmi2Fatal is never returned). "x": allowed; ".": not; a
# number: allowed if the standard's condition of that number holds (CONDITIONS).
CO_SIMULATION_TABLE = """
                              instantiated initializationMode stepComplete stepFailed terminated
fmi2SetDebugLogging                x            x                x           x          x
fmi2FreeInstance                   x            x                x           x          x
fmi2SetupExperiment                x            .                .           .          .
fmi2EnterInitializationMode        x            .                .           .          .
fmi2ExitInitializationMode         .            x                .           .          .
fmi2Terminate                      .            .                x           x          .
fmi2Reset                          x            x                x           x          x
fmi2GetReal                        .            2                x           8          x
fmi2GetInteger                     .            2                x           8          x
fmi2GetBoolean                     .            2                x           8          x
fmi2GetString                      .            2                x           8          x
fmi2SetReal                        1            3                6           .          .
fmi2SetInteger                     1            3                6           .          .
fmi2SetBoolean                     1            3                6           .          .
fmi2SetString                      1            3                6           .          .
fmi2GetFMUstate                    x            x                x           8          x
fmi2SetFMUstate                    x            x                x           x          x
fmi2FreeFMUstate                   x            x                x           x          x
fmi2SerializedFMUstateSize         x            x                x           x          x
fmi2SerializeFMUstate              x            x                x           x          x
fmi2DeSerializeFMUstate            x            x                x           x          x
fmi2GetDirectionalDerivative       .            x                x           8          x
fmi2SetRealInputDerivatives        x            x                x           .          .
fmi2GetRealOutputDerivatives       .            .                x           8          x
fmi2DoStep                         .            .                x           .          .
fmi2CancelStep                     .            .                .           .          .
fmi2GetStatus                      .            .                x           x          x
fmi2GetRealStatus                  .            .                x           x          x
fmi2GetIntegerStatus               .            .                x           x          x
fmi2GetBooleanStatus               .            .                x           x          x
fmi2GetStringStatus                .            .                x           x          x
"""
MODEL_EXCHANGE_TABLE = """
                              instantiated initializationMode eventMode continuousTimeMode terminated
fmi2SetDebugLogging                x            x               x           x             x
fmi2FreeInstance                   x            x               x           x             x
fmi2SetupExperiment                x            .               .           .             .
fmi2EnterInitializationMode        x            .               .           .             .
fmi2ExitInitializationMode         .            x               .           .             .
fmi2Terminate                      .            .               x           x             .
fmi2Reset                          x            x               x           x             x
fmi2GetReal                        .            2               x           x             x
fmi2GetInteger                     .            2               x           x             x
fmi2GetBoolean                     .            2               x           x             x
fmi2GetString                      .            2               x           x             x
fmi2SetReal                        1            3               4           5             .
fmi2SetInteger                     1            3               4           .             .
fmi2SetBoolean                     1            3               4           .             .
fmi2SetString                      1            3               4           .             .
fmi2GetFMUstate                    x            x               x           x             x
fmi2SetFMUstate                    x            x               x           x             x
fmi2FreeFMUstate                   x            x               x           x             x
fmi2SerializedFMUstateSize         x            x               x           x             x
fmi2SerializeFMUstate              x            x               x           x             x
fmi2DeSerializeFMUstate            x            x               x           x             x
fmi2GetDirectionalDerivative       .            x               x           x             x
fmi2EnterEventMode                 .            .               x           x             .
fmi2NewDiscreteStates              .            .               x           .             .
fmi2EnterContinuousTimeMode        .            .               x           .             .
fmi2CompletedIntegratorStep        .            .               .           x             .
fmi2SetTime                        .            .               8           x             .
fmi2SetContinuousStates            .            .               .           x             .
fmi2GetEventIndicators             .            x               x           x             x
fmi2GetContinuousStates            .            x               x           x             x
fmi2GetDerivatives                 .            x               x           x             x
fmi2GetNominalsOfContinuousStates  x            x               x           x             x
"""
# The numbered conditions, and whether the call below meets them. Co-Simulation: 1 a variable
# with initial exact or approx (the parameter l0), 2 an output or initial unknown (alpha0),
# 3 initial exact or an input (l0), 6 an input or tunable parameter (a_pivot_x; this FMU has
# no Integer, Boolean or String one, so those calls set none), 8 "always, but if status is
# other than fmi2Terminated, retrieved values are useable for debugging only". Model Exchange:
# 1, 2 and 3 as there, 4 an input or tunable parameter, 5 a continuous input or a
# continuous-time state (a_pivot_x), 8 "only for a Pure Discrete-Time FMU": this FMU has
# continuous states, so fmi2SetTime in eventMode is not allowed.
CONDITIONS = {
    CO_SIMULATION: {"1": True, "2": True, "3": True, "6": True, "8": True},
    MODEL_EXCHANGE: {"1": True, "2": True, "3": True, "4": True, "5": True, "8": False},
}


def parse(table, interface):
    """{function: {state: allowed}} from one of the tables above."""
    header, *rows = table.strip().splitlines()
    states = header.split()
    allowed = {}
    for row in rows:
        function, *marks = row.split()
        assert len(marks) == len(states), function
        allowed[function] = {
            state: mark == "x" or CONDITIONS[interface].get(mark, False) for state, mark in zip(states, marks)
        }
    return states, allowed


SCENE = Scene.uniform(3, coupling=True)  # inputs (a_pivot_*), so that conditions 4 to 6 can hold
C = c_void_p
SIGNATURES = {  # name: (result, argument types)
    "fmi2Instantiate": (
        c_void_p,
        [c_char_p, c_int, c_char_p, c_char_p, POINTER(fmi2CallbackFunctions), c_int, c_int],
    ),
    "fmi2FreeInstance": (None, [C]),
    "fmi2SetDebugLogging": (c_int, [C, c_int, c_size_t, POINTER(c_char_p)]),
    "fmi2SetupExperiment": (c_int, [C, c_int, c_double, c_double, c_int, c_double]),
    "fmi2EnterInitializationMode": (c_int, [C]),
    "fmi2ExitInitializationMode": (c_int, [C]),
    "fmi2Terminate": (c_int, [C]),
    "fmi2Reset": (c_int, [C]),
    "fmi2GetReal": (c_int, [C, POINTER(c_uint), c_size_t, POINTER(c_double)]),
    "fmi2GetInteger": (c_int, [C, POINTER(c_uint), c_size_t, POINTER(c_int)]),
    "fmi2GetBoolean": (c_int, [C, POINTER(c_uint), c_size_t, POINTER(c_int)]),
    "fmi2GetString": (c_int, [C, POINTER(c_uint), c_size_t, POINTER(c_char_p)]),
    "fmi2SetReal": (c_int, [C, POINTER(c_uint), c_size_t, POINTER(c_double)]),
    "fmi2SetInteger": (c_int, [C, POINTER(c_uint), c_size_t, POINTER(c_int)]),
    "fmi2SetBoolean": (c_int, [C, POINTER(c_uint), c_size_t, POINTER(c_int)]),
    "fmi2SetString": (c_int, [C, POINTER(c_uint), c_size_t, POINTER(c_char_p)]),
    "fmi2GetFMUstate": (c_int, [C, POINTER(c_void_p)]),
    "fmi2SetFMUstate": (c_int, [C, c_void_p]),
    "fmi2FreeFMUstate": (c_int, [C, POINTER(c_void_p)]),
    "fmi2SerializedFMUstateSize": (c_int, [C, c_void_p, POINTER(c_size_t)]),
    "fmi2SerializeFMUstate": (c_int, [C, c_void_p, POINTER(c_char), c_size_t]),
    "fmi2DeSerializeFMUstate": (c_int, [C, POINTER(c_char), c_size_t, POINTER(c_void_p)]),
    "fmi2GetDirectionalDerivative": (
        c_int,
        [C, POINTER(c_uint), c_size_t, POINTER(c_uint), c_size_t, POINTER(c_double), POINTER(c_double)],
    ),
    "fmi2EnterEventMode": (c_int, [C]),
    "fmi2NewDiscreteStates": (c_int, [C, POINTER(fmi2EventInfo)]),
    "fmi2EnterContinuousTimeMode": (c_int, [C]),
    "fmi2CompletedIntegratorStep": (c_int, [C, c_int, POINTER(c_int), POINTER(c_int)]),
    "fmi2SetTime": (c_int, [C, c_double]),
    "fmi2SetContinuousStates": (c_int, [C, POINTER(c_double), c_size_t]),
    "fmi2GetEventIndicators": (c_int, [C, POINTER(c_double), c_size_t]),
    "fmi2GetContinuousStates": (c_int, [C, POINTER(c_double), c_size_t]),
    "fmi2GetDerivatives": (c_int, [C, POINTER(c_double), c_size_t]),
    "fmi2GetNominalsOfContinuousStates": (c_int, [C, POINTER(c_double), c_size_t]),
    "fmi2SetRealInputDerivatives": (c_int, [C, POINTER(c_uint), c_size_t, POINTER(c_int), POINTER(c_double)]),
    "fmi2GetRealOutputDerivatives": (
        c_int,
        [C, POINTER(c_uint), c_size_t, POINTER(c_int), POINTER(c_double)],
    ),
    "fmi2DoStep": (c_int, [C, c_double, c_double, c_int]),
    "fmi2CancelStep": (c_int, [C]),
    "fmi2GetStatus": (c_int, [C, c_int, POINTER(c_int)]),
    "fmi2GetRealStatus": (c_int, [C, c_int, POINTER(c_double)]),
    "fmi2GetIntegerStatus": (c_int, [C, c_int, POINTER(c_int)]),
    "fmi2GetBooleanStatus": (c_int, [C, c_int, POINTER(c_int)]),
    "fmi2GetStringStatus": (c_int, [C, c_int, POINTER(c_char_p)]),
}
DO_STEP_STATUS, PENDING_STATUS, LAST_SUCCESSFUL_TIME, TERMINATED = range(4)  # fmi2StatusKind


def array(ctype, values):
    return (ctype * max(len(values), 1))(*values)


class Binary:
    """The FMU's shared library through ctypes, with a logger that collects (status, category,
    message) and the value references and start values the calls use."""

    def __init__(self, path, folder):
        with zipfile.ZipFile(path) as archive:
            archive.extractall(folder)
        self.lib = CDLL(str(folder / "binaries" / "linux64" / "ConicalPendulum.so"))
        for name, (result, arguments) in SIGNATURES.items():
            function = getattr(self.lib, name)
            function.restype, function.argtypes = result, arguments
        md = read_model_description(str(path))
        self.guid = md.guid.encode()
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.x_start = [float(v.start) for v in md.modelVariables if v.name in SCENE.state_names()]
        self.messages = []
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(
            lambda env, name, status, category, message: self.messages.append(
                (status, category.decode(), message.decode())
            )
        )
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)

    def __getattr__(self, name):
        return getattr(self.lib, name)

    def instantiate(self, interface, name=b"sm"):
        c = self.fmi2Instantiate(name, interface, self.guid, b"", byref(self.callbacks), 0, 1)
        assert c
        return c


def drive(fmu, interface, state):
    """A fresh instance of the given type in the given state."""
    c = fmu.instantiate(interface)
    if state == "stepFailed":  # the scene cannot cover 10 s in one solver step: discarded
        assert fmu.fmi2SetInteger(c, array(c_uint, [fmu.vr["max_steps"]]), 1, array(c_int, [1])) == OK
    if state != "instantiated":
        assert fmu.fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) == OK
        assert fmu.fmi2EnterInitializationMode(c) == OK
    if state not in ("instantiated", "initializationMode"):
        assert fmu.fmi2ExitInitializationMode(c) == OK  # stepComplete or eventMode
    if state == "stepFailed":
        assert fmu.fmi2DoStep(c, 0.0, 10.0, 1) == DISCARD
    elif state == "continuousTimeMode":
        assert fmu.fmi2EnterContinuousTimeMode(c) == OK
    elif state == "terminated":
        assert fmu.fmi2Terminate(c) == OK
    return c


def saved_state(fmu, c):
    state = c_void_p()
    assert fmu.fmi2GetFMUstate(c, byref(state)) == OK
    return state


def calls(fmu, interface, serialized):
    """{function: call(c, state) -> status}: each function once, with valid arguments; where
    the standard's condition on the variable is to hold, with a variable that meets it."""
    vr, nx = fmu.vr, len(fmu.x_start)
    before_init = ("instantiated", "initializationMode")

    def reals(*names):
        return array(c_uint, [vr[n] for n in names])

    def set_real(c, state):  # a parameter before initialization, an input after
        name = "l0" if state in before_init else "a_pivot_x"
        value = 10.0 if name == "l0" else 0.5
        return fmu.fmi2SetReal(c, reals(name), 1, array(c_double, [value]))

    def set_integer(c, state):  # no Integer input or tunable parameter: none after initialization
        n = 1 if state in before_init else 0
        return fmu.fmi2SetInteger(c, reals("solver"), n, array(c_int, [1]))

    def with_state(c, action):  # on a state of this instance (fmi2GetFMUstate: every state)
        state = saved_state(fmu, c)
        status = action(state)
        fmu.fmi2FreeFMUstate(c, byref(state))
        return status

    def get_state(c, _):
        state = c_void_p()
        status = fmu.fmi2GetFMUstate(c, byref(state))
        if state:
            fmu.fmi2FreeFMUstate(c, byref(state))
        return status

    def serialize(c, _):
        def action(state):
            size = c_size_t()
            assert fmu.fmi2SerializedFMUstateSize(c, state, byref(size)) == OK
            return fmu.fmi2SerializeFMUstate(c, state, create_string_buffer(size.value), size.value)

        return with_state(c, action)

    def deserialize(c, _):
        state = c_void_p()
        status = fmu.fmi2DeSerializeFMUstate(c, serialized, len(serialized), byref(state))
        if state:
            fmu.fmi2FreeFMUstate(c, byref(state))
        return status

    def state_size(c, _):
        return with_state(c, lambda state: fmu.fmi2SerializedFMUstateSize(c, state, byref(c_size_t())))

    none = array(c_uint, [])
    x = array(c_double, fmu.x_start)
    flags = (c_int(), c_int())
    return {
        "fmi2SetDebugLogging": lambda c, s: fmu.fmi2SetDebugLogging(c, 1, 0, None),
        "fmi2SetupExperiment": lambda c, s: fmu.fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0),
        "fmi2EnterInitializationMode": lambda c, s: fmu.fmi2EnterInitializationMode(c),
        "fmi2ExitInitializationMode": lambda c, s: fmu.fmi2ExitInitializationMode(c),
        "fmi2Terminate": lambda c, s: fmu.fmi2Terminate(c),
        "fmi2Reset": lambda c, s: fmu.fmi2Reset(c),
        "fmi2GetReal": lambda c, s: fmu.fmi2GetReal(c, reals("alpha0"), 1, array(c_double, [0])),
        "fmi2GetInteger": lambda c, s: fmu.fmi2GetInteger(c, none, 0, array(c_int, [])),
        "fmi2GetBoolean": lambda c, s: fmu.fmi2GetBoolean(c, none, 0, array(c_int, [])),
        "fmi2GetString": lambda c, s: fmu.fmi2GetString(c, none, 0, array(c_char_p, [])),
        "fmi2SetReal": set_real,
        "fmi2SetInteger": set_integer,
        "fmi2SetBoolean": lambda c, s: fmu.fmi2SetBoolean(c, none, 0, array(c_int, [])),
        "fmi2SetString": lambda c, s: fmu.fmi2SetString(c, none, 0, array(c_char_p, [])),
        "fmi2GetFMUstate": get_state,
        "fmi2SetFMUstate": lambda c, s: with_state(c, lambda state: fmu.fmi2SetFMUstate(c, state)),
        "fmi2FreeFMUstate": lambda c, s: fmu.fmi2FreeFMUstate(c, byref(saved_state(fmu, c))),
        "fmi2SerializedFMUstateSize": state_size,
        "fmi2SerializeFMUstate": serialize,
        "fmi2DeSerializeFMUstate": deserialize,
        "fmi2GetDirectionalDerivative": lambda c, s: fmu.fmi2GetDirectionalDerivative(
            c, reals("F_pivot_x"), 1, reals("alpha0"), 1, array(c_double, [1.0]), array(c_double, [0])
        ),
        "fmi2EnterEventMode": lambda c, s: fmu.fmi2EnterEventMode(c),
        "fmi2NewDiscreteStates": lambda c, s: fmu.fmi2NewDiscreteStates(c, byref(fmi2EventInfo())),
        "fmi2EnterContinuousTimeMode": lambda c, s: fmu.fmi2EnterContinuousTimeMode(c),
        "fmi2CompletedIntegratorStep": lambda c, s: fmu.fmi2CompletedIntegratorStep(
            c, 1, byref(flags[0]), byref(flags[1])
        ),
        "fmi2SetTime": lambda c, s: fmu.fmi2SetTime(c, 0.0),
        "fmi2SetContinuousStates": lambda c, s: fmu.fmi2SetContinuousStates(c, x, nx),
        "fmi2GetEventIndicators": lambda c, s: fmu.fmi2GetEventIndicators(c, array(c_double, []), 0),
        "fmi2GetContinuousStates": lambda c, s: fmu.fmi2GetContinuousStates(c, array(c_double, [0] * nx), nx),
        "fmi2GetDerivatives": lambda c, s: fmu.fmi2GetDerivatives(c, array(c_double, [0] * nx), nx),
        "fmi2GetNominalsOfContinuousStates": lambda c, s: fmu.fmi2GetNominalsOfContinuousStates(
            c, array(c_double, [0] * nx), nx
        ),
        "fmi2SetRealInputDerivatives": lambda c, s: fmu.fmi2SetRealInputDerivatives(
            c, none, 0, array(c_int, []), array(c_double, [])
        ),
        "fmi2GetRealOutputDerivatives": lambda c, s: fmu.fmi2GetRealOutputDerivatives(
            c, none, 0, array(c_int, []), array(c_double, [])
        ),
        "fmi2DoStep": lambda c, s: fmu.fmi2DoStep(c, 0.0, 0.01, 1),  # every instance here is at t = 0
        "fmi2CancelStep": lambda c, s: fmu.fmi2CancelStep(c),
        "fmi2GetStatus": lambda c, s: fmu.fmi2GetStatus(c, DO_STEP_STATUS, byref(c_int())),
        "fmi2GetRealStatus": lambda c, s: fmu.fmi2GetRealStatus(c, LAST_SUCCESSFUL_TIME, byref(c_double())),
        "fmi2GetIntegerStatus": lambda c, s: fmu.fmi2GetIntegerStatus(c, DO_STEP_STATUS, byref(c_int())),
        "fmi2GetBooleanStatus": lambda c, s: fmu.fmi2GetBooleanStatus(c, TERMINATED, byref(c_int())),
        "fmi2GetStringStatus": lambda c, s: fmu.fmi2GetStringStatus(c, PENDING_STATUS, byref(c_char_p())),
    }


@pytest.fixture(scope="module")
def native(built_fmu):
    return built_fmu(SCENE, backend="native")


@pytest.fixture(scope="module")
def binary(native, tmp_path_factory):
    return Binary(native, tmp_path_factory.mktemp("binary"))


def test_every_function_in_every_state_as_the_standard_allows(binary):
    fmu, checked = binary, 0
    every_function = [name for name in SIGNATURES if name not in ("fmi2Instantiate", "fmi2FreeInstance")]
    for interface, table, name in (
        (CO_SIMULATION, CO_SIMULATION_TABLE, "Co-Simulation"),
        (MODEL_EXCHANGE, MODEL_EXCHANGE_TABLE, "Model Exchange"),
    ):
        states, allowed = parse(table, interface)
        c = fmu.instantiate(interface)
        serialized_state = saved_state(fmu, c)
        size = c_size_t()
        assert fmu.fmi2SerializedFMUstateSize(c, serialized_state, byref(size)) == OK
        serialized = create_string_buffer(size.value)
        assert fmu.fmi2SerializeFMUstate(c, serialized_state, serialized, size.value) == OK
        fmu.fmi2FreeFMUstate(c, byref(serialized_state))
        fmu.fmi2FreeInstance(c)
        call = calls(fmu, interface, serialized)
        assert set(call) == set(every_function)
        wrong = []
        for function in every_function:
            for state in states:  # the other interface's functions: in no state of this one
                expected = allowed.get(function, {}).get(state, False)
                c = drive(fmu, interface, state)
                fmu.messages.clear()
                status = call[function](c, state)
                refusal = f"{function} is not allowed in state {state} (FMI 2.0, {name}"
                named = any(s == ERROR and text.startswith(refusal) for s, _, text in fmu.messages)
                if (status == ERROR) == expected or named == expected:
                    wrong.append((function, state, status, fmu.messages[-1:]))
                fmu.fmi2FreeInstance(c)
                checked += 1
        assert not wrong, f"{name}: {wrong}"
        for state in states:  # fmi2FreeInstance: in every state, so never refused; it logs nothing
            c = drive(fmu, interface, state)
            fmu.messages.clear()
            fmu.fmi2FreeInstance(c)
            assert fmu.messages == []
            checked += 1
    print(f"\n{checked} calls: {len(every_function) + 1} functions x 5 states x 2 interfaces")
    assert checked == (len(every_function) + 1) * 5 * 2


def test_the_tables_cover_the_whole_api(binary):
    """The two tables above hold every FMI 2.0 function but those without an instance
    (fmi2Instantiate, and fmi2GetTypesPlatform and fmi2GetVersion, allowed in every state and
    outside any), 22 of them in both."""
    cs = set(parse(CO_SIMULATION_TABLE, CO_SIMULATION)[1])
    me = set(parse(MODEL_EXCHANGE_TABLE, MODEL_EXCHANGE)[1])
    assert cs | me == set(SIGNATURES) - {"fmi2Instantiate"} and len(cs & me) == 22
    for name, value in (("fmi2GetVersion", b"2.0"), ("fmi2GetTypesPlatform", b"default")):
        function = getattr(binary, name)
        function.restype, function.argtypes = c_char_p, []
        assert function() == value


# ---- fmi2SetDebugLogging and the log categories --------------------------------------------


def categories_declared(path):
    root = ET.fromstring(zipfile.ZipFile(path).read("modelDescription.xml"))
    return [c.get("name") for c in root.find("LogCategories")]


class Logged:
    """A Co-Simulation instance through fmpy that collects (status, category, message), with a
    step that is discarded and a call that is refused, each repeatable."""

    def __init__(self, path, logging_on):
        md = read_model_description(str(path))
        self.messages = []
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(
            lambda env, name, status, category, message: self.messages.append(
                (status, category.decode(), message.decode())
            )
        )
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self.unzipped = extract(str(path))
        self.fmu = FMU2Slave(
            guid=md.guid,
            unzipDirectory=self.unzipped,
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName="logged",
        )
        self.fmu.instantiate(callbacks=self.callbacks, loggingOn=logging_on)
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.fmu.setInteger([self.vr["max_steps"]], [1])
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self.start = self.fmu.getFMUstate()

    def logged(self):
        """{category: status} of what a discarded step and a refused value log now."""
        self.messages.clear()
        with pytest.raises(FMICallException) as discarded:
            self.fmu.doStep(0.0, 10.0)
        assert discarded.value.status == DISCARD  # whether logged or not
        self.fmu.setFMUstate(self.start)  # back to stepComplete
        with pytest.raises(FMICallException) as refused:
            self.fmu.setReal([self.vr["l0"]], [-1.0])
        assert refused.value.status == ERROR
        return {category: status for status, category, _ in self.messages}

    def set(self, logging_on, categories):
        self.fmu.setDebugLogging(logging_on, categories)
        return self.logged()

    def close(self):
        self.fmu.freeFMUstate(self.start)
        self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.unzipped, ignore_errors=True)


def test_the_log_categories_are_written_once_and_the_glue_logs_in_no_other(native):
    assert categories_declared(native) == list(LOG_CATEGORIES)
    with zipfile.ZipFile(native) as archive:
        config = archive.read("sources/fmu_config.h").decode()
        glue = archive.read("sources/fmi2_glue.c").decode()
    assert "enum { CP_LOG_STATUS_ERROR, CP_LOG_STATUS_DISCARD, CP_LOG_STATUS_WARNING, CP_NLOG };" in config
    assert '{"logStatusError", "logStatusDiscard", "logStatusWarning"}' in config
    assert "logStatus" not in glue  # categories by their constants only: a new one must be declared


def test_set_debug_logging_honours_the_declared_categories(native):
    both = {"logStatusError": ERROR, "logStatusDiscard": DISCARD}
    errors = {"logStatusError": ERROR}  # FMI 2.0, section 2.1.3: an fmi2Error is always reported
    fmu = Logged(native, logging_on=False)
    assert fmu.logged() == errors  # debug logging off: the discarded step's diagnosis is not shown
    assert fmu.set(True, []) == both  # nCategories = 0: every category
    assert fmu.set(True, ["logStatusError"]) == errors  # a list: only those
    assert fmu.set(True, ["logStatusDiscard"]) == both
    with pytest.raises(FMICallException) as refused:
        fmu.fmu.setDebugLogging(True, ["logStatusError", "logEverything"])
    assert refused.value.status == ERROR
    assert fmu.messages[-1] == (
        ERROR,
        "logStatusError",
        "fmi2SetDebugLogging: log category "
        '"logEverything" is not this FMU\'s (its model description declares '
        "logStatusError, logStatusDiscard, logStatusWarning)",
    )
    assert fmu.logged() == both  # unchanged: logStatusDiscard alone is still on
    assert fmu.set(False, ["logStatusDiscard"]) == errors  # off: those listed
    assert fmu.set(True, []) == both
    assert fmu.set(False, ["logStatusError"]) == both  # the others stay on
    assert fmu.set(False, []) == errors  # all off, but errors are still reported
    fmu.close()
    fmu = Logged(native, logging_on=True)
    assert fmu.logged() == both  # loggingOn in fmi2Instantiate: every category
    fmu.close()


def test_without_debug_logging_the_diagnosis_comes_with_the_next_refusal(native):
    """A discard's diagnosis is debug logging; the error a host meets next carries it, so a
    host that never asked for debug logging (fmpy's default) still learns why."""
    fmu = Logged(native, logging_on=False)
    fmu.messages.clear()
    with pytest.raises(FMICallException):
        fmu.fmu.doStep(0.0, 10.0)
    assert fmu.messages == []
    with pytest.raises(FMICallException) as refused:
        fmu.fmu.doStep(0.0, 10.0)
    assert refused.value.status == ERROR
    [(status, category, text)] = fmu.messages
    assert (status, category) == (ERROR, "logStatusError")
    assert "not allowed in state stepFailed" in text
    assert "The step was discarded: do_step from t = 0 s by 10 s failed: too many steps." in text
    fmu.fmu.setFMUstate(fmu.start)  # gone with the failed step
    fmu.messages.clear()
    with pytest.raises(FMICallException):
        fmu.fmu.enterInitializationMode()
    assert "discarded" not in fmu.messages[0][2]
    fmu.close()
