"""The cluster a sweep runs on: a LocalCluster made for it and closed after, or a running
one reached through its scheduler's address."""

from __future__ import annotations

import contextlib
import logging
import signal

import dask
from distributed import Client, LocalCluster, WorkerPlugin

LOW_LEVEL_LOG = 10  # messages of each Dask stream kept for debugging (Dask's default: 1000)


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
            if n_workers < 1:
                raise ValueError(f"n_workers = {n_workers}: must be at least 1")
            # The workers' statistical profiler (for the dashboard) takes the GIL every 10 ms
            # and would cost these runs, Python in fmpy and the slave, about 17 %. A task whose
            # worker dies is not tried on another: the sweep retries its runs one by one.
            settings = {
                "distributed.worker.profile.enabled": False,
                "distributed.scheduler.allowed-failures": 0,
            }
            with dask.config.set(settings):
                cluster = LocalCluster(
                    n_workers=n_workers,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address="127.0.0.1:0",
                    silence_logs=logging.ERROR,
                )
            with cluster, Client(cluster) as client:
                client.register_plugin(LeaveCtrlCToTheClient(), name="conical-pendulum-sweep-ctrl-c")
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
