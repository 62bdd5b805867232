"""Driving an FMU through fmpy's low-level API, with its log messages collected."""

from __future__ import annotations

import shutil

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from conical_pendulum.analysis.fmpy_runs import logging_callbacks

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
        self.fmu.instantiate(callbacks=self._callbacks, loggingOn=True)
        self.time = 0.0
        self.set(start_values or {})
        if initialize:
            self.fmu.setupExperiment(startTime=0.0)
            self.fmu.enterInitializationMode()
            self.fmu.exitInitializationMode()

    def set(self, values):
        for name, value in values.items():
            if self.types[name] == "Integer":
                self.fmu.setInteger([self.vr[name]], [int(value)])
            else:
                self.fmu.setReal([self.vr[name]], [float(value)])

    def get(self, *names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def step(self, dt):
        self.fmu.doStep(currentCommunicationPoint=self.time, communicationStepSize=dt)
        self.time += dt

    def close(self, after_fatal=False):
        """Free the instance; after fmi2Fatal FMI allows nothing else."""
        if not after_fatal:
            self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.unzipdir, ignore_errors=True)
