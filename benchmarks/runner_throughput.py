"""Runs per second of the seed scenario: fmpy's loop against the compiled runner, both FMUs,
in one process and through the sweep on 2 workers, next to the physics floor.

    python benchmarks/runner_throughput.py [--runs 600] [--repeats 3]

The same runs (10 s, an output every 1/60 s, every output recorded; l0 and alpha0 drawn
at random), in one run of the script:

- the floor: the compiled core without any FMU. `stepper`: the core's Stepper taking the
  same 600 communication steps with the FMU's default settings, outputs updated at each,
  ending every integration on the point (across_points = 0: the pythonfmu FMU's physics
  until its slave runs the model contract, step for step); `dense grid`: one integration
  with dense output on the 601 times with the FMU's default solver and tolerances
  (core.integrate_grid, no outputs in the timing): the physics with no communication steps
  at all, which the native FMU's solver running across the points follows step for step;
- LoadedFmu in this process (what each sweep worker does), loop="fmpy" and "runner",
  for the native and the pythonfmu FMU; for the native runner also the time inside the
  C loop (the FMU's doStep and getReal), so the rest is what a run costs outside it;
- sweep() on a running LocalCluster of 2 worker processes (one thread each, profiler
  off, as sweep() makes its own), both loops, both FMUs; and the native FMU's runner
  sweep recording the energy only, to show what moving all 47 columns (226 kB a run)
  from the workers into the client's Parquet dataset costs (the sweep's time includes
  writing it; the energies are read back after).

Every method of one FMU must give bit-identical energies (the script prints which methods
agree with which); methods take turns in rounds, medians are reported. Writes
benchmarks/results/runner_throughput.csv.
"""

import argparse
import os
import shutil
import tempfile
import time
from pathlib import Path

import dask
import numpy as np
from distributed import LocalCluster

from conical_pendulum import Scene
from conical_pendulum.analysis.sweep import LoadedFmu, random_samples, sweep
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.builder.fmu import build_fmu
from conical_pendulum.runtime.rules import SETTINGS
from results_csv import write_rows

STOP, INTERVAL = 10.0, 1.0 / 60.0
STEPS = 600


def timed(call):
    start = time.perf_counter()
    value = call()
    return value, time.perf_counter() - start


class TimedLoop:
    """The runner's library with the time spent in its C loop added up."""

    def __init__(self, library):
        self.library, self.seconds = library, 0.0

    def fmi2_cs_run(self, run):
        start = time.perf_counter()
        outcome = self.library.fmi2_cs_run(run)
        self.seconds += time.perf_counter() - start
        return outcome


def floor_methods(scene, runs):
    core = load_core(scene)
    energy = core.NSTATE + scene.output_names().index("energy")
    settings = [SETTINGS[name].default for name in ("solver", "rtol", "atol", "max_step", "max_steps")]
    times = np.arange(STEPS + 1) * INTERVAL

    def stepper():
        energies = []
        start = time.perf_counter()
        for run in runs:
            params = np.array(scene.parameters({"l0": run["l0"]}))
            values = np.zeros(core.NSTATE + core.NOUTPUT)
            values[: core.NSTATE] = scene.initial_state({"alpha0": run["alpha0"]})
            stepper = core.Stepper(params, values)
            stepper.update_outputs()
            stepper.configure(*settings)
            recorded = np.empty(STEPS + 1)
            recorded[0] = values[energy]
            for k in range(STEPS):  # the FMU's communication points: (k + 1) / 60
                if stepper.advance(k * INTERVAL, (k + 1) * INTERVAL - k * INTERVAL):
                    raise RuntimeError(f"step {k} failed")
                recorded[k + 1] = values[energy]
            energies.append(recorded)
        return energies, time.perf_counter() - start, None

    method, rtol, atol = {1: "rk45", 2: "dop853"}[settings[0]], settings[1], settings[2]

    def dense_grid():
        start, states = time.perf_counter(), []
        for run in runs:
            params = np.array(scene.parameters({"l0": run["l0"]}))
            x0 = np.array(scene.initial_state({"alpha0": run["alpha0"]}))
            states.append((core.integrate_grid(x0, params, times, rtol, atol, method=method)[0], params))
        took = time.perf_counter() - start
        energies = [np.array([core.outputs(x, p)[energy - core.NSTATE] for x in xs]) for xs, p in states]
        return energies, took, None

    yield "floor: core Stepper, the FMU's 600 steps", "-", "-", stepper
    yield f"floor: core dense grid (one {method} run)", "-", "-", dense_grid


def fmu_methods(backend, path, runs, cluster):
    def in_process(loop):
        fmu = LoadedFmu(path.read_bytes(), loop)
        outputs = [v.name for v in fmu.md.modelVariables if v.causality == "output"]
        try:
            fmu.run(runs[0], STOP, INTERVAL, outputs)  # the runner's plan made, outside the timing
            timing = None
            if loop == "runner":
                timing = fmu._runners[tuple(outputs)]._library = TimedLoop(
                    fmu._runners[tuple(outputs)]._library
                )
            results, seconds = timed(lambda: [fmu.run(run, STOP, INTERVAL, outputs)[0] for run in runs])
        finally:
            fmu.close()
        return [r["energy"] for r in results], seconds, timing and timing.seconds

    def on_cluster(loop, outputs=None):
        results, seconds = timed(
            lambda: sweep(
                path,
                runs,
                stop_time=STOP,
                output_interval=INTERVAL,
                outputs=outputs,
                scheduler=cluster.scheduler_address,
                progress=False,
                loop=loop,
                out=Path(tempfile.gettempdir()) / f"runner_throughput_{os.getpid()}.parquet",
            )
        )
        energies = results.to_pandas(["energy"])
        shutil.rmtree(results.path)
        return (
            [energies.loc[energies["run"] == k, "energy"].to_numpy() for k in range(len(runs))],
            seconds,
            None,
        )

    for loop in ("fmpy", "runner"):
        yield f"in-process LoadedFmu, loop={loop}", backend, 1, lambda loop=loop: in_process(loop)
        yield f"sweep on a running cluster, loop={loop}", backend, 2, lambda loop=loop: on_cluster(loop)
    if backend == "native":  # what moving every output's rows to the client costs the sweep
        yield "sweep, loop=runner, energy recorded only", backend, 2, lambda: on_cluster("runner", ["energy"])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=600)
    parser.add_argument("--repeats", type=int, default=3, help="rounds over every method; medians reported")
    args = parser.parse_args()
    runs = random_samples({"l0": (5.0, 15.0), "alpha0": (0.05, 1.0)}, args.runs, seed=1)
    scene = Scene.uniform(3)
    with (
        tempfile.TemporaryDirectory() as tmp,
        dask.config.set({"distributed.worker.profile.enabled": False}),
        LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address="127.0.0.1:0") as cluster,
    ):
        paths = {
            backend: build_fmu(scene, Path(tmp) / f"{backend}.fmu", backend=backend).path
            for backend in ("native", "pythonfmu")
        }
        table = list(floor_methods(scene, runs))
        for backend, path in paths.items():
            table += list(fmu_methods(backend, path, runs, cluster))
        seconds = {k: [] for k in range(len(table))}
        inside = {k: [] for k in range(len(table))}
        found = {}  # the energies of each method's first round
        for _ in range(args.repeats):  # rounds, so that a busy moment hits every method alike
            for k, (*_, call) in enumerate(table):
                energies, took, in_loop = call()
                found.setdefault(k, energies)
                seconds[k].append(took)
                if in_loop is not None:
                    inside[k].append(in_loop / took)
    print(
        f"{args.runs} runs of the seed scenario, 10 s at 60 Hz, every output recorded; medians of {args.repeats}"
    )
    print(f"{'method':<45} {'FMU':>9} {'workers':>7} {'runs/s':>8} {'per worker':>10} {'ms/run':>7}")
    rows = []
    for k, (name, backend, workers, _) in enumerate(table):
        median = float(np.median(seconds[k]))
        rate = args.runs / median
        per_worker = rate / (workers if workers != "-" else 1)
        share = float(np.median(inside[k])) if inside[k] else None
        rows.append(
            {
                "method": name,
                "fmu": backend,
                "workers": workers,
                "runs": args.runs,
                "seconds": round(median, 3),
                "runs_per_s": round(rate, 1),
                "runs_per_s_per_worker": round(per_worker, 1),
                "ms_per_run": round(1e3 / per_worker, 3),
                "share_in_c_loop": "" if share is None else round(share, 3),
                "hours_for_100000_runs": round(100_000 / rate / 3600, 3),
            }
        )
        print(
            f"{name:<45} {backend:>9} {workers:>7} {rate:>8.1f} {per_worker:>10.1f} {1e3 / per_worker:>7.3f}"
            + ("" if share is None else f"   ({share:.1%} of the run in the C loop)")
        )
    classes = []  # methods whose energies are bit-identical in every run
    for k, energies in found.items():
        same = next((c for c in classes if all(map(np.array_equal, energies, found[c[0]]))), None)
        if same is None:
            classes.append([k])
        else:
            same.append(k)
    for c in classes:
        print("bit-identical energies:", "; ".join(f"{table[k][0]} ({table[k][1]})" for k in c))
    identical = all(
        len(
            {
                next(i for i, c in enumerate(classes) if k in c)
                for k in range(len(table))
                if table[k][1] == fmu
            }
        )
        == 1
        for fmu in ("native", "pythonfmu")
    )
    print(f"every method of one FMU bit-identical: {'yes' if identical else 'NO'}")
    print(f"wrote {write_rows('runner_throughput', rows)}")
    return 0 if identical else 1


if __name__ == "__main__":
    raise SystemExit(main())
