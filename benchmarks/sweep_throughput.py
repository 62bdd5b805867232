"""Runs per second of a sweep on Dask (1 and 2 workers) against plain loops of fmpy.simulate_fmu.

    python benchmarks/sweep_throughput.py [--runs 200]

The same runs of the seed scenario (10 s, an output every 1/60 s, every output
recorded; l0 and alpha0 drawn at random), in one run of the script:

- fmpy.simulate_fmu on the FMU file in a loop: what a user would write first (fmpy
  extracts the FMU and loads its library at every call);
- simulate_fmu in a loop on the FMU extracted once and its model description read once
  (the library is still loaded and unloaded per run);
- LoadedFmu in this process: the library also loaded once, what each sweep worker does;
- sweep() on a LocalCluster of 1 and of 2 worker processes (one thread each, the
  workers' profiler off): the sweep on a cluster already running, and end to end (the
  default path: the cluster started and closed by the sweep).

Every method here runs fmpy's loop (loop="fmpy"); the compiled runner, the sweep's
default, is measured against it by runner_throughput.py. Every method must give
bit-identical results; the methods take turns, in rounds, and
medians are reported. Writes benchmarks/results/sweep_throughput.csv.
"""

import argparse
import os
import shutil
import tempfile
import time
from pathlib import Path

import dask
import fmpy
import numpy as np
from distributed import LocalCluster

from conical_pendulum import Scene
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.analysis.sweep import LoadedFmu, random_samples, sweep
from conical_pendulum.builder.fmu import build_fmu
from results_csv import write_rows

STOP, INTERVAL = 10.0, 1.0 / 60.0


def timed(call):
    start = time.perf_counter()
    value = call()
    return value, time.perf_counter() - start


def sweep_out() -> Path:
    """Where a round's sweep writes its dataset (replaced at each round)."""
    return Path(tempfile.gettempdir()) / f"sweep_throughput_{os.getpid()}.parquet"


def sweep_energies(results, n):
    """Each run's energy, read back from a sweep's dataset (then removed)."""
    energies = results.to_pandas(["energy"])
    shutil.rmtree(results.path)
    return [energies.loc[energies["run"] == k, "energy"].to_numpy() for k in range(n)]


def methods(path, runs):
    """(name, workers, call): each call does every run and returns (energies, seconds, cluster start)."""

    def plain():
        results, seconds = timed(lambda: [run_fmu(path, STOP, INTERVAL, run) for run in runs])
        return [r["energy"] for r in results], seconds, None

    def extracted_once():
        unzipdir = fmpy.extract(str(path))
        try:
            md = fmpy.read_model_description(unzipdir)
            results, seconds = timed(
                lambda: [run_fmu(unzipdir, STOP, INTERVAL, run, model_description=md) for run in runs]
            )
        finally:
            shutil.rmtree(unzipdir)
        return [r["energy"] for r in results], seconds, None

    def loaded_once():
        fmu = LoadedFmu(path.read_bytes(), loop="fmpy")
        outputs = [v.name for v in fmu.md.modelVariables if v.causality == "output"]
        try:
            results, seconds = timed(lambda: [fmu.run(run, STOP, INTERVAL, outputs)[0] for run in runs])
        finally:
            fmu.close()
        return [r["energy"] for r in results], seconds, None

    def on_running_cluster(workers):
        with dask.config.set({"distributed.worker.profile.enabled": False}):  # as sweep() makes its own
            cluster, start_seconds = timed(
                lambda: LocalCluster(n_workers=workers, threads_per_worker=1, dashboard_address="127.0.0.1:0")
            )
        with cluster:
            results, seconds = timed(
                lambda: sweep(
                    path,
                    runs,
                    stop_time=STOP,
                    output_interval=INTERVAL,
                    scheduler=cluster.scheduler_address,
                    progress=False,
                    loop="fmpy",
                    out=sweep_out(),
                )
            )
        return sweep_energies(results, len(runs)), seconds, start_seconds

    def end_to_end(workers):
        results, seconds = timed(
            lambda: sweep(
                path,
                runs,
                stop_time=STOP,
                output_interval=INTERVAL,
                n_workers=workers,
                progress=False,
                loop="fmpy",
                out=sweep_out(),
            )
        )
        return sweep_energies(results, len(runs)), seconds, None

    yield "fmpy.simulate_fmu loop", "-", plain
    yield "simulate_fmu loop, FMU extracted once", "-", extracted_once
    yield "in-process, library loaded once (LoadedFmu)", "-", loaded_once
    for workers in (1, 2):
        yield "sweep, cluster already running", workers, lambda w=workers: on_running_cluster(w)
        yield "sweep end to end (starts its cluster)", workers, lambda w=workers: end_to_end(w)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=3, help="rounds over every method; medians reported")
    args = parser.parse_args()
    runs = random_samples({"l0": (5.0, 15.0), "alpha0": (0.05, 1.0)}, args.runs, seed=1)
    with tempfile.TemporaryDirectory() as tmp:
        path = build_fmu(Scene.uniform(3), Path(tmp) / "ConicalPendulum.fmu").path
        run_fmu(path)  # warm: imports, the slave module, the page cache
        table = list(methods(path, runs))
        seconds = {k: [] for k in range(len(table))}
        starts = {k: [] for k in range(len(table))}
        reference, identical = None, True
        for _ in range(args.repeats):  # rounds, so that a busy moment hits every method alike
            for k, (_, _, call) in enumerate(table):
                energies, took, start = call()
                reference = reference or energies
                identical &= all(np.array_equal(a, b) for a, b in zip(energies, reference))
                seconds[k].append(took)
                if start is not None:
                    starts[k].append(start)
    print(
        f"{args.runs} runs of the seed scenario, 10 s at 60 Hz, every output recorded; "
        f"medians of {args.repeats}"
    )
    print(f"{'method':<45} {'workers':>7} {'runs/s':>8} {'seconds':>8}")
    rows = []
    for k, (name, workers, _) in enumerate(table):
        median = float(np.median(seconds[k]))
        start = float(np.median(starts[k])) if starts[k] else None
        rows.append(
            {
                "method": name,
                "workers": workers,
                "runs": args.runs,
                "seconds": round(median, 3),
                "runs_per_s": round(args.runs / median, 1),
                "cluster_start_s": "" if start is None else round(start, 2),
            }
        )
        print(
            f"{name:<45} {workers:>7} {args.runs / median:>8.1f} {median:>8.2f}"
            + ("" if start is None else f"   (cluster start {start:.1f} s)")
        )
    print(f"every method bit-identical to the plain loop: {'yes' if identical else 'NO'}")
    path = write_rows("sweep_throughput", rows)
    print(f"wrote {path}")
    return 0 if identical else 1


if __name__ == "__main__":
    raise SystemExit(main())
