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

The package by job: runs.py (the run tables), worker.py (the FMU loaded on a worker, a
batch run there), crashes.py (which run killed a worker, and how), dataset.py (the Parquet
parts, the settings, resuming), results.py (SweepResults, the reader), cluster.py (the
cluster made or reached, its workers watched), guard.py (on each nanny: a run's time
limit, how its worker ended) and loop.py (sweep(): the client's loop and progress bar).
"""

from .cluster import NoWorkers
from .crashes import FATAL_SIGNALS, LOST_TIMES
from .dataset import PART_BYTES, PART_SECONDS, SETTINGS_FILE
from .loop import LOOPS, sweep
from .results import SweepResults
from .runs import Runs, grid, random_samples
from .worker import LoadedFmu

__all__ = [
    "FATAL_SIGNALS",
    "LOOPS",
    "LOST_TIMES",
    "PART_BYTES",
    "PART_SECONDS",
    "SETTINGS_FILE",
    "LoadedFmu",
    "NoWorkers",
    "Runs",
    "SweepResults",
    "grid",
    "random_samples",
    "sweep",
]
