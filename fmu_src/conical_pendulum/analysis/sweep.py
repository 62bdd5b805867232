"""Parameter and initial-condition sweeps of an FMU, run as Dask tasks, streamed into a Parquet dataset.

    conical-pendulum sweep dist/ConicalPendulum.fmu --grid l0=5,10,15 --grid alpha0=0.1,0.2
    conical-pendulum sweep dist/ConicalPendulum.fmu --random l0=5:15 --samples 100 --seed 1

Each worker process extracts the FMU, reads its model description and loads its library
once (a WorkerPlugin carries the FMU's bytes, so a remote cluster needs no shared
filesystem), then instantiates it once per run, since pythonfmu 0.7 has no fmi2Reset
to rely on, and runs it with the communication loop in C (analysis.runner; fmpy's own
loop with loop="fmpy", or where the runner cannot be compiled: the same rows). Runs
travel in batches, several to a task, so that Dask's cost per task stays small next to
a run's few milliseconds. A run fails, keeping the rows it produced and the
FMU's message, when a value is refused (fmi2Fatal), a step is discarded (the rows up
to the last good point), an output is not finite, or it kills its worker process twice.

The client writes what the workers return, batch by batch, into a folder of Parquet
files, with a bounded number of batches in flight: its memory does not grow with the
runs, a killed sweep keeps what it wrote, and `resume` runs only what is missing.
"""

from __future__ import annotations

import asyncio
import contextlib
import faulthandler
import hashlib
import io
import itertools
import json
import logging
import math
import numbers
import os
import shutil
import signal
import sys
import tempfile
import threading
import time
import uuid
import zipfile
from collections import deque
from collections.abc import Iterable, Mapping, Sequence
from concurrent.futures import CancelledError
from pathlib import Path

import dask
import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.dataset as ds
import pyarrow.parquet as pq
from distributed import Client, LocalCluster, WorkerPlugin, as_completed, get_worker
from distributed.scheduler import KilledWorker
from fmpy import read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.simulation import settable_in_initialization_mode, settable_in_instantiated

from ..progress import bar
from . import runner
from .fmpy_runs import WHOLE_TYPES, logging_callbacks, run_fmu

logger = logging.getLogger(__name__)
LOOPS = ("runner", "fmpy")  # sweep()'s loop: analysis.runner's compiled loop, or fmpy's own
SETTINGS_FILE = "_sweep.json"  # the dataset's settings; a leading _ hides it from Parquet readers
PART_SECONDS, PART_BYTES = 5.0, 256 << 20  # a part file is closed after this long or this much
LOST_TIMES = 4  # a run lost with its worker this often, no note saying it was running, fails


def grid(axes: Mapping[str, Sequence[float]]) -> list[dict]:
    """Every combination of the values given per variable (the last varies fastest), as runs."""
    empty = [name for name, values in axes.items() if len(values) == 0]
    if empty:
        raise ValueError(f"grid: no values for {', '.join(empty)}")
    return [dict(zip(axes, combination)) for combination in itertools.product(*axes.values())]


def random_samples(ranges: Mapping[str, tuple[float, float]], n: int, seed=None) -> list[dict]:
    """n runs drawn uniformly from [low, high) per variable; the same seed gives the same runs."""
    if n < 1:
        raise ValueError(f"random samples: n = {n}: must be at least 1")
    for name, (low, high) in ranges.items():
        if not (math.isfinite(low) and math.isfinite(high) and low <= high):
            raise ValueError(f"random samples: {name} range {low}:{high} must be finite with low <= high")
    lows, highs = zip(*ranges.values()) if ranges else ((), ())
    draws = np.random.default_rng(seed).uniform(lows, highs, size=(n, len(ranges)))
    return [dict(zip(ranges, map(float, row))) for row in draws]


class LoadedFmu:
    """An FMU extracted, described and its library loaded once; instantiated afresh per run.

    A run goes through the compiled runner (analysis.runner) or, with loop="fmpy" or where
    the runner cannot serve (`fallback` says why), fmpy's own loop: the same rows.
    Runs in one process take turns: one library serves them, and a pythonfmu slave, being
    Python, would hold the GIL anyway. `loads` counts the FMUs this process has loaded (a sweep loads once per worker).
    """

    loads = 0

    def __init__(self, data: bytes, loop: str = "runner"):
        self.directory = tempfile.mkdtemp(prefix="conical_pendulum_sweep_")
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
        not_finite = [name for name in outputs if not np.isfinite(rows[name]).all()]
        if not_finite:
            problems.append(f"non-finite values in {', '.join(not_finite)}")
        return rows, not (failure or stopped_early or not_finite), "; ".join(problems)

    def close(self):
        self.slave.freeLibrary()
        shutil.rmtree(self.directory, ignore_errors=True)


# faulthandler's words for the fatal signals it catches
FATAL_SIGNALS = {
    "Segmentation fault": "SIGSEGV",
    "Floating-point exception": "SIGFPE",
    "Aborted": "SIGABRT",
    "Bus error": "SIGBUS",
    "Illegal instruction": "SIGILL",
}


class _LeaveCtrlCToTheClient(WorkerPlugin):
    """A terminal's Ctrl-C reaches the local cluster's worker processes too: they ignore it,
    so that the client stops the sweep (keeping what is written) and closes them, rather
    than each dying with a traceback."""

    def setup(self, worker):
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def _notes_folder(plugin: str) -> Path:
    """Where a host's worker processes of one sweep note the run they are in."""
    return Path(tempfile.gettempdir()) / plugin


class _FmuPlugin(WorkerPlugin):
    """Loads the FMU it carries once on each worker, and removes it when unregistered.

    The worker notes in a file of its host which run it is in, and faulthandler adds the
    fatal signal that kills it there: a worker that dies names its run and the signal to
    the workers that come after it (`_deaths`), on any cluster."""

    def __init__(self, data: bytes, loop: str, name: str):
        self.data, self.loop, self.name = data, loop, name

    def setup(self, worker):
        self.fmu = LoadedFmu(self.data, self.loop)
        self.data = None  # extracted: the worker keeps no second copy
        _notes_folder(self.name).mkdir(exist_ok=True)
        self.note = open(_notes_folder(self.name) / str(os.getpid()), "w")  # noqa: SIM115 (closed in teardown)
        self.catches = not faulthandler.is_enabled()  # a process's one handler: leave another's alone
        if self.catches:
            faulthandler.enable(self.note, all_threads=False)

    def running(self, index: int | None):
        """Notes the run this worker is in (None: none)."""
        self.note.seek(0)
        self.note.truncate()
        if index is not None:
            self.note.write(f"{index}\n")
        self.note.flush()

    def teardown(self, worker):
        if self.catches:
            faulthandler.disable()
        self.note.close()
        Path(self.note.name).unlink(missing_ok=True)
        with contextlib.suppress(OSError):  # other workers' notes may still be there
            _notes_folder(self.name).rmdir()
        self.fmu.close()


def _deaths(plugin: str) -> dict[int, tuple[int | None, str]]:
    """On a worker: the notes its host's dead worker processes of this sweep left, as
    {pid: (the run it was in or None, faulthandler's words for the signal or "")}; read
    once, then removed."""
    found = {}
    folder = _notes_folder(plugin)
    for note in folder.iterdir() if folder.is_dir() else ():
        if _running(int(note.name)):
            continue
        first, _, rest = note.read_text().partition("\n")
        fatal = [line for line in rest.splitlines() if line.startswith("Fatal Python error: ")]
        cause = fatal[0].removeprefix("Fatal Python error: ") if fatal else ""
        found[int(note.name)] = (int(first) if first.isdigit() else None, cause)
        note.unlink()
    return found


def _running(pid: int) -> bool:
    """Whether that process runs (a zombie, dead but not yet reaped by its nanny, does not)."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rpartition(")")[2].split()[0] != "Z"
    except FileNotFoundError:
        return False
    except OSError:  # no /proc
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return False
        return True


def _death_message(causes: list[str]) -> str:
    """A failed run's message when its worker process died: twice running it, as the notes
    say, or lost LOST_TIMES times with it and no note saying why."""
    fatal = causes[-1] if causes else ""
    if fatal:
        cause = f"{FATAL_SIGNALS[fatal]}, {fatal.lower()}" if fatal in FATAL_SIGNALS else fatal
    elif causes:
        cause = "no fatal signal caught: killed from outside, e.g. SIGKILL or out of memory"
    else:
        return f"the worker process was lost {LOST_TIMES} times with this run, with no note of why"
    return f"the worker process died running this run, twice ({cause})"


def _run_batch(
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


def _check_runs(md, runs: Iterable[Mapping]) -> list[dict]:
    """The runs with values as the FMU's types; unknown or unsettable names and non-numbers refused."""
    runs = [dict(run) for run in runs]
    if not runs:
        raise ValueError("no runs to do")
    variables = {v.name: v for v in md.modelVariables}
    names = set().union(*runs)
    unknown = sorted(names - variables.keys())
    if unknown:
        raise ValueError(f"unknown variable(s) {', '.join(unknown)}: {md.modelName} has no such variable")
    fixed = sorted(
        name
        for name in names
        if not (settable_in_instantiated(variables[name]) or settable_in_initialization_mode(variables[name]))
    )
    if fixed:
        raise ValueError(
            f"{', '.join(fixed)} cannot be set (calculated); a run sets parameters and start values"
        )
    for index, run in enumerate(runs):
        for name, value in run.items():
            if isinstance(value, bool) or not isinstance(value, numbers.Real):
                raise ValueError(f"run {index}: {name} = {value!r} is not a number")
            if variables[name].type in WHOLE_TYPES:
                if not float(value).is_integer():
                    raise ValueError(
                        f"run {index}: {name} = {value!r}: {name} is an {variables[name].type} variable"
                    )
                run[name] = int(value)
            else:
                run[name] = float(value)
    return runs


def _check_outputs(md, outputs: Sequence[str] | None) -> list[str]:
    """The variables to record: the given ones, known to the FMU, or all its outputs."""
    if outputs is None:
        return [v.name for v in md.modelVariables if v.causality == "output"]
    outputs = list(dict.fromkeys(outputs))
    if not outputs:
        raise ValueError("no outputs chosen")
    known = {v.name for v in md.modelVariables}
    unknown = [name for name in outputs if name not in known]
    if unknown:
        raise ValueError(f"unknown output(s) {', '.join(unknown)}: {md.modelName} has no such variable")
    return outputs


def _inputs(md, runs: list[dict]):
    """One row per run with every variable any run sets; a run that leaves one alone gets
    the FMU's start value (what it ran with). A state's start value is `<name>_start`,
    apart from its recorded trajectory."""
    variables = {v.name: v for v in md.modelVariables}
    names = list(dict.fromkeys(itertools.chain.from_iterable(runs)))
    columns = {}
    for name in names:
        variable = variables[name]
        start = (int if variable.type in WHOLE_TYPES else float)(variable.start)
        column = f"{name}_start" if variable.causality == "output" else name
        columns[column] = [run.get(name, start) for run in runs]
    return pd.DataFrame(columns, index=pd.RangeIndex(len(runs), name="run"))


def _schema(md, inputs: pd.DataFrame, outputs: list[str], settings: dict) -> pa.Schema:
    """The dataset's columns, the same in every file whatever its runs did, with the
    settings where pandas reads them into `attrs`."""
    kinds = {v.name: v.type for v in md.modelVariables}
    types = {"Real": pa.float64(), "Integer": pa.int32(), "Enumeration": pa.int32(), "Boolean": pa.bool_()}
    return pa.schema(
        [
            ("run", pa.int64()),
            *((name, pa.from_numpy_dtype(inputs[name].dtype)) for name in inputs.columns),
            ("status", pa.string()),
            ("message", pa.string()),
            ("time", pa.float64()),
            *((name, types[kinds[name]]) for name in outputs),
        ],
        metadata={"PANDAS_ATTRS": json.dumps(settings)},
    )


def _table(summary: list, rows: np.ndarray | None, inputs: dict, schema: pa.Schema) -> pa.Table:
    """A batch's rows in long form: each column copied once; a run that kept no rows gets
    one row with no time and no outputs (NaN in pandas)."""
    index, ok, message, kept = zip(*summary)
    kept = np.array(kept)
    lengths = np.maximum(kept, 1)
    run = np.repeat(np.array(index, dtype=np.int64), lengths)
    has_rows = np.repeat(kept > 0, lengths)
    columns = {
        "run": run,
        **{name: values[run] for name, values in inputs.items()},
        "status": np.repeat(np.array(["ok" if good else "failed" for good in ok], dtype=object), lengths),
        "message": np.repeat(np.array(message, dtype=object), lengths),
    }
    arrays = []
    for field in schema:
        if field.name in columns:
            arrays.append(pa.array(columns[field.name], type=field.type))
        elif rows is None:
            arrays.append(pa.nulls(len(run), field.type))
        elif has_rows.all():
            arrays.append(pa.array(np.ascontiguousarray(rows[field.name])).cast(field.type))
        else:
            values = np.zeros(len(run), rows.dtype[field.name])
            values[has_rows] = rows[field.name]
            arrays.append(pa.array(values, mask=~has_rows).cast(field.type))
    return pa.Table.from_arrays(arrays, schema=schema)


class _Parts:
    """The dataset's files as the client writes them: batches appended as row groups to a
    hidden file, renamed into the dataset once PART_SECONDS old or PART_BYTES large and when
    the sweep ends or stops, so a dataset holds only whole files and a killed client loses
    at most the open one's runs."""

    def __init__(self, folder: Path, schema: pa.Schema, number: int):
        self.folder, self.schema, self.number, self.writer = folder, schema, number, None
        # repeated values (a run's number, inputs, status, message) as dictionaries; outputs plain
        self.dictionary = [field.name for field in schema if field.name not in ("time", *_outputs_of(schema))]

    def write(self, table: pa.Table):
        if self.writer is None:
            self.path = self.folder / f".part-{self.number:05d}.parquet.tmp"
            self.writer = pq.ParquetWriter(self.path, self.schema, use_dictionary=self.dictionary)
            self.opened, self.size = time.monotonic(), 0
        self.writer.write_table(table)
        self.size += table.nbytes
        if self.size >= PART_BYTES or time.monotonic() - self.opened >= PART_SECONDS:
            self.close()

    def close(self):
        if self.writer is not None:
            self.writer.close()
            os.replace(self.path, self.folder / f"part-{self.number:05d}.parquet")
            self.writer, self.number = None, self.number + 1


def _outputs_of(schema: pa.Schema) -> list[str]:
    return json.loads(schema.metadata[b"PANDAS_ATTRS"])["outputs"]


def _settings(md, data: bytes, inputs: pd.DataFrame, stop_time, output_interval, outputs) -> dict:
    """What makes a sweep this sweep: a dataset written with other settings is never resumed."""
    runs = hashlib.sha256()
    for name in inputs.columns:
        values = inputs[name].to_numpy()
        runs.update(f"{name}:{values.dtype}:".encode())
        runs.update(np.ascontiguousarray(values).tobytes())
    return {
        "fmu": md.modelName,
        "fmu_guid": md.guid,
        "fmu_sha256": hashlib.sha256(data).hexdigest(),
        "stop_time": stop_time,
        "output_interval": output_interval,
        "outputs": outputs,
        "inputs": list(inputs.columns),
        "runs": len(inputs),
        "runs_sha256": runs.hexdigest(),
    }


def _shown(value) -> str:
    text = ",".join(map(str, value)) if isinstance(value, list) else f"{value}"
    return text if len(text) <= 40 else f"{text[:37]}..."


def _differences(found: dict, wanted: dict) -> list[str]:
    """What differs between a dataset's settings and this sweep's, in words."""
    said = []
    if found.get("fmu_sha256") != wanted["fmu_sha256"]:
        said.append(
            f"another FMU ({found.get('fmu')} sha256 {str(found.get('fmu_sha256'))[:12]} there, "
            f"{wanted['fmu']} {wanted['fmu_sha256'][:12]} here)"
        )
    for key, name in [
        ("outputs", "outputs"),
        ("stop_time", "stop time"),
        ("output_interval", "output interval"),
        ("runs", "runs"),
        ("inputs", "variables set"),
    ]:
        if found.get(key) != wanted[key]:
            said.append(f"{name} {_shown(found.get(key))} there, {_shown(wanted[key])} here")
    if not said and found.get("runs_sha256") != wanted["runs_sha256"]:
        said.append("other values of the runs (another grid, ranges, samples or seed)")
    return said


def _done_runs(folder: Path, total: int) -> np.ndarray:
    """Which runs the dataset's files hold, from their footers: the client writes a batch
    of consecutive runs, each whole, as one row group, so each row group's least and
    greatest run bound the runs it holds."""
    done = np.zeros(total, dtype=bool)
    for part in folder.glob("part-*.parquet"):
        metadata = pq.ParquetFile(part).metadata
        column = metadata.schema.names.index("run")
        for group in range(metadata.num_row_groups):
            statistics = metadata.row_group(group).column(column).statistics
            done[statistics.min : statistics.max + 1] = True
    return done


def _check_out(out: Path, settings: dict, resume: bool, overwrite: bool) -> tuple[np.ndarray, bool]:
    """(the runs the output holds already, whether to remove it first); refuses an output
    that is not this sweep's to resume or a sweep's to replace, before anything runs."""
    none = np.zeros(settings["runs"], dtype=bool)
    if not out.parent.is_dir():
        raise ValueError(f"out: {out.parent} is not a directory")
    if out.exists() and not out.is_dir():
        raise ValueError(f"out: {out} is a file; a sweep writes a folder: give another name")
    if not out.exists() or not any(out.iterdir()):
        return none, False
    settings_file = out / SETTINGS_FILE
    if not settings_file.is_file():
        raise ValueError(f"out: {out} is a folder that holds no sweep; give another name")
    if overwrite:
        return none, True
    if not resume:
        raise ValueError(
            f"out: {out} holds a sweep already; --resume (resume=True) finishes it, "
            "--overwrite (overwrite=True) replaces it"
        )
    different = _differences(json.loads(settings_file.read_text()), settings)
    if different:
        raise ValueError(
            f"out: {out} holds another sweep, not resumed: {'; '.join(different)}; "
            "give another output, or overwrite it"
        )
    return _done_runs(out, settings["runs"]), False


def _begin(out: Path, settings: dict, replace: bool) -> int:
    """The output folder made ready to write (the last client's open file dropped), and the
    number of its next file."""
    if replace:
        shutil.rmtree(out)
    out.mkdir(exist_ok=True)
    for unfinished in out.glob(".part-*.parquet.tmp"):
        unfinished.unlink()
    if not (out / SETTINGS_FILE).exists():
        written = out / f".{SETTINGS_FILE}.tmp"
        written.write_text(json.dumps(settings, indent=1))
        os.replace(written, out / SETTINGS_FILE)
    taken = [int(part.stem.removeprefix("part-")) for part in out.glob("part-*.parquet")]
    return max(taken, default=-1) + 1


def _batches(missing: np.ndarray, size: int) -> deque:
    """The missing runs as (first, last) batches of consecutive runs, at most `size` each."""
    batches = deque()
    starts = np.flatnonzero(np.diff(missing, prepend=-2) != 1)
    for first, last in zip(missing[starts], np.r_[missing[starts[1:] - 1], missing[-1:]]):
        for begin in range(int(first), int(last) + 1, size):
            batches.append((begin, min(begin + size - 1, int(last))))
    return batches


class SweepResults:
    """A sweep's dataset, not read until asked: a folder of Parquet files (`part-*.parquet`)
    and the settings (`_sweep.json`; also in each file's metadata, pandas' `attrs`).

    pandas.read_parquet(path), pyarrow.dataset.dataset(path), dask.dataframe.read_parquet(path)
    and duckdb's read_parquet('<path>/*.parquet') read it; rows of a run are together and
    in time order, runs in the order they finished (sort by run, as to_pandas does)."""

    def __init__(self, path, ran: int | None = None):
        self.path, self.ran = Path(path), ran  # ran: the runs the sweep() that returned it ran
        self.attrs = json.loads((self.path / SETTINGS_FILE).read_text())

    def __repr__(self):
        return f"SweepResults({str(self.path)!r}: {self.attrs['runs']} runs of {self.attrs['fmu']})"

    def dataset(self) -> ds.Dataset:
        return ds.dataset(self.path, format="parquet")

    def to_pandas(self, columns: Sequence[str] | None = None, filter=None) -> pd.DataFrame:
        """The rows (those `filter`, a pyarrow expression, keeps), ordered by run then time, with
        the settings in `attrs`; every column by default, or `columns` (run always)."""
        if columns is not None:
            columns = list(dict.fromkeys(["run", *columns]))
        table = self.dataset().to_table(columns=columns, filter=filter).sort_by("run")  # stable
        frame = table.to_pandas()
        frame.attrs = dict(self.attrs)
        return frame

    def done(self) -> int:
        """How many runs the dataset holds (all of them once the sweep has ended)."""
        return int(_done_runs(self.path, self.attrs["runs"]).sum())

    # rows() and failed() read the files one at a time: a scan of the whole dataset keeps
    # every file's footer (its row groups' metadata, ~2 MB a file) until it ends, so the
    # client's peak, after the sweep, grew with the runs (about 4 kB a run).
    def rows(self) -> int:
        return sum(pq.read_metadata(part).num_rows for part in self.dataset().files)

    def failed(self) -> pd.DataFrame:
        """One row per failed run, by run: its inputs and message; only the row groups whose
        statistics of `status` say they hold a failed run are read."""
        columns = ["run", *self.attrs["inputs"], "message"]
        tables, schema = [], None
        for part in self.dataset().files:
            file = pq.ParquetFile(part)
            schema = file.schema_arrow
            status = schema.get_field_index("status")
            groups = []
            for group in range(file.metadata.num_row_groups):
                statistics = file.metadata.row_group(group).column(status).statistics
                if statistics is None or not statistics.has_min_max or statistics.min == "failed":
                    groups.append(group)  # "failed" < "ok": a group with one has it as its least
            if groups:
                table = file.read_row_groups(groups, columns=[*columns, "status"])
                tables.append(table.filter(pc.equal(table["status"], "failed")).select(columns))
            file.close()
        if schema is None:  # no files
            frame = self.to_pandas(columns[1:], filter=ds.field("status") == "failed")
        else:
            table = pa.concat_tables(tables) if tables else schema.empty_table().select(columns)
            frame = table.sort_by("run").to_pandas()  # stable: each run's first row first
            frame.attrs = dict(self.attrs)
        return frame.drop_duplicates("run").set_index("run")


@contextlib.contextmanager
def _client(scheduler: str | None, n_workers: int, timeout: float):
    """A client of the scheduler at that address, or of a LocalCluster made and closed here."""
    if scheduler is None:
        if n_workers < 1:
            raise ValueError(f"n_workers = {n_workers}: must be at least 1")
        # The workers' statistical profiler (for the dashboard) takes the GIL every 10 ms
        # and would cost these runs, Python in fmpy and the slave, about 17 %. A task whose
        # worker dies is not tried on another: the sweep retries its runs one by one.
        settings = {"distributed.worker.profile.enabled": False, "distributed.scheduler.allowed-failures": 0}
        with dask.config.set(settings):
            cluster = LocalCluster(
                n_workers=n_workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address="127.0.0.1:0",
                silence_logs=logging.ERROR,
            )
        with cluster, Client(cluster) as client:
            client.register_plugin(_LeaveCtrlCToTheClient(), name="conical-pendulum-sweep-ctrl-c")
            yield client
        return
    try:
        client = Client(scheduler, timeout=timeout)
    except Exception as exc:
        raise ConnectionError(f"scheduler {scheduler!r}: cannot connect ({exc})") from None
    with client:
        try:
            client.wait_for_workers(1, timeout=timeout)
        except TimeoutError:
            raise ConnectionError(f"scheduler {scheduler!r}: no workers after {timeout:g} s") from None
        yield client


def _duration(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "?"
    seconds = round(seconds)
    return (
        f"{seconds // 3600}h{seconds // 60 % 60:02d}m"
        if seconds >= 3600
        else f"{seconds // 60}m{seconds % 60:02d}s"
    )


class _Progress:
    """The progress bar: runs done of all, failed, runs per second of this session, time left."""

    def __init__(self, total: int, done: int, shown: bool):
        self.total, self.done, self.failed, self.shown = total, done, 0, shown
        self.start, self.done_before = time.perf_counter(), done

    def add(self, runs: int, failed: int):
        self.done, self.failed = self.done + runs, self.failed + failed
        self.show()

    def stop(self):
        """Ends the bar's line when the sweep stops short."""
        if self.shown and self.done < self.total:
            print(file=sys.stderr)

    def show(self):
        if not self.shown:
            return
        seconds = time.perf_counter() - self.start
        rate = (self.done - self.done_before) / seconds if seconds > 0 else 0.0
        left = (self.total - self.done) / rate if rate > 0 else math.inf
        bar(
            self.done,
            self.total,
            "sweep",
            f" runs, {self.failed} failed, {rate:.0f} runs/s, {_duration(left)} left  ",
        )


class _Deaths:
    """The worker processes that died, read from their notes: which run each was in and the
    signal; a task lost with its worker may have been only waiting there, the notes tell."""

    def __init__(self, client, plugin: str):
        self.client, self.plugin = client, plugin
        self.notes, self.of_run, self.lost = {}, {}, {}

    def read(self, pid: int | None = None, wait: float = 5.0):
        """Reads the notes left; with `pid`, waits up to `wait` s for that process's (a host
        whose only worker died has none to read it until the nanny starts another)."""
        end = time.monotonic() + wait
        while True:
            for found in self.client.run(
                _deaths, self.plugin, on_error="ignore"
            ).values():  # some may be dying
                for dead, (run, cause) in found.items():
                    self.notes[dead] = run, cause
                    if run is not None:
                        self.of_run.setdefault(run, []).append(cause)
            if pid is None or pid in self.notes or time.monotonic() > end:
                return
            time.sleep(0.25)

    def failed(self, run: int, pid: int | None) -> str | None:
        """After the task of that run alone was lost with its worker: the run's message when
        it has killed a worker twice (or was lost LOST_TIMES times, no note saying why), else
        None: try it again."""
        self.read(pid)
        self.lost[run] = self.lost.get(run, 0) + 1
        causes = self.of_run.get(run, [])
        if len(causes) >= 2 or (self.lost[run] >= LOST_TIMES and not causes):
            return _death_message(causes)
        return None


def _stop_workers_noting(deaths: _Deaths, plugin: str):
    """The dead workers' notes read (and removed), then the plugin unregistered."""
    deaths.read()
    deaths.client.unregister_worker_plugin(plugin)
    deaths.client.run(_remove_notes_folder, plugin, on_error="ignore")  # emptied by teardowns and reads


def _remove_notes_folder(plugin: str):
    with contextlib.suppress(OSError):
        _notes_folder(plugin).rmdir()


def sweep(
    fmu,
    runs: Iterable[Mapping[str, float]],
    *,
    out,
    stop_time: float = 10.0,
    output_interval: float = 1.0 / 60.0,
    outputs: Sequence[str] | None = None,
    scheduler: str | None = None,
    n_workers: int = 2,
    batch: int | None = None,
    progress: bool = True,
    timeout: float = 10.0,
    loop: str = "runner",
    resume: bool = False,
    overwrite: bool = False,
) -> SweepResults:
    """Run the FMU once per run (a dict of parameters and start values) on a Dask cluster,
    into the Parquet dataset (a folder) `out`; returns a handle on it (SweepResults).

    On a LocalCluster of `n_workers` processes made for the sweep, or on the cluster whose
    scheduler is at `scheduler` ("tcp://host:8786"; its workers need this package, and
    connecting gives up after `timeout` s). The dataset is in long form, one row per run
    and time: `run`, the inputs (every variable any run sets; a state's start value as
    `<name>_start`), `status` ("ok" or "failed"), `message` (why a run failed; one row of
    NaN when it produced nothing), `time` and the `outputs` (default: all of the FMU's).
    The client writes the batches as they come, at most a few per worker in flight.
    A run that kills its worker process twice (alone, after its batch's worker died) is
    failed with that message. An existing sweep at `out` is refused unless `resume`
    (run only the runs it misses; refused when written with other settings) or
    `overwrite`. `batch` runs go to a task (default: about four tasks per worker, at most
    25 runs). `loop`: "runner", the compiled runner (analysis.runner), or "fmpy", fmpy's
    own loop: the same rows; a worker that cannot compile the runner uses fmpy's, and the
    log says why.
    """
    path = Path(fmu)
    try:
        data = path.read_bytes()
        md = read_model_description(str(path))
    except (OSError, zipfile.BadZipFile) as exc:
        raise ValueError(f"{path}: cannot read the FMU ({getattr(exc, 'strerror', None) or exc})") from None
    if md.fmiVersion != "2.0" or md.coSimulation is None:
        raise ValueError(f"{path}: not an FMI 2.0 co-simulation FMU")
    runs = _check_runs(md, runs)
    outputs = _check_outputs(md, outputs)
    if not (
        math.isfinite(stop_time) and stop_time > 0 and math.isfinite(output_interval) and output_interval > 0
    ):
        raise ValueError(f"stop time {stop_time} and output interval {output_interval} must be positive")
    if loop not in LOOPS:
        raise ValueError(f"loop = {loop!r}: choose {' or '.join(map(repr, LOOPS))}")
    if batch is not None and batch < 1:
        raise ValueError(f"batch = {batch}: must be at least 1")
    if resume and overwrite:
        raise ValueError("resume and overwrite exclude each other")
    inputs = _inputs(md, runs)
    settings = _settings(md, data, inputs, stop_time, output_interval, outputs)
    out = Path(out)
    done, replace = _check_out(out, settings, resume, overwrite)
    schema = _schema(md, inputs, outputs, settings)
    columns = {name: inputs[name].to_numpy() for name in inputs.columns}
    shown = _Progress(len(runs), int(done.sum()), progress)
    with _client(scheduler, n_workers, timeout) as client:
        parts = _Parts(out, schema, _begin(out, settings, replace))
        plugin = f"conical-pendulum-sweep-{uuid.uuid4().hex}"
        deaths = _Deaths(client, plugin)
        try:
            client.register_plugin(_FmuPlugin(data, loop, plugin), name=plugin)
            fallbacks = client.run(lambda dask_worker: dask_worker.plugins[plugin].fmu.fallback)
            for worker, reason in sorted(fallbacks.items()):
                if reason:
                    logger.warning(
                        "sweep: worker %s runs fmpy's loop, not the compiled runner: %s", worker, reason
                    )
            threads = sum(client.nthreads().values())
            size = batch or max(1, min(25, math.ceil(len(runs) / (4 * threads))))
            todo, running, finished = _batches(np.flatnonzero(~done), size), {}, as_completed()

            def submit():
                while todo and len(running) < 3 * threads:  # bounded: the client's memory stays flat
                    first, last = todo.popleft()
                    numbered = [(index, runs[index]) for index in range(first, last + 1)]
                    task = client.submit(
                        _run_batch, plugin, numbered, stop_time, output_interval, outputs, pure=False
                    )
                    running[task] = first, last
                    finished.add(task)

            shown.show()
            submit()
            for task in finished:
                first, last = running.pop(task)
                try:
                    summary, rows = task.result()
                except KilledWorker as exc:
                    summary, rows = None, None
                    if last > first:  # find the run that killed it: each alone
                        todo.extendleft((index, index) for index in range(last, first - 1, -1))
                    elif message := deaths.failed(first, getattr(exc.last_worker, "pid", None)):
                        summary = [(first, False, message, 0)]
                    else:
                        todo.appendleft((first, first))
                del task
                if summary is not None:
                    parts.write(_table(summary, rows, columns, schema))
                    shown.add(len(summary), sum(not ok for _, ok, _, _ in summary))
                submit()
        except BaseException as exc:
            shown.stop()
            parts.close()  # what was written stays, to resume
            with contextlib.suppress(Exception):  # the cluster may be gone
                _stop_workers_noting(deaths, plugin)
            if isinstance(exc, (OSError, CancelledError, asyncio.CancelledError)):
                raise ConnectionError(
                    f"lost the cluster ({type(exc).__name__}: {' '.join(str(exc).split())}); "
                    f"the runs done are kept in {out}: "
                    "run again with --resume (resume=True) to finish"
                ) from None
            raise
        parts.close()
        _stop_workers_noting(deaths, plugin)
    return SweepResults(out, ran=int((~done).sum()))
