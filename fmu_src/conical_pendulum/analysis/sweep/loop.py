"""sweep(): the arguments checked, then the client's loop: batches submitted, a bounded
number in flight, results written as they come, a batch lost with its worker retried run
by run, and the progress bar."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import time
import uuid
import zipfile
from collections.abc import Iterable, Mapping, Sequence
from concurrent.futures import CancelledError
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
from distributed import wait
from distributed.scheduler import KilledWorker
from fmpy import read_model_description

from ...progress import Bar
from ..runner import LOOPS
from . import dataset
from .cluster import NoWorkers, Workers, connect
from .crashes import Deaths
from .guard import Guard
from .results import SweepResults
from .runs import check_outputs, dataset_inputs, run_table
from .worker import FmuPlugin, run_batch

logger = logging.getLogger(__name__)
WAIT_SECONDS = 1.0  # the longest the client waits for a batch before it looks at the workers


def _duration(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "?"
    seconds = round(seconds)
    return (
        f"{seconds // 3600}h{seconds // 60 % 60:02d}m"
        if seconds >= 3600
        else f"{seconds // 60}m{seconds % 60:02d}s"
    )


class Progress:
    """The progress bar: runs done of all, failed, runs per second of this session, time left."""

    def __init__(self, total: int, done: int, shown: bool):
        self.total, self.done, self.failed, self.shown = total, done, 0, shown
        self.start, self.done_before = time.perf_counter(), done
        self.bar = Bar(total, "sweep")

    def add(self, runs: int, failed: int):
        self.done, self.failed = self.done + runs, self.failed + failed
        self.show()

    def stop(self):
        """Ends the bar's line when the sweep stops short."""
        self.bar.stop()

    def show(self):
        if not self.shown:
            return
        seconds = time.perf_counter() - self.start
        rate = (self.done - self.done_before) / seconds if seconds > 0 else 0.0
        left = (self.total - self.done) / rate if rate > 0 else math.inf
        self.bar.update(
            self.done, f" runs, {self.failed} failed, {rate:.0f} runs/s, {_duration(left)} left  "
        )


@dataclass
class Plan:
    """A sweep checked before anything runs: the FMU, what each run sets, and the output."""

    data: bytes
    out: Path
    columns: dict  # the inputs by the dataset's names, one array each
    values: dict  # the same arrays by the names the FMU knows
    done: np.ndarray  # the runs the output holds already
    replace: bool
    settings: dict
    schema: pa.Schema
    stop_time: float
    output_interval: float
    outputs: list[str]


def _plan(fmu, runs, out, stop_time, output_interval, outputs, loop, batch, resume, overwrite) -> Plan:
    """The sweep's arguments checked, every mistake refused with ValueError naming it."""
    path = Path(fmu)
    try:
        data = path.read_bytes()
        md = read_model_description(str(path))
    except (OSError, zipfile.BadZipFile) as exc:
        raise ValueError(f"{path}: cannot read the FMU ({getattr(exc, 'strerror', None) or exc})") from None
    if md.fmiVersion != "2.0" or md.coSimulation is None:
        raise ValueError(f"{path}: not an FMI 2.0 co-simulation FMU")
    table = run_table(md, runs)
    outputs = check_outputs(md, outputs)
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
    inputs = dataset_inputs(md, table)
    settings = dataset.settings_of(md, data, inputs, stop_time, output_interval, outputs)
    out = Path(out)
    done, replace = dataset.check_out(out, settings, resume, overwrite)
    columns = {name: inputs[name].to_numpy() for name in inputs.columns}
    values = dict(zip(table.columns, columns.values()))  # by the names the FMU knows
    schema = dataset.schema(md, inputs, outputs, settings)
    return Plan(
        data, out, columns, values, done, replace, settings, schema, stop_time, output_interval, outputs
    )


def _warn_of_fallbacks(client, plugin: str):
    fallbacks = client.run(lambda dask_worker: dask_worker.plugins[plugin].fmu.fallback)
    for worker, reason in sorted(fallbacks.items()):
        if reason:
            logger.warning("sweep: worker %s runs fmpy's loop, not the compiled runner: %s", worker, reason)


def _run(client, plan: Plan, parts: dataset.Parts, deaths: Deaths, shown: Progress, options: dict):
    """The loop: batches in flight, at most three per worker thread, written as they finish;
    never a wait without bound: when no worker has been alive for `no_workers_timeout` s,
    NoWorkers."""
    plugin = deaths.plugin
    threads = sum(client.nthreads().values())
    size = options["batch"] or max(1, min(25, math.ceil(len(plan.done) / (4 * threads))))
    todo, running = dataset.batches(np.flatnonzero(~plan.done), size), {}
    workers = Workers(client, options["no_workers_timeout"])

    def submit():
        while todo and len(running) < 3 * threads:  # bounded: the client's memory stays flat
            first, last = todo.popleft()
            numbered = [
                (index, {name: column[index].item() for name, column in plan.values.items()})
                for index in range(first, last + 1)
            ]
            task = client.submit(
                run_batch, plugin, numbered, plan.stop_time, plan.output_interval, plan.outputs, pure=False
            )
            running[task] = first, last

    shown.show()
    submit()
    while running:
        with contextlib.suppress(TimeoutError):
            wait(list(running), timeout=WAIT_SECONDS, return_when="FIRST_COMPLETED")
        for task in [task for task in running if task.done()]:
            first, last = running.pop(task)
            try:
                summary, rows = task.result()
            except KilledWorker as exc:
                rows = None
                summary, again = deaths.lost_with(first, last, getattr(exc.last_worker, "pid", None))
                todo.extendleft((index, index) for index in reversed(again))
            del task
            if summary:
                parts.write(dataset.batch_table(summary, rows, plan.columns, plan.schema))
                shown.add(len(summary), sum(not ok for _, ok, _, _ in summary))
        workers.check()
        submit()


def _register(client, plan: Plan, plugin: str, loop: str, run_timeout: float | None):
    """The FMU loaded on every worker, and a guard on every nanny; a time limit without
    nannies, which end a run's process, refused."""
    guarded = client.register_plugin(Guard(plugin, run_timeout), name=plugin)  # {nanny: answer}
    if run_timeout is not None and not guarded:
        raise ValueError(
            f"run timeout {run_timeout:g} s: the cluster's workers have no nanny to end a run "
            "that exceeds it (start them with `dask worker --nanny`)"
        )
    client.register_plugin(FmuPlugin(plan.data, loop, plugin), name=plugin)
    _warn_of_fallbacks(client, plugin)


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
    run_timeout: float | None = None,
    no_workers_timeout: float = 60.0,
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
    log says why. `run_timeout` (s, None: no limit): a run that takes longer has its worker
    process ended by its nanny and is failed, "exceeded N s" (refused on workers without
    nannies). The client never waits without bound: when no worker has been alive for
    `no_workers_timeout` s, the sweep stops (NoWorkers, a ConnectionError), resumable.
    """
    plan = _plan(fmu, runs, out, stop_time, output_interval, outputs, loop, batch, resume, overwrite)
    for name, seconds in [("run timeout", run_timeout), ("no-workers timeout", no_workers_timeout)]:
        if seconds is not None and not (math.isfinite(seconds) and seconds > 0):
            raise ValueError(f"{name} {seconds} s: must be a positive number of seconds")
    shown = Progress(len(plan.done), int(plan.done.sum()), progress)
    with connect(scheduler, n_workers, timeout) as client:
        parts = dataset.Parts(plan.out, plan.schema, dataset.begin(plan.out, plan.settings, plan.replace))
        plugin = f"conical-pendulum-sweep-{uuid.uuid4().hex}"
        deaths = Deaths(client, plugin, local=scheduler is None)
        try:
            _register(client, plan, plugin, loop, run_timeout)
            _run(
                client, plan, parts, deaths, shown, {"batch": batch, "no_workers_timeout": no_workers_timeout}
            )
        except BaseException as exc:
            shown.stop()
            parts.close()  # what was written stays, to resume
            with contextlib.suppress(Exception):  # the cluster may be gone
                deaths.stop()
            if isinstance(exc, (OSError, CancelledError, asyncio.CancelledError)):
                why = (
                    str(exc)
                    if isinstance(exc, NoWorkers)
                    else f"lost the cluster ({type(exc).__name__}: {' '.join(str(exc).split())})"
                )
                raise ConnectionError(
                    f"{why}; the runs done are kept in {plan.out}: run again with --resume (resume=True) to finish"
                ) from None
            raise
        parts.close()
        deaths.stop()
    return SweepResults(plan.out, ran=int((~plan.done).sum()))
