"""Parameter and initial-condition sweeps of an FMU, run as Dask tasks, kept in one Parquet file.

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
to the last good point) or an output is not finite.
"""

from __future__ import annotations

import contextlib
import io
import itertools
import logging
import math
import numbers
import shutil
import tempfile
import threading
import time
import uuid
import zipfile
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

import dask
import numpy as np
import pandas as pd
from distributed import Client, LocalCluster, WorkerPlugin, as_completed, get_worker
from fmpy import read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.simulation import settable_in_initialization_mode, settable_in_instantiated

from ..progress import bar
from . import runner
from .fmpy_runs import logging_callbacks, run_fmu

logger = logging.getLogger(__name__)
LOOPS = ("runner", "fmpy")  # sweep()'s loop: analysis.runner's compiled loop, or fmpy's own


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


class _FmuPlugin(WorkerPlugin):
    """Loads the FMU it carries once on each worker, and removes it when unregistered."""

    def __init__(self, data: bytes, loop: str):
        self.data, self.loop = data, loop

    def setup(self, worker):
        self.fmu = LoadedFmu(self.data, self.loop)
        self.data = None  # extracted: the worker keeps no second copy

    def teardown(self, worker):
        self.fmu.close()


def _run_batch(
    plugin: str, batch: list[tuple[int, dict]], stop_time: float, output_interval: float, outputs: list[str]
):
    """On a worker: the batch's runs as ([(run, ok, message, rows kept)], their rows in one
    record array or None). One buffer crosses to the client: a frame of the rows, with a
    message per row, cost more to build and send than the runs themselves."""
    fmu = get_worker().plugins[plugin].fmu
    done = [
        (index, *fmu.run(start_values, stop_time, output_interval, outputs)) for index, start_values in batch
    ]
    kept = [rows for _, rows, _, _ in done if rows is not None]
    summary = [(index, ok, message, 0 if rows is None else len(rows)) for index, rows, ok, message in done]
    return summary, np.concatenate(kept) if kept else None


def _table(batches: list, inputs: pd.DataFrame, outputs: list[str]) -> pd.DataFrame:
    """The sweep's long table from its batches: each column copied once; a run that kept no
    rows gets one row of NaN."""
    batches = sorted(batches, key=lambda batch: batch[0][0][0])
    index, ok, message, kept = zip(*(run for summary, _ in batches for run in summary))
    kept = np.array(kept)
    lengths = np.maximum(kept, 1)

    def repeated(values):
        return np.repeat(np.array(values, dtype=object), lengths)

    run = np.repeat(np.array(index), lengths)
    columns = {
        "run": run,
        **{name: inputs[name].to_numpy()[run] for name in inputs.columns},
        "status": repeated(["ok" if good else "failed" for good in ok]),
        "message": repeated(message),
    }
    blocks = [rows for _, rows in batches if rows is not None]
    rows = np.concatenate(blocks) if blocks else None
    has_rows = np.repeat(kept > 0, lengths)
    for name in ["time", *outputs]:
        if has_rows.all():
            columns[name] = np.ascontiguousarray(rows[name])
        else:
            columns[name] = np.full(len(run), math.nan)
            if rows is not None:
                columns[name][has_rows] = rows[name]
    return pd.DataFrame(columns, copy=False)


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
            if variables[name].type == "Integer":
                if not float(value).is_integer():
                    raise ValueError(f"run {index}: {name} = {value!r}: {name} is an Integer variable")
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
        start = (int if variable.type == "Integer" else float)(variable.start)
        column = f"{name}_start" if variable.causality == "output" else name
        columns[column] = [run.get(name, start) for run in runs]
    return pd.DataFrame(columns, index=pd.RangeIndex(len(runs), name="run"))


@contextlib.contextmanager
def _client(scheduler: str | None, n_workers: int, timeout: float):
    """A client of the scheduler at that address, or of a LocalCluster made and closed here."""
    if scheduler is None:
        if n_workers < 1:
            raise ValueError(f"n_workers = {n_workers}: must be at least 1")
        # The workers' statistical profiler (for the dashboard) takes the GIL every 10 ms
        # and would cost these runs, Python in fmpy and the slave, about 17 %.
        with dask.config.set({"distributed.worker.profile.enabled": False}):
            cluster = LocalCluster(
                n_workers=n_workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address="127.0.0.1:0",
                silence_logs=logging.ERROR,
            )
        with cluster, Client(cluster) as client:
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


def _show_progress(done: int, total: int, failed: int, start: float) -> None:
    bar(done, total, "sweep", f" runs, {failed} failed, {time.perf_counter() - start:.1f} s")


def sweep(
    fmu,
    runs: Iterable[Mapping[str, float]],
    *,
    stop_time: float = 10.0,
    output_interval: float = 1.0 / 60.0,
    outputs: Sequence[str] | None = None,
    scheduler: str | None = None,
    n_workers: int = 2,
    batch: int | None = None,
    out=None,
    progress: bool = True,
    timeout: float = 10.0,
    loop: str = "runner",
) -> pd.DataFrame:
    """Run the FMU once per run (a dict of parameters and start values) on a Dask cluster.

    On a LocalCluster of `n_workers` processes made for the sweep, or on the cluster whose
    scheduler is at `scheduler` ("tcp://host:8786"; its workers need this package, and
    connecting gives up after `timeout` s). Returns the results in long form, one row per
    run and time, ordered by run: `run`, the inputs (every variable any run sets; a
    state's start value as `<name>_start`), `status` ("ok" or "failed"),
    `message` (why a run failed; one row of NaN when it produced nothing), `time` and the
    `outputs` (default: all of the FMU's). With `out`, also written there as Parquet;
    the FMU's name and the sweep's settings are in `attrs`, which the file keeps.
    `batch` runs go to a task (default: about four tasks per worker, at most 25 runs).
    `loop`: "runner", the compiled runner (analysis.runner), or "fmpy", fmpy's own loop: the
    same rows; a worker that cannot compile the runner uses fmpy's, and the log says why.
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
    if out is not None and not Path(out).parent.is_dir():
        raise ValueError(f"out: {Path(out).parent} is not a directory")
    if out is not None and Path(out).is_dir():
        raise ValueError(f"out: {out} is a directory; give a file name")
    inputs = _inputs(md, runs)
    start, batches, done, failed = time.perf_counter(), [], 0, 0
    with _client(scheduler, n_workers, timeout) as client:
        plugin = f"conical-pendulum-sweep-{uuid.uuid4().hex}"
        client.register_plugin(_FmuPlugin(data, loop), name=plugin)
        try:
            fallbacks = client.run(lambda dask_worker: dask_worker.plugins[plugin].fmu.fallback)
            for worker, reason in sorted(fallbacks.items()):
                if reason:
                    logger.warning(
                        "sweep: worker %s runs fmpy's loop, not the compiled runner: %s", worker, reason
                    )
            size = batch or max(1, min(25, math.ceil(len(runs) / (4 * sum(client.nthreads().values())))))
            numbered = list(enumerate(runs))
            futures = [
                client.submit(
                    _run_batch,
                    plugin,
                    numbered[i : i + size],
                    stop_time,
                    output_interval,
                    outputs,
                    pure=False,
                )
                for i in range(0, len(runs), size)
            ]
            if progress:
                _show_progress(0, len(runs), 0, start)
            for future in as_completed(futures):
                summary, rows = future.result()
                batches.append((summary, rows))
                done += len(summary)
                failed += sum(not ok for _, ok, _, _ in summary)
                if progress:
                    _show_progress(done, len(runs), failed, start)
        finally:
            client.unregister_worker_plugin(plugin)
    results = _table(batches, inputs, outputs)
    results.attrs = {
        "fmu": md.modelName,
        "fmu_guid": md.guid,
        "stop_time": stop_time,
        "output_interval": output_interval,
        "outputs": outputs,
        "inputs": list(inputs.columns),
    }
    if out is not None:
        results.to_parquet(out, index=False)
    return results
