"""The cluster a sweep runs on: a LocalCluster made for it and closed after, or a running
one reached through its scheduler's address."""

from __future__ import annotations

import contextlib
import logging
import math
import multiprocessing
import shutil
import signal
import tempfile
import time

import dask
from distributed import Client, LocalCluster, SpecCluster, WorkerPlugin
from distributed.core import Status

LOW_LEVEL_LOG = 10  # messages of each Dask stream kept for debugging (Dask's default: 1000)
SETTLE_SECONDS = 60.0  # the longest a finished sweep waits for its workers' restarts to end


class LeaveCtrlCToTheClient(WorkerPlugin):
    """A terminal's Ctrl-C reaches the local cluster's worker processes too: they ignore it,
    so that the client stops the sweep (keeping what is written) and closes them, rather
    than each dying with a traceback."""

    def setup(self, worker):
        signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def connect(scheduler: str | None, n_workers: int, timeout: float):
    """A client of the scheduler at that address, or of a LocalCluster made and closed here."""
    # Dask keeps, for its developers, the last `low-level-log-length` (1000) messages of
    # every stream in memory: in the client and its local scheduler, the batches' runs and
    # results, which grew the client by some 0.6 kB a run up to 25,000 runs. Ten will do.
    with dask.config.set({"distributed.admin.low-level-log-length": LOW_LEVEL_LOG}):
        if scheduler is None:
            with _local_cluster(n_workers) as cluster, Client(cluster) as client:
                client.register_plugin(LeaveCtrlCToTheClient(), name="conical-pendulum-sweep-ctrl-c")
                yield client
                _settle(client, cluster, SETTLE_SECONDS)
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


@contextlib.contextmanager
def _local_cluster(n_workers: int):
    """n_workers worker processes, each with a nanny that restarts it when a run kills it,
    for as long as the sweep lasts; Dask's scratch space (the scheduler's and
    the workers') in a folder removed after."""
    if n_workers < 1:
        raise ValueError(f"n_workers = {n_workers}: must be at least 1")
    # The workers' statistical profiler (for the dashboard) takes the GIL every 10 ms and
    # would cost these runs, Python in fmpy and the slave, about 17 %. A task whose worker
    # dies is not tried on another: the sweep retries its runs one by one. SpecCluster arms
    # a timer of `lost-worker-timeout` (15 s) at every worker's removal, and when it fires
    # while that worker's nanny is restarting it after another crash, closes the nanny for
    # good and starts none: with a run crashing every few seconds, the cluster lost all its
    # workers and the sweep waited forever. The nannies restart their workers: a day. A
    # worker a run killed restarts forked from a server that imported Dask and numpy once
    # (where there is one: not on Windows), not spawned to import them again: 15 all-crashing
    # runs on one worker 47 s spawned, 15 s forked (docs/sweeps.md).
    settings = {
        **(
            {"distributed.worker.multiprocessing-method": "forkserver"}
            if "forkserver" in multiprocessing.get_all_start_methods()
            else {}
        ),
        "distributed.worker.profile.enabled": False,
        "distributed.scheduler.allowed-failures": 0,
        "distributed.deploy.lost-worker-timeout": "1 day",
        "temporary-directory": tempfile.mkdtemp(prefix="conical_pendulum_sweep_dask_"),
    }
    try:
        with (
            dask.config.set(settings),  # read at every removal: for the cluster's lifetime
            LocalCluster(
                n_workers=n_workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address="127.0.0.1:0",
                silence_logs=logging.CRITICAL,  # the sweep reports the runs that killed workers
            ) as cluster,
        ):
            yield cluster
    finally:
        shutil.rmtree(settings["temporary-directory"], ignore_errors=True)


def _settle(client, cluster: SpecCluster, seconds: float):
    """Waits, at most `seconds`, until every nanny's worker process is up and known to the
    scheduler. After the last run killed its worker, the nanny starts another; a cluster
    closed while that one starts closed it half-started, and its process printed Dask's
    "ConnectionPool is closed" traceback (or kept the command from ending)."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        processes = [getattr(nanny, "process", None) for nanny in list(cluster.workers.values())]
        if len(client.nthreads()) == len(cluster.worker_spec) == len(processes) and all(
            process is not None and process.status == Status.running for process in processes
        ):
            return
        time.sleep(0.05)


class NoWorkers(ConnectionError):
    """No worker alive for longer than the sweep waits."""


class Workers:
    """The cluster's workers as the client watches them while it waits: a local cluster's
    nannies that closed are replaced, and a cluster with no worker alive for `patience` s
    stops the sweep (NoWorkers)."""

    def __init__(self, client, patience: float):
        self.client, self.patience = client, patience
        self.alive, self.checked = time.monotonic(), -math.inf

    def check(self, every: float = 1.0):
        now = time.monotonic()
        if now - self.checked < every:
            return
        self.checked = now
        if self.client.nthreads():
            self.alive = now
        cluster = self.client.cluster
        if isinstance(cluster, SpecCluster):
            cluster.loop.add_callback(_replace_closed, cluster)
        if now - self.alive > self.patience:
            raise NoWorkers(f"no worker alive for {self.patience:g} s")


def _replace_closed(cluster: SpecCluster):
    """On the cluster's event loop: nannies that closed (or that the cluster dropped) started
    anew from the cluster's specification; none while the cluster closes, whose nannies close
    too (replacing them then started workers against a closing scheduler, which printed
    tracebacks and could keep the command from ending)."""
    if cluster.status in (Status.closing, Status.closed, Status.failed):
        return
    for name, nanny in list(cluster.workers.items()):
        if nanny.status in (Status.closed, Status.failed):
            del cluster.workers[name]
    if len(cluster.workers) < len(cluster.worker_spec):
        cluster.scale(len(cluster.worker_spec))
