"""The elastic rope's located events: what they cost and what they buy, against a host's.

    python benchmarks/rope_events.py

A load bouncing on an undamped elastic rope (100 kg under 10 m of EA = 1e6 N, 0.2 m of slack:
tests/test_elastic_ropes.py's BOUNCING), 20 bounces (10.5 s, 21 snaps), read by a master at
50 Hz:
- the native FMU's Co-Simulation (FMI 2.0) with each adaptive solver at rtol = atol = 1e-6
  and 1e-10, which locate the snaps and slackenings inside their steps;
- the same FMU's Model Exchange through fmpy's CVode (fmpy.simulate_fmu, its output interval
  50 Hz), which locates them from the FMU's event indicators;
- RK4 in Co-Simulation at 1 ms and 0.1 ms steps, which steps over them.
Each row: the wall time of the run, the right-hand sides (Co-Simulation's n_rhs), the snaps
counted (snaps0), the largest error of the stretch at the points against the closed form
(bounce_stretch), and of the largest tension read (T_rope_peak0; Model Exchange and RK4: the
largest T_rope0 they output) against the spring's peak k (s_e + A). Writes
benchmarks/results/rope_events.csv; docs/performance.md#elastic-ropes shows it.
"""

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
import test_elastic_ropes as checks
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.builder.fmu import build_fmu
from results_csv import write_rows

M, LENGTH, SLACK, EA = 100.0, 10.0, 0.2, 1e6
INTERVAL, BOUNCES = 0.02, 20
START = {**checks.AT_REST, "r0": LENGTH - SLACK}


def spring_peak():
    """The bounce's largest tension: k (s_e + A), A the half cycle's amplitude about s_e."""
    k, v0 = EA / LENGTH, np.sqrt(2 * checks.G * SLACK)
    omega, s_e = np.sqrt(k / M), M * checks.G / k
    return k * (s_e + np.hypot(s_e, v0 / omega))


def timed(path, stop, **options):
    begin = time.perf_counter()
    run = run_fmu(path, stop_time=stop, output_interval=INTERVAL, **options)
    return run, time.perf_counter() - begin


def main():
    path = build_fmu(checks.BOUNCING, Path(tempfile.mkdtemp()) / "Bouncing.fmu", backend="native").path
    stop = (BOUNCES + 0.5) * checks.bounce_period(M, LENGTH, SLACK, EA)
    peak, rows = spring_peak(), []

    def row(how, tolerance, run, seconds, tension, counted=True):
        rows.append(
            {
                "run": how,
                "tolerance": tolerance,
                "seconds": round(seconds, 4),
                "rhs": int(run["n_rhs"][-1]) if counted else "",  # Model Exchange: the host's
                "snaps": int(run["snaps0"][-1]),
                "stretch_error_m": f"{np.abs(run['stretch0'] - checks.bounce_stretch(run['time'])).max():.2g}",
                "peak_error_relative": f"{abs(run[tension].max() / peak - 1):.2g}",
            }
        )
        print(", ".join(f"{k} = {v}" for k, v in rows[-1].items()), flush=True)

    for tolerance in (1e-6, 1e-10):
        for name, solver in checks.CS_SOLVERS.items():
            start = {**START, "solver": solver, "rtol": tolerance, "atol": tolerance}
            run, seconds = timed(path, stop, start_values=start)
            row(f"Co-Simulation {name}", tolerance, run, seconds, "T_rope_peak0")
        run, seconds = timed(
            path, stop, start_values=START, fmi_type="ModelExchange", relative_tolerance=tolerance
        )
        row("Model Exchange, fmpy's CVode", tolerance, run, seconds, "T_rope0", counted=False)
    for step in (1e-3, 1e-4):
        start = {**START, "solver": 0, "max_step": step}
        run, seconds = timed(path, stop, start_values=start)
        row(f"Co-Simulation rk4, {step:g} s", "", run, seconds, "T_rope0")
    print(write_rows("rope_events", rows))


if __name__ == "__main__":
    main()
