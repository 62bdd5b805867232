"""fmpy.simulate_fmu for any FMI 2.0 Co-Simulation FMU, with the communication loop in C.

fmpy's loop costs some 25 us of Python per communication step, about 20 times the
physics of a step of our native FMU. Here Python pays once per run (setupExperiment, the
start values and initialization through fmpy's own functions, terminate), and
csrc/runner.c does every doStep and getReal/getInteger/getBoolean, calling the functions
fmpy loaded from the FMU's library, into one record buffer in the layout of fmpy's
result. The communication points, the calls, the handling of fmi2Discard and the rows
are fmpy's (simulateCS, without input signals), so the results are bit for bit the same.

The C is compiled on first use on each machine (a Dask worker on another host compiles
its own, for its platform) and cached under the project's cache root by a hash of its
source, the FMI headers and the compile command; without a C compiler `unavailable()`
says why and callers fall back to fmpy's loop.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import os
import platform
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from fmpy.fmi1 import FMICallException
from fmpy.simulation import (
    Recorder,
    apply_start_values,
    settable_in_initialization_mode,
    settable_in_instantiated,
)

from ..builder.core.cache import cache_root
from ..builder.packaging.native import COMPILERS, fmi_headers
from ..errors import UserError

SOURCE = Path(__file__).parent / "csrc" / "runner.c"
LOOPS = ("runner", "fmpy")  # the communication loops a run can take: this module's, or fmpy's own
RUN_DONE, RUN_FULL, RUN_FAILED = 0, 1, 2
# the FMI functions the loop calls: runner.c's Run begins with them, and FAILED_* numbers them
LOOP_FUNCTIONS = (
    "fmi2DoStep",
    "fmi2GetReal",
    "fmi2GetInteger",
    "fmi2GetBoolean",
    "fmi2GetBooleanStatus",
    "fmi2GetRealStatus",
)
# per recorded type: Run's field for one row of values, and the values' C type
ROW_VALUES = {
    "Real": ("reals", np.float64),
    "Integer": ("integers", np.int32),
    "Boolean": ("booleans", np.int32),
}


class RunFailed(FMICallException):
    """fmpy's FMICallException for a call of the loop that failed, with the rows recorded
    before it: fmpy's loop loses them, a sweep keeps them."""

    def __init__(self, function: str, status: int, rows: np.ndarray):
        super().__init__(function=function, status=status)
        self.rows = rows


class _Run(ctypes.Structure):
    """runner.c's Run."""

    _fields_ = [
        *((name, ctypes.c_void_p) for name in LOOP_FUNCTIONS),
        ("component", ctypes.c_void_p),
        ("realVrs", ctypes.c_void_p),
        ("integerVrs", ctypes.c_void_p),
        ("booleanVrs", ctypes.c_void_p),
        ("nReal", ctypes.c_size_t),
        ("nInteger", ctypes.c_size_t),
        ("nBoolean", ctypes.c_size_t),
        ("reals", ctypes.c_void_p),
        ("integers", ctypes.c_void_p),
        ("booleans", ctypes.c_void_p),
        ("startTime", ctypes.c_double),
        ("stopTime", ctypes.c_double),
        ("interval", ctypes.c_double),
        ("canHandleVariableStepSize", ctypes.c_int),
        ("rows", ctypes.c_void_p),
        ("rowSize", ctypes.c_size_t),
        ("capacity", ctypes.c_size_t),
        ("time", ctypes.c_double),
        ("nSteps", ctypes.c_longlong),
        ("nRows", ctypes.c_size_t),
        ("failedFunction", ctypes.c_int),
        ("failedStatus", ctypes.c_int),
    ]


def _compile_command(output: Path) -> list[str]:
    compiler, _, libraries = COMPILERS["linux64"]
    # -ffp-contract=off: no fused multiply-add, so the communication points are Python's
    return [
        *compiler,
        "-std=c99",
        "-O2",
        "-ffp-contract=off",
        "-shared",
        "-Wall",
        "-Wextra",
        "-Werror",
        f"-I{fmi_headers()}",
        str(SOURCE),
        "-o",
        str(output),
        *libraries,
    ]


@functools.cache
def library() -> ctypes.CDLL:
    """runner.c compiled for this machine, on first use, cached by what it is built from."""
    if sys.platform != "linux":
        raise UserError(f"the compiled runner is built on Linux only (this is {sys.platform})")
    compiler = COMPILERS["linux64"][0][0]
    if shutil.which(compiler) is None:
        raise UserError(f"the compiled runner needs the C compiler {compiler}, which is not on PATH")
    digest = hashlib.sha256(
        " ".join(_compile_command(Path("runner.so"))).encode() + platform.machine().encode()
    )
    for path in [SOURCE, fmi_headers() / "fmi2FunctionTypes.h", fmi_headers() / "fmi2TypesPlatform.h"]:
        digest.update(path.read_bytes())
    path = cache_root() / "runner" / f"fmi2_runner_{digest.hexdigest()[:16]}.so"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        # compiled beside its place and renamed into it: processes compiling at once each
        # install a whole library
        descriptor, building = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=".so")
        os.close(descriptor)
        try:
            command = _compile_command(Path(building))
            run = subprocess.run(command, check=False, capture_output=True, text=True)
            if run.returncode:
                raise UserError(f"compiling the runner failed:\n{' '.join(command)}\n{run.stderr}")
            os.replace(building, path)
        finally:
            Path(building).unlink(missing_ok=True)
    loaded = ctypes.CDLL(str(path))  # CDLL: the GIL is released for the loop
    loaded.fmi2_cs_run.argtypes = [ctypes.POINTER(_Run)]
    loaded.fmi2_cs_run.restype = ctypes.c_int
    return loaded


def unavailable() -> str | None:
    """Why the compiled runner cannot serve on this machine, or None when it can."""
    try:
        library()
    except UserError as exc:
        return str(exc)
    return None


class Runner:
    """simulate_fmu's Co-Simulation run of one loaded FMU (fmpy's FMU2Slave), recording
    `output` (None: fmpy's default), with the loop in C; made once, run many times."""

    def __init__(self, slave, model_description, output=None):
        md = model_description
        if md.fmiVersion != "2.0" or md.coSimulation is None:
            raise ValueError(f"{md.modelName}: the runner serves FMI 2.0 Co-Simulation FMUs only")
        self.slave, self.md = slave, md
        recorder = Recorder(fmu=slave, modelDescription=md, variableNames=output)
        self.dtype = np.dtype(recorder.cols)  # fmpy's record: time, Reals, Integers, Booleans
        self._run = run = _Run()
        for name in LOOP_FUNCTIONS:
            setattr(run, name, ctypes.cast(getattr(slave.dll, name), ctypes.c_void_p).value)
        self._arrays = []  # the value references and one row of values, alive as long as _run
        for kind, (field, c_type) in ROW_VALUES.items():
            vrs = recorder.info[kind][1] if kind in recorder.info else []
            references, values = np.array(vrs, dtype=np.uint32), np.zeros(len(vrs), dtype=c_type)
            self._arrays += [references, values]
            setattr(run, f"{kind.lower()}Vrs", references.ctypes.data)
            setattr(run, f"n{kind}", len(vrs))
            setattr(run, field, values.ctypes.data)
        run.rowSize = self.dtype.itemsize
        run.canHandleVariableStepSize = bool(md.coSimulation.canHandleVariableCommunicationStepSize)
        experiment = md.defaultExperiment
        self.start_time = (
            float(experiment.startTime) if experiment and experiment.startTime is not None else 0.0
        )
        self.tolerance = (
            float(experiment.tolerance) if experiment and experiment.tolerance is not None else None
        )
        self._library = library()

    @functools.lru_cache(maxsize=64)  # noqa: B019 (a Runner lives as long as its FMU)
    def _named(self, names: tuple[str, ...]) -> SimpleNamespace:
        """The model description as apply_start_values reads it, with only the variables
        `names` names, in its order: fmpy's setting of the start values, without its pass over
        every variable twice a run."""
        md = self.md
        return SimpleNamespace(
            fmiVersion=md.fmiVersion,
            unitDefinitions=md.unitDefinitions,
            modelVariables=[v for v in md.modelVariables if v.name in names],
        )

    def simulate(self, stop_time: float, output_interval: float, start_values=None) -> np.ndarray:
        """fmpy.simulate_fmu(..., fmu_instance=slave) on the instantiated slave: its rows, or
        fmpy's exceptions where it raises (a failed call of the loop: RunFailed, with the rows
        before it)."""
        slave, start_time, stop_time = self.slave, self.start_time, float(stop_time)
        start_values = start_values or {}
        named = self._named(tuple(start_values))
        slave.setupExperiment(tolerance=self.tolerance, startTime=start_time, stopTime=stop_time)
        left = apply_start_values(slave, named, start_values, settable=settable_in_instantiated)
        slave.enterInitializationMode()
        left = apply_start_values(slave, named, left, settable=settable_in_initialization_mode)
        slave.exitInitializationMode()
        if left:
            raise Exception(  # fmpy's words
                "The start values for the following variables could not be set: " + ", ".join(left.keys())
            )
        run = self._run
        run.component = slave.component
        run.startTime, run.stopTime, run.interval = start_time, stop_time, output_interval
        run.time, run.nSteps, run.nRows = start_time, 0, 0
        # fmpy's points, the last one stepped short, and a discarded step's repeat
        rows = np.empty(max(1, int((stop_time - start_time) / output_interval)) + 3, dtype=self.dtype)
        while True:
            run.rows, run.capacity = rows.ctypes.data, len(rows)
            outcome = self._library.fmi2_cs_run(ctypes.byref(run))
            if outcome != RUN_FULL:
                break
            rows = np.concatenate([rows, np.empty(len(rows), dtype=self.dtype)])
        if outcome == RUN_FAILED:
            raise RunFailed(LOOP_FUNCTIONS[run.failedFunction], run.failedStatus, rows[: run.nRows].copy())
        slave.terminate()
        return rows[: run.nRows]
