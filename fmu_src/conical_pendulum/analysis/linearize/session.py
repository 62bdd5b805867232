"""One Model Exchange instance of an FMU through fmpy's low-level API, held at an operating
point in continuous-time mode: instantiated with its start values, initialized at a time, its
states and inputs set and its derivatives and outputs read, every failing call a UserError
with what the FMU said. Only Model Exchange gives the state derivatives at states set from
outside: a Co-Simulation-only FMU is refused, saying so."""

from __future__ import annotations

import contextlib
import ctypes
import functools
import shutil
from pathlib import Path

import numpy as np

from ...errors import UserError
from ..fmi3_arrays import fmu_data
from ..fmpy_runs import logging_callbacks
from .variables import FLOAT_TYPES, Block, block_of, continuous_float, fmi2_names, replaced

NATIVE_BUILD = "conical-pendulum build --native (FMI 2.0) or --native --fmi 3 (docs/native.md)"


class Session:
    """One Model Exchange instance at the operating point, in continuous-time mode."""

    def __init__(self, path: Path, time: float, parameters: dict):
        from fmpy import extract, read_model_description

        if path.is_dir():
            raise UserError(f"{path}: is a directory, not an FMU")
        if not path.is_file():
            raise UserError(f"{path}: no such FMU")
        try:
            # not validated against the schema: what is read here is checked where it is used,
            # and the validation costs as much as the rest of a 100-link chain's linearization
            self.md = read_model_description(str(path), validate=False)
        except Exception as exc:  # fmpy's reasons: not a zip, no or a bad modelDescription.xml
            raise UserError(f"{path}: not an FMU fmpy can read ({exc})") from None
        self.path, self.time = path, float(time)
        self.fmi3 = self.md.fmiVersion.startswith("3")
        interface = self.md.modelExchange
        if interface is None:
            offered = [
                name
                for name, part in (
                    ("Co-Simulation", self.md.coSimulation),
                    ("Scheduled Execution", getattr(self.md, "scheduledExecution", None)),
                )
                if part is not None
            ]
            raise UserError(
                f"{path}: has no Model Exchange interface ({' and '.join(offered) or 'nothing else'} only): "
                "a linearization needs the state derivatives, which only Model Exchange gives, at states "
                "set from outside; build an FMU with Model Exchange (this project's native FMUs have it: "
                f"{NATIVE_BUILD})"
            )
        self.directional = _gives_directional_derivatives(path)
        self.messages: list[str] = []
        named = functools.partial(block_of, fmi3=self.fmi3, names=fmi2_names(path) if self.fmi3 else {})
        self._variables = {v.name: v for v in self.md.modelVariables}
        self.states = named([u.variable.derivative for u in self.md.derivatives])
        self.inputs = named(
            [v for v in self.md.modelVariables if v.causality == "input" and continuous_float(v)]
        )
        state_vrs = set(self.states.vrs)
        self.unknown_outputs = [u for u in self.md.outputs if continuous_float(u.variable)]
        self.outputs = named([u.variable for u in self.unknown_outputs])
        self.computed = named(
            [u.variable for u in self.unknown_outputs if u.variable.valueReference not in state_vrs]
        )
        self.derivatives = named([u.variable for u in self.md.derivatives])
        self.unzipdir = extract(str(path))
        try:
            self._instantiate(interface.modelIdentifier, parameters)
        except UserError:
            self.close()
            raise
        except Exception as exc:  # fmpy's: no binary for this platform, a library that does not load
            self.close()
            raise UserError(
                f"{path}: its Model Exchange binary cannot be loaded or instantiated: {exc}"
            ) from None
        except BaseException:
            self.close()
            raise

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # --- the instance and its start values ---

    def _instantiate(self, identifier: str, parameters: dict) -> None:
        from fmpy.fmi2 import FMU2Model
        from fmpy.fmi3 import FMU3Model

        cls = FMU3Model if self.fmi3 else FMU2Model
        self.fmu = cls(
            guid=self.md.guid,
            unzipDirectory=self.unzipdir,
            modelIdentifier=identifier,
            instanceName="linearize",
        )
        if self.fmi3:

            def log(environment, status, category, message):
                self.messages.append(message.decode(errors="replace"))

            self._logger = log
            self.fmu.instantiate(loggingOn=True, logMessage=log)
        else:
            self._logger = logging_callbacks(lambda status, text: self.messages.append(text))
            self.fmu.instantiate(callbacks=self._logger, loggingOn=True)
        self._instantiated = True
        self.call("setting up the experiment", self._start, parameters)

    def _start(self, parameters: dict) -> None:
        fmu = self.fmu
        if not self.fmi3:
            fmu.setupExperiment(startTime=self.time)
        self._set_parameters(parameters)
        if self.fmi3:
            fmu.enterInitializationMode(startTime=self.time)
            fmu.exitInitializationMode()
            while fmu.updateDiscreteStates()[0]:
                pass
        else:
            fmu.enterInitializationMode()
            fmu.exitInitializationMode()
            while fmu.newDiscreteStates()[0]:
                pass
        fmu.enterContinuousTimeMode()
        fmu.setTime(self.time)

    def _set_parameters(self, values: dict) -> None:
        data = fmu_data(self.path) if self.fmi3 else None
        if data is not None:  # this package's FMI 3.0 FMU, given the FMI 2.0 names
            from ..fmi3_arrays import array_start_values

            values = array_start_values(data, values)
        for name, value in values.items():
            variable = self._variables.get(name)
            if variable is None or (
                variable.causality not in ("parameter", "input") and variable.initial != "exact"
            ):
                raise UserError(
                    f"parameter {name!r}: {self.path.name} has no parameter or start value by that name"
                )
            numbers = list(np.atleast_1d(value))
            if variable.type in FLOAT_TYPES:
                (self.fmu.setFloat64 if self.fmi3 else self.fmu.setReal)(
                    [variable.valueReference], [float(x) for x in numbers]
                )
            elif variable.type in ("Integer", "Enumeration", "Int32", "Int64"):
                setter = {"Int32": "setInt32", "Enumeration": "setInt64", "Int64": "setInt64"}
                setter = getattr(self.fmu, setter[variable.type] if self.fmi3 else "setInteger")
                setter([variable.valueReference], [int(x) for x in numbers])
            else:
                raise UserError(f"parameter {name!r}: its type {variable.type} cannot be set here")

    def call(self, what: str, function, *args):
        """function(*args), an FMI call failing as a UserError with what the FMU said."""
        from fmpy.fmi1 import FMICallException

        try:
            return function(*args)
        except FMICallException as exc:
            said = "; ".join(self.messages[-3:]) or "no message"
            raise UserError(f"{self.path.name}: {what}: {exc} ({said})", status=1) from None

    # --- the operating point and the values at it ---

    def _reals(self, block: Block) -> np.ndarray:
        if not block.vrs:
            return np.zeros(0)
        if self.fmi3:
            return np.array(self.fmu.getFloat64(list(block.vrs), nValues=len(block.names)))
        return np.array(self.fmu.getReal(list(block.vrs)))

    def _set_inputs(self, u: np.ndarray) -> None:
        if self.inputs.vrs:
            (self.fmu.setFloat64 if self.fmi3 else self.fmu.setReal)(
                list(self.inputs.vrs), [float(v) for v in u]
            )

    def _set_states(self, x: np.ndarray) -> None:
        n = len(x)
        self.fmu.setContinuousStates((ctypes.c_double * n)(*x), n)

    def place(self, states: dict, inputs: dict) -> None:
        """The operating point: the FMU's values after initialization, some replaced by name."""
        n = len(self.states.names)
        x = (ctypes.c_double * n)()
        if n:
            self.call("reading the states", self.fmu.getContinuousStates, x, n)
        self.x0 = replaced(np.array(x[:]), self.states, states, "state", self.path.name)
        self.u0 = replaced(self._reals(self.inputs), self.inputs, inputs, "input", self.path.name)
        self.call("setting the operating point", self.at, self.x0, self.u0)
        self.dx0 = self.call("evaluating at the operating point", self.evaluate)[0]
        self.y0 = self._reals(self.outputs)

    def at(self, x, u) -> None:
        """The states x (where the FMU has any) and the inputs u set."""
        if len(x):
            self._set_states(x)
        self._set_inputs(u)

    def evaluate(self) -> tuple[np.ndarray, np.ndarray]:
        """The state derivatives and the outputs that are not states at what is set."""
        n = len(self.states.names)
        dx = (ctypes.c_double * n)()
        if n:
            (self.fmu.getContinuousStateDerivatives if self.fmi3 else self.fmu.getDerivatives)(dx, n)
        return np.array(dx[:]), self._reals(self.computed)

    def nominal(self, name: str) -> float:
        """A variable's nominal, 1 where it has none: the differences' step near a value of 0."""
        variable = self._variables.get(name)
        nominal = getattr(variable, "nominal", None) if variable is not None else None
        try:
            return abs(float(nominal)) if nominal is not None else 1.0
        except ValueError:
            return 1.0

    def close(self) -> None:
        if getattr(self, "_instantiated", False):
            # terminate after an error is the FMU's to refuse; freeing is what counts
            with contextlib.suppress(Exception):
                self.fmu.terminate()
            self.fmu.freeInstance()
            self._instantiated = False
        if getattr(self, "unzipdir", None):
            shutil.rmtree(self.unzipdir, ignore_errors=True)
            self.unzipdir = None


def _gives_directional_derivatives(path: Path) -> bool:
    """Whether the Model Exchange interface provides directional derivatives, read from the
    model description itself (fmpy 0.3 reads FMI 3.0's providesDirectionalDerivatives as False);
    parsed only up to its interfaces, which come before the variables."""
    import xml.etree.ElementTree as ET
    import zipfile

    version, found = "", False
    with zipfile.ZipFile(path) as archive, archive.open("modelDescription.xml") as stream:
        for _, element in ET.iterparse(stream, events=("start",)):
            if element.tag == "fmiModelDescription":
                version = element.get("fmiVersion", "")
            elif element.tag == "ModelExchange":
                name = (
                    "providesDirectionalDerivatives"
                    if version.startswith("3")
                    else "providesDirectionalDerivative"
                )
                found = element.get(name) == "true"
            elif element.tag == "ModelVariables":
                break
    return found
