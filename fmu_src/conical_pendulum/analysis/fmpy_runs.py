"""fmpy glue: runs with the output interval always given and the FMU's folder removed however
they end, and a logger that collects messages."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from .fmi3_arrays import array_start_values, fmu_data, scalar_columns

# fmpy's types of a whole-number variable (the solver is an Enumeration): set as integers
WHOLE_TYPES = ("Integer", "Int32", "Enumeration")


def logging_callbacks(on_message):
    """fmi2CallbackFunctions that hand each log message to on_message(status, text).

    Pass them to fmpy's instantiate with loggingOn=True: pythonfmu forwards messages
    only then. Keep the returned object alive as long as the instance.
    """
    from fmpy.fmi1 import calloc, free
    from fmpy.fmi2 import (
        fmi2CallbackAllocateMemoryTYPE,
        fmi2CallbackFreeMemoryTYPE,
        fmi2CallbackFunctions,
        fmi2CallbackLoggerTYPE,
    )

    def log(component, instance, status, category, message):
        on_message(status, message.decode(errors="replace"))

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(log)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    return callbacks


def simulate_fmu(fmu_path, **kwargs):
    """fmpy.simulate_fmu on the FMU unzipped into a temporary folder, removed on leaving whatever
    happened (a folder given is run as it is and kept): fmpy removes the folder it extracts to
    only when the run completes, and leaves it behind whenever the FMU refuses and it raises."""
    import fmpy

    if Path(fmu_path).is_dir():
        return fmpy.simulate_fmu(str(fmu_path), **kwargs)
    folder = tempfile.mkdtemp(prefix="conical_pendulum_fmu_")
    try:
        fmpy.extract(str(fmu_path), folder)
        return fmpy.simulate_fmu(folder, **kwargs)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def run_fmu(fmu_path, stop_time=10.0, output_interval=1.0 / 60.0, start_values=None, **kwargs):
    """fmpy.simulate_fmu with the output interval always given (fmpy ignores step_size for CS).
    An FMI 3.0 FMU of this package takes and gives the FMI 2.0 FMU's scalar names (its arrays
    set whole and split into columns: analysis.fmi3_arrays)."""
    data = fmu_data(fmu_path)
    if data is not None:
        start_values = array_start_values(data, start_values or {})
    result = simulate_fmu(
        fmu_path,
        stop_time=stop_time,
        output_interval=output_interval,
        start_values=start_values or {},
        **kwargs,
    )
    return result if data is None else scalar_columns(data, result)
