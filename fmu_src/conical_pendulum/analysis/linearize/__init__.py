"""Linear models of any FMI 2.0 or 3.0 FMU at an operating point: A, B, C, D from its derivatives.

Around (x0, u0) at time t, x' = f(x, u) and y = g(x, u) give A = df/dx, B = df/du, C = dg/dx,
D = dg/du, rows and columns named in the ModelStructure's order (states as its derivatives
list them, the Float inputs in the model's order, the outputs as it lists them). An FMI 3.0
array is one name per element (`x[2]`; an FMU of this package: the FMI 2.0 FMU's names,
`alpha0`, so that both versions give the same model).

Where the FMU gives directional derivatives (Model Exchange with
providesDirectionalDerivative(s)), the columns come from them, exact to the FMU's own
accuracy, grouped by the ModelStructure's sparsity: columns whose listed dependencies share
no row are asked for in one call (Curtis, Powell and Reid's grouping, greedy, in the
ModelStructure's order), and a column nothing depends on costs no call. Without them, central
differences of fmi2GetDerivatives / fmi3GetContinuousStateDerivatives and the outputs at the
steps h and 2h, extrapolated (Richardson), grouped the same way, with an error estimate
per entry. The state derivatives exist only in Model Exchange: a Co-Simulation-only FMU is
refused, saying so. An output that is a state is its own row of C, exactly.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import math
import shutil
from pathlib import Path

import numpy as np

from ...errors import UserError
from ..fmi3_arrays import fmu_data
from ..fmpy_runs import logging_callbacks
from .model import LinearModel, Mode, Stiffness, describe_modes
from .variables import FLOAT_TYPES, Block, block_of, continuous_float, fmi2_names, replaced

__all__ = [
    "DIFFERENCE_STEP",
    "FLOAT_TYPES",
    "NATIVE_BUILD",
    "Block",
    "LinearModel",
    "Mode",
    "Stiffness",
    "color_columns",
    "describe_modes",
    "linearize",
]

DIFFERENCE_STEP = 1e-3  # relative to max(|value|, nominal): central differences' h^2 and h^4 terms
NATIVE_BUILD = "conical-pendulum build --native (FMI 2.0) or --native --fmi 3 (docs/native.md)"


def linearize(
    path,
    states: dict | None = None,
    inputs: dict | None = None,
    parameters: dict | None = None,
    time: float = 0.0,
    method: str = "auto",
    grouped: bool = True,
    step: float = DIFFERENCE_STEP,
) -> LinearModel:
    """The linear model of the FMU at `path` around its start (after initialization at
    `time`), or states, inputs and parameters given by name (an FMI 3.0 array by its name
    and all its values, or by its elements' names).

    method: "directional" (the FMU's directional derivatives; refused where it has none),
    "differences", or "auto" (directional where given); grouped=False: one call per column."""
    if method not in ("auto", "directional", "differences"):
        raise UserError(f"method: {method!r} is not one of 'auto', 'directional', 'differences'")
    if not math.isfinite(time):
        raise UserError(f"time: must be finite, got {time!r}")
    if not 0 < step <= 0.1:
        raise UserError(f"step: the differences' relative step must be in (0, 0.1], got {step!r}")
    with _Session(Path(path), time, parameters or {}) as session:
        if method == "directional" and not session.directional:
            raise UserError(
                f"{path}: gives no directional derivatives (providesDirectionalDerivative is not "
                "set in its Model Exchange); use method 'differences'"
            )
        session.place(states or {}, inputs or {})
        use = "directional" if method != "differences" and session.directional else "differences"
        return session.linearize(use, grouped, step)


def color_columns(pattern: np.ndarray) -> list[list[int]]:
    """Columns of a boolean pattern (rows x columns) in groups whose columns share no row
    (greedy, in order); columns with no row are in no group: they are zero."""
    groups: list[list[int]] = []
    taken: list[int] = []  # each group's rows as the bits of one integer
    for j in range(pattern.shape[1]):
        rows = int.from_bytes(np.packbits(pattern[:, j]).tobytes(), "big")
        if not rows:
            continue
        for k, used in enumerate(taken):
            if not used & rows:
                groups[k].append(j)
                taken[k] |= rows
                break
        else:
            groups.append([j])
            taken.append(rows)
    return groups


class _Session:
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
        self._call("setting up the experiment", self._start, parameters)

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

    def _call(self, what: str, function, *args):
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
            self._call("reading the states", self.fmu.getContinuousStates, x, n)
        self.x0 = replaced(np.array(x[:]), self.states, states, "state", self.path.name)
        self.u0 = replaced(self._reals(self.inputs), self.inputs, inputs, "input", self.path.name)
        self._call("setting the operating point", self._at, self.x0, self.u0)
        self.dx0 = self._call("evaluating at the operating point", self._evaluate)[0]
        self.y0 = self._reals(self.outputs)

    def _at(self, x, u) -> None:
        if len(x):
            self._set_states(x)
        self._set_inputs(u)

    def _evaluate(self) -> tuple[np.ndarray, np.ndarray]:
        n = len(self.states.names)
        dx = (ctypes.c_double * n)()
        if n:
            (self.fmu.getContinuousStateDerivatives if self.fmi3 else self.fmu.getDerivatives)(dx, n)
        return np.array(dx[:]), self._reals(self.computed)

    # --- the matrices ---

    def pattern(self) -> np.ndarray:
        """Which unknowns (derivatives, then the outputs that are not states) the ModelStructure
        says depend on which knowns (states, then inputs), element by element."""
        knowns = dict(self.states.columns)
        offset = len(self.states.names)
        knowns |= {vr: range(r.start + offset, r.stop + offset) for vr, r in self.inputs.columns.items()}
        n_knowns = offset + len(self.inputs.names)
        computed = set(self.computed.vrs)
        unknowns = list(self.md.derivatives) + [
            u for u in self.unknown_outputs if u.variable.valueReference in computed
        ]
        sizes = [math.prod(tuple(u.variable.shape or ())) if self.fmi3 else 1 for u in unknowns]
        pattern = np.zeros((sum(sizes), n_knowns), dtype=bool)
        row = 0
        for unknown, size in zip(unknowns, sizes):
            if unknown.dependencies is None:  # no list: every known
                pattern[row : row + size] = True
            else:
                columns = [
                    k
                    for variable in unknown.dependencies
                    if variable.valueReference in knowns
                    for k in knowns[variable.valueReference]
                ]
                pattern[row : row + size, columns] = True
            row += size
        return pattern

    def linearize(self, method: str, grouped: bool, step: float) -> LinearModel:
        pattern = self.pattern()
        n_knowns = pattern.shape[1]
        groups = color_columns(pattern) if grouped else [[j] for j in range(n_knowns) if pattern[:, j].any()]
        if method == "directional":
            jacobian, error = self._directional(pattern, groups), None
            calls = len(groups)
        else:
            jacobian, error = self._differences(pattern, groups, step)
            calls = 4 * len(groups)
        self._call("restoring the operating point", self._at, self.x0, self.u0)
        return self._model(jacobian, error, method, calls)

    def _directional(self, pattern, groups) -> np.ndarray:
        """One fmi2GetDirectionalDerivative / fmi3GetDirectionalDerivative per group, its seed 1
        on the group's columns (FMI 2.0: only the group's knowns are passed; FMI 3.0: every
        known, an array whole), into ctypes arrays made once."""
        from ctypes import c_double, c_uint

        knowns = list(self.states.vrs) + list(self.inputs.vrs)
        unknowns = list(self.derivatives.vrs) + list(self.computed.vrs)
        n_rows, n_columns = pattern.shape
        unknown_refs = (c_uint * len(unknowns))(*unknowns)
        sensitivity = (c_double * n_rows)()
        jacobian = np.zeros(pattern.shape)
        if self.fmi3:
            known_refs = (c_uint * len(knowns))(*knowns)
            seed = (c_double * n_columns)()
        for group in groups:
            if self.fmi3:
                ctypes.memset(seed, 0, ctypes.sizeof(seed))
                for j in group:
                    seed[j] = 1.0
                arguments = (unknown_refs, len(unknowns), known_refs, len(knowns), seed, n_columns)
                self._call(
                    "fmi3GetDirectionalDerivative",
                    self.fmu.fmi3GetDirectionalDerivative,
                    self.fmu.component,
                    *arguments,
                    sensitivity,
                    n_rows,
                )
            else:
                group_refs = (c_uint * len(group))(*(knowns[j] for j in group))
                ones = (c_double * len(group))(*([1.0] * len(group)))
                self._call(
                    "fmi2GetDirectionalDerivative",
                    self.fmu.fmi2GetDirectionalDerivative,
                    self.fmu.component,
                    unknown_refs,
                    len(unknowns),
                    group_refs,
                    len(group),
                    ones,
                    sensitivity,
                )
            _scatter(jacobian, pattern, group, np.ctypeslib.as_array(sensitivity))
        return jacobian

    def _differences(self, pattern, groups, step) -> tuple[np.ndarray, np.ndarray]:
        """Central differences at h and 2h per group, extrapolated: R = (4 D(h) - D(2h)) / 3.
        The error estimate of each entry: |D(h) - D(2h)| / 3 (D(h)'s own truncation error,
        which bounds R's where the h^2 term dominates) plus rounding, 4 eps s / h, with s the
        size of what f is made of: its largest value, or the terms J_ik x_k where they cancel
        to a smaller f (y = C x + D u can be near 0 with every term of order 1)."""
        point = np.concatenate([self.x0, self.u0])
        nominal = np.array(
            [self._nominal(name) for name in self.states.names + self.inputs.names] if len(point) else []
        )
        h = step * np.maximum(np.abs(point), nominal)
        jacobian, truncation = np.zeros(pattern.shape), np.zeros(pattern.shape)
        largest = np.zeros(pattern.shape[0])  # each unknown's largest value met
        n = len(self.x0)

        def values(at):
            self._at(at[:n], at[n:])
            return np.concatenate(self._evaluate())

        for group in groups:
            direction = np.zeros(len(point))
            direction[group] = h[group]
            scale = np.zeros(pattern.shape[0])
            for j in group:
                scale[pattern[:, j]] = h[j]
            fs = [
                self._call("evaluating a difference", values, point + k * direction) for k in (1, -1, 2, -2)
            ]
            largest = np.maximum(largest, np.max(np.abs(fs), axis=0))
            with np.errstate(divide="ignore", invalid="ignore"):
                near = np.where(scale > 0, (fs[0] - fs[1]) / (2 * scale), 0.0)
                far = np.where(scale > 0, (fs[2] - fs[3]) / (4 * scale), 0.0)
            _scatter(jacobian, pattern, group, (4 * near - far) / 3)
            _scatter(truncation, pattern, group, np.abs(near - far) / 3)
        size = np.maximum(largest, np.abs(jacobian) @ np.abs(point))
        rounding = 4 * np.finfo(float).eps * np.outer(size, 1 / np.where(h > 0, h, 1.0))
        return jacobian, np.where(pattern, truncation + rounding, 0.0)

    def _nominal(self, name: str) -> float:
        variable = self._variables.get(name)
        nominal = getattr(variable, "nominal", None) if variable is not None else None
        try:
            return abs(float(nominal)) if nominal is not None else 1.0
        except ValueError:
            return 1.0

    def _model(self, jacobian, error, method, calls) -> LinearModel:
        n, m = len(self.states.names), len(self.inputs.names)
        n_out = len(self.outputs.names)
        full = np.zeros((n + n_out, n + m))
        full_error = None if error is None else np.zeros(full.shape)
        rows = self._unknown_rows()
        full[rows] = jacobian
        if error is not None:
            full_error[rows] = error
        state_of = dict(zip(self.states.vrs, self.states.columns.values()))
        for vr, positions in self.outputs.columns.items():
            if vr in state_of:  # an output that is a state: its own row, exactly
                for row, column in zip(positions, state_of[vr]):
                    full[n + row, column] = 1.0
        return LinearModel(
            A=full[:n, :n],
            B=full[:n, n:],
            C=full[n:, :n],
            D=full[n:, n:],
            states=list(self.states.names),
            inputs=list(self.inputs.names),
            outputs=list(self.outputs.names),
            x0=self.x0,
            u0=self.u0,
            y0=self.y0,
            dx0=self.dx0,
            time=self.time,
            method=method,
            calls=calls,
            fmu=str(self.path),
            error=full_error,
        )

    def _unknown_rows(self) -> list[int]:
        """Where the unknowns' rows go in [[A, B], [C, D]]: the derivatives, then the outputs
        that are not states at their places among the outputs."""
        n = len(self.states.names)
        places = self.outputs.columns
        return list(range(n)) + [n + row for vr in self.computed.vrs for row in places[vr]]

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


def _scatter(matrix, pattern, group, values) -> None:
    """A group's values into its columns: each row to the one column of the group it depends on."""
    for j in group:
        rows = pattern[:, j]
        matrix[rows, j] = values[rows]


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
