"""Driving an FMU through fmpy's low-level API, with its log messages collected."""
from __future__ import annotations

import shutil

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from conical_pendulum.analysis.fmpy_runs import logging_callbacks


class Instance:
    """One instantiated FMU; `messages` collects (status, text) from its logger."""

    def __init__(self, path, name="instance", start_values=None, initialize=True):
        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.unzipdir = extract(str(path))
        self.messages = []
        self._callbacks = logging_callbacks(lambda status, text: self.messages.append((status, text)))
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipdir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
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
