"""On a worker: the FMU extracted and loaded once (a WorkerPlugin carries its bytes), and a
batch of runs run on it, each noted while it runs (crashes.py reads the notes)."""

from __future__ import annotations

import contextlib
import faulthandler
import functools
import io
import logging
import math
import os
import shutil
import tempfile
import threading
import zipfile
from pathlib import Path

import numpy as np
from distributed import WorkerPlugin, get_worker
from fmpy import read_model_description
from fmpy.fmi2 import FMU2Slave

from .. import runner
from ..fmpy_runs import logging_callbacks, run_fmu
from .crashes import extracted, notes_folder

logger = logging.getLogger(__name__)


class LoadedFmu:
    """An FMU extracted, described and its library loaded once; instantiated afresh per run.

    A run goes through the compiled runner (analysis.runner) or, with loop="fmpy" or where
    the runner cannot serve (`fallback` says why), fmpy's own loop: the same rows.
    Runs in one process take turns: one library serves them, and a pythonfmu slave, being
    Python, would hold the GIL anyway. `loads` counts the FMUs this process has loaded (a sweep loads once per worker).
    """

    loads = 0

    def __init__(self, data: bytes, loop: str = "runner", directory: Path | None = None):
        if directory is None:
            directory = tempfile.mkdtemp(prefix="conical_pendulum_sweep_")
        else:
            directory.mkdir()
        self.directory = str(directory)
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            archive.extractall(self.directory)
        self.md = read_model_description(self.directory)

        self._callbacks = logging_callbacks(
            lambda status, text: self.messages.append(text.replace("\n", " "))
        )
        # fmpy's freeInstance also unloads the library; instances are freed with
        # fmi2FreeInstance instead, so the library stays loaded for the next run.
        self.slave = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=self.directory,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName="sweep",
        )
        self._lock = threading.Lock()
        self.messages = []
        self.loop, self.fallback = loop, None
        if loop == "runner":
            self.fallback = runner.unavailable()
            if self.fallback:
                self.loop = "fmpy"
                logger.warning(
                    "%s: fmpy's loop instead of the compiled runner: %s", self.md.modelName, self.fallback
                )
        self._runners = {}  # by the outputs recorded
        LoadedFmu.loads += 1

    def simulate(
        self, start_values: dict, stop_time: float, output_interval: float, outputs: list[str]
    ) -> np.ndarray:
        """fmpy.simulate_fmu's rows on a fresh instance, by this FMU's loop; raises as fmpy does."""
        self.slave.instantiate(callbacks=self._callbacks, loggingOn=True)
        try:
            if self.loop == "fmpy":
                return run_fmu(
                    self.directory,
                    stop_time,
                    output_interval,
                    start_values,
                    output=outputs,
                    model_description=self.md,
                    fmu_instance=self.slave,
                )
            key = tuple(outputs)
            if key not in self._runners:
                self._runners[key] = runner.Runner(self.slave, self.md, outputs)
            return self._runners[key].simulate(stop_time, output_interval, start_values)
        finally:  # fmi2FreeInstance is all FMI allows after fmi2Fatal
            self.slave.fmi2FreeInstance(self.slave.component)

    def run(
        self, start_values: dict, stop_time: float, output_interval: float, outputs: list[str]
    ) -> tuple[np.ndarray | None, bool, str]:
        """(rows as fmpy records them or None, ok, message), with the FMU's messages."""
        with self._lock:
            self.messages = problems = []  # this run's, also once the next has begun
            failure = None
            try:
                rows = self.simulate(start_values, stop_time, output_interval, outputs)
            except Exception as exc:
                # the compiled runner keeps the rows before a failed call (runner.RunFailed)
                rows, failure = getattr(exc, "rows", None), str(exc)
                problems.append(failure)
        if rows is None or len(rows) == 0:
            return None, False, "; ".join(problems)
        # after a discarded step fmpy samples the last good point a second time
        later = np.diff(rows["time"]) > 0
        if not later.all():
            rows = rows[np.r_[True, later]]
        end = rows["time"][-1]
        stopped_early = end < stop_time and not math.isclose(end, stop_time)
        if stopped_early and not problems:
            problems.append(f"stopped at t = {end:g} s, short of the stop time {stop_time:g} s")
        not_finite = non_finite_columns(rows, outputs)
        if not_finite:
            problems.append(f"non-finite values in {', '.join(not_finite)}")
        return rows, not (failure or stopped_early or not_finite), "; ".join(problems)

    def close(self):
        self.slave.freeLibrary()
        shutil.rmtree(self.directory, ignore_errors=True)


@functools.cache
def _leading_reals(dtype: np.dtype) -> tuple[str, ...]:
    """The names of fmpy's record's leading float64 fields at offsets 0, 8, 16, ...: the time
    and the Reals."""
    leading = []
    for name in dtype.names:
        if dtype.fields[name][0] != np.float64 or dtype.fields[name][1] != 8 * len(leading):
            break
        leading.append(name)
    return tuple(leading)


def non_finite_columns(rows: np.ndarray, names: list[str]) -> list[str]:
    """The columns among `names` holding a NaN or an infinity. fmpy's record begins with the
    time and the Reals, 8 bytes each: one isfinite over that block, not one pass per column (a
    quarter of the runner's time outside its C loop). Integers and Booleans are always finite."""
    leading = _leading_reals(rows.dtype)
    block = np.ndarray((len(rows), len(leading)), np.float64, buffer=rows, strides=(rows.dtype.itemsize, 8))
    finite = np.isfinite(block)
    if finite.all():  # the common case, at a third of the cost of the columns' answers
        return []
    by_name = dict(zip(leading, finite.all(axis=0)))
    return [name for name in names if not by_name.get(name, True)]


class FmuPlugin(WorkerPlugin):
    """Loads the FMU it carries once on each worker, and removes it when unregistered.

    The worker notes in a file of its host which run it is in, and faulthandler adds the
    fatal signal that kills it there: a worker that dies names its run and the signal to
    the workers that come after it (`crashes.read_notes`), on any cluster."""

    def __init__(self, data: bytes, loop: str, name: str):
        self.data, self.loop, self.name = data, loop, name

    def setup(self, worker):
        notes_folder(self.name).mkdir(exist_ok=True)
        self.note = open(notes_folder(self.name) / str(os.getpid()), "w")  # noqa: SIM115 (closed in teardown)
        self.catches = not faulthandler.is_enabled()  # a process's one handler: leave another's alone
        if self.catches:
            faulthandler.enable(self.note, all_threads=False)
        # beside the note: whatever ends this process, its nanny or the client removes it
        self.fmu = LoadedFmu(self.data, self.loop, extracted(self.name, os.getpid()))
        self.data = None  # extracted: the worker keeps no second copy

    def running(self, index: int | None):
        """Notes the run this worker is in (None: none)."""
        self.note.seek(0)
        self.note.truncate()
        if index is not None:
            self.note.write(f"{index}\n")
        self.note.flush()

    def teardown(self, worker):
        self.fmu.close()
        if self.catches:
            faulthandler.disable()
        self.note.close()
        Path(self.note.name).unlink(missing_ok=True)
        with contextlib.suppress(OSError):  # other workers' notes may still be there
            notes_folder(self.name).rmdir()


def run_batch(
    plugin: str, batch: list[tuple[int, dict]], stop_time: float, output_interval: float, outputs: list[str]
):
    """On a worker: the batch's runs as ([(run, ok, message, rows kept)], their rows in one
    record array or None). One buffer crosses to the client: a frame of the rows, with a
    message per row, cost more to build and send than the runs themselves."""
    loaded = get_worker().plugins[plugin]
    done = []
    for index, start_values in batch:
        loaded.running(index)
        done.append((index, *loaded.fmu.run(start_values, stop_time, output_interval, outputs)))
    loaded.running(None)
    kept = [rows for _, rows, _, _ in done if rows is not None]
    summary = [(index, ok, message, 0 if rows is None else len(rows)) for index, rows, ok, message in done]
    return summary, np.concatenate(kept) if kept else None
