"""Driving an FMU through fmpy's low-level API (FMI 2.0: Instance, FMI 3.0: Instance3), with its log
messages collected; both answer initialize, texts and the FMU state calls alike, so that one test
body runs on either (INSTANCES by FMI version)."""

from __future__ import annotations

import json
import shutil
import zipfile

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Model, FMU3Slave

from conical_pendulum.analysis.fmi3_arrays import element_names
from conical_pendulum.analysis.fmpy_runs import logging_callbacks, run_fmu
from conical_pendulum.analysis.simulate import simulate

# Values every FMU of the package refuses, whatever its backend, with these words (runtime.rules).
BAD_VALUES = [
    ("l0", -1.0, "l0 = -1.0: a length must be positive"),
    ("M1", 0.0, "M1 = 0.0: a link mass must be positive"),
    ("m2", 0.0, "m2 = 0.0: a bob mass must be positive"),
    ("Ixx0", -2.0, "Ixx0 = -2.0: a moment of inertia cannot be negative"),
    ("g", float("nan"), "g = nan: must be finite"),
    ("alpha0", float("inf"), "alpha0 = inf: must be finite"),
    (
        "rtol",
        0.0,
        "rtol = 0.0: a relative tolerance must be at least 2.22e-14 (100 machine "
        "epsilons): no solver resolves less",
    ),
    (
        "rtol",
        1e-15,
        "rtol = 1e-15: a relative tolerance must be at least 2.22e-14 (100 machine "
        "epsilons): no solver resolves less",
    ),
    ("max_steps", 0, "max_steps = 0: must be at least 1"),
    ("energy", 1.0, "energy is a calculated output: it cannot be set"),
]


def start(instance, instantiate, start_values, initialize) -> None:
    """An Instance's or Instance3's start: instantiated, its start values set, initialized if
    asked; its extracted folder removed when any of it is refused (the instance as it was left)."""
    try:
        instantiate()
        instance.time = 0.0
        instance.set(start_values or {})
        if initialize:
            instance.initialize()
    except Exception:
        shutil.rmtree(instance.unzipdir, ignore_errors=True)
        raise


class Instance:
    """One instantiated FMU; `messages` collects (status, text) from its logger."""

    def __init__(self, path, name="instance", start_values=None, initialize=True):
        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.unzipdir = extract(str(path))
        self.messages = []
        self._callbacks = logging_callbacks(lambda status, text: self.messages.append((status, text)))
        self.fmu = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=self.unzipdir,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        start(
            self,
            lambda: self.fmu.instantiate(callbacks=self._callbacks, loggingOn=True),
            start_values,
            initialize,
        )

    def initialize(self, stop_time=None):
        self.fmu.setupExperiment(startTime=0.0, stopTime=stop_time)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()

    def set(self, values):
        for name, value in values.items():
            if self.types[name] in ("Integer", "Enumeration"):  # fmi2SetInteger sets both
                self.fmu.setInteger([self.vr[name]], [int(value)])
            else:
                self.fmu.setReal([self.vr[name]], [float(value)])

    def get(self, *names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def step(self, dt):
        self.fmu.doStep(currentCommunicationPoint=self.time, communicationStepSize=dt)
        self.time += dt

    def texts(self, status=None):
        return " ".join(t for s, t in self.messages if status is None or s == status)

    def get_state(self):
        return self.fmu.getFMUstate()

    def set_state(self, state):
        self.fmu.setFMUstate(state)

    def free_state(self, state):
        self.fmu.freeFMUstate(state)

    def serialize(self, state):
        return self.fmu.serializeFMUstate(state)

    def deserialize(self, data):
        return self.fmu.deSerializeFMUstate(data)

    def close(self, after_fatal=False):
        """Free the instance; after fmi2Fatal FMI allows nothing else."""
        if not after_fatal:
            self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.unzipdir, ignore_errors=True)


def fmi3_names(path):
    """The FMI 2.0 scalars' names -> (the FMI 3.0 array, 0-based index), and the records
    (the variables' description) from the FMU's model.json."""
    with zipfile.ZipFile(path) as archive:
        data = json.loads(archive.read("resources/model.json"))
    return element_names(data), {v["name"]: v for v in data["variables"]}


def fmi3_start_values(path, values):
    """start values by FMI 2.0 scalar name -> fmpy's start values of the FMI 3.0 FMU (arrays whole)."""
    elements, records = fmi3_names(path)
    starts = {}
    for name, value in values.items():
        if name in elements:
            array, k = elements[name]
            members = sorted((i, n) for n, (a, i) in elements.items() if a == array)
            current = starts.setdefault(array, [records[n]["start"] for _, n in members])
            current[k] = value
        else:
            starts[name] = value
    return starts


class Instance3:
    """One FMI 3.0 instance through fmpy's low-level API, read and set by the FMI 2.0 FMU's scalar
    names (an element of an array through its array); `messages` collects (status, text)."""

    def __init__(
        self, path, interface="CoSimulation", start_values=None, initialize=True, name="instance", **options
    ):
        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.elements, self.records = fmi3_names(path)
        self.path = path
        self.unzipdir = extract(str(path))
        self.messages = []

        def log(environment, status, category, message):
            self.messages.append((status, message.decode(errors="replace")))

        self._log = log
        cls = FMU3Slave if interface == "CoSimulation" else FMU3Model
        self.fmu = cls(
            guid=self.md.guid,
            unzipDirectory=self.unzipdir,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        start(
            self,
            lambda: self.fmu.instantiate(loggingOn=True, logMessage=log, **options),
            start_values,
            initialize,
        )

    def initialize(self, stop_time=None):
        self.fmu.enterInitializationMode(startTime=0.0, stopTime=stop_time)
        self.fmu.exitInitializationMode()

    def set(self, values):
        """Before initialization (an array is set whole, from its start values)."""
        for name, value in fmi3_start_values(self.path, values).items():
            if self.types[name] == "Int32":
                self.fmu.setInt32([self.vr[name]], [int(value)])
            elif self.types[name] == "Enumeration":  # FMI 3.0 sets an enumeration as Int64
                self.fmu.setInt64([self.vr[name]], [int(value)])
            else:
                value = [float(x) for x in value] if isinstance(value, list) else [float(value)]
                self.fmu.setFloat64([self.vr[name]], value)

    def get(self, *names):
        values = []
        for name in names:
            if name in self.elements:
                array, k = self.elements[name]
                n = int(self.fmu.getUInt64([self.vr["n_links"]])[0])
                values.append(self.fmu.getFloat64([self.vr[array]], nValues=n)[k])
            else:
                values.append(self.fmu.getFloat64([self.vr[name]])[0])
        return values

    def step(self, dt):
        result = self.fmu.doStep(currentCommunicationPoint=self.time, communicationStepSize=dt)
        self.time += dt
        return result

    def texts(self, status=None):
        return " ".join(t for s, t in self.messages if status is None or s == status)

    def get_state(self):
        return self.fmu.getFMUState()

    def set_state(self, state):
        self.fmu.setFMUState(state)

    def free_state(self, state):
        self.fmu.freeFMUState(state)

    def serialize(self, state):
        return self.fmu.serializeFMUState(state)

    def deserialize(self, data):
        return self.fmu.deserializeFMUState(data)

    def close(self):
        self.fmu.freeInstance()
        shutil.rmtree(self.unzipdir, ignore_errors=True)


INSTANCES = {2: Instance, 3: Instance3}


def assert_model_exchange_follows(path, scene, start: dict, stop_time: float) -> None:
    """The FMU's Model Exchange through fmpy's CVode at 1e-10 against the native reference at
    1e-12 from the same start values: every state within 1e-6 of max(1, its largest size). An
    event (an elastic rope's snap) is a second row at its time, which fmpy records after it:
    the states are continuous there, so the row after is left out."""
    run = run_fmu(
        path, stop_time=stop_time, fmi_type="ModelExchange", relative_tolerance=1e-10, start_values=start
    )
    run = run[np.unique(run["time"], return_index=True)[1]]
    inputs = {k: v for k, v in start.items() if k in scene.input_names()}
    state = {k: v for k, v in start.items() if k in scene.state_names()}
    reference = simulate(scene, run["time"], parameters=inputs, state=state, rtol=1e-12, atol=1e-12)
    for name in scene.state_names():  # angles and rates of order one, lengths in m, books in kJ
        scale = max(1.0, abs(reference[name]).max())
        assert abs(run[name] - reference[name]).max() < 1e-6 * scale, name
