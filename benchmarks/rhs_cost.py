"""Cost of one right-hand side evaluation (n = 3), and of the seed scenario natively.

    python benchmarks/rhs_cost.py

Compared in one run on this machine:
- the compiled core's RHS timed in a C loop (what its own solvers pay per stage);
- the same RHS called from Python (what scipy pays per call);
- the seed's pipeline: pydy's Cython RHS with its symbolic LU, and with numpy's solve,
  called from Python as odeint calls it.
Then the seed scenario (10 s, 601 samples) simulated natively (printed only).
Writes the per-call table (docs/performance.md) to benchmarks/results/rhs_cost.csv.
"""

import sys
import time
from pathlib import Path

import numpy as np

from conical_pendulum import Scene
from conical_pendulum.analysis.simulate import simulate
from conical_pendulum.builder.compiler import load_core
from results_csv import write_rows

sys.path.insert(
    0, str(Path(__file__).resolve().parents[1] / "tests")
)  # the seed's pipeline, a test reference
from references.seed_pipeline import seed_right_hand_side


def per_call(f, repeats=7, calls=20000):
    """Median over repeats of the seconds per call of f()."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(calls):
            f()
        times.append((time.perf_counter() - start) / calls)
    return float(np.median(times))


def main():
    scene = Scene.uniform(3)
    core = load_core(scene)
    x = np.array(scene.state_defaults()) + np.linspace(0.1, 0.3, 12)
    p = np.array(scene.parameter_defaults())
    in_c = float(np.median([core.seconds_per_call("rhs", x, p, 200000) for _ in range(7)]))
    from_python = per_call(lambda: core.rhs(x, p))
    print(f"compiled core RHS, n = 3, timed in C:           {in_c * 1e6:7.3f} us/call")
    print(f"compiled core RHS called from Python:           {from_python * 1e6:7.3f} us/call")
    rows = [
        {"rhs": "compiled core, timed in a C loop", "us_per_call": in_c * 1e6},
        {"rhs": "compiled core called from Python", "us_per_call": from_python * 1e6},
    ]
    for solver, label in (("sympy", "symbolic LU"), ("numpy", "numpy solve")):
        rhs, values = seed_right_hand_side(solver)
        pv = np.array(values)
        cost = per_call(lambda: rhs(x, 0.0, pv))
        print(
            f"seed pipeline (pydy cython, {solver:>5} LU) from Python: {cost * 1e6:7.3f} us/call"
            f"  ({cost / in_c:5.1f} x the C loop)"
        )
        rows.append(
            {"rhs": f"seed pipeline: pydy Cython RHS, {label}, from Python", "us_per_call": cost * 1e6}
        )
    for row in rows:
        row["us_per_call"] = round(row["us_per_call"], 3)
        row["times_the_c_loop"] = round(row["us_per_call"] / (in_c * 1e6), 1)
    write_rows("rhs_cost", rows)
    times = np.linspace(0.0, 10.0, 601)
    for method, tol in [("DOP853", 1e-10), ("DOP853", 1e-6), ("odeint", 1.49012e-8)]:
        runs = []
        for _ in range(5):
            start = time.perf_counter()
            simulate(scene, times, method=method, rtol=tol, atol=tol, core=core)
            runs.append(time.perf_counter() - start)
        print(f"seed scenario natively, scipy {method:<7} tol {tol:.0e}: {np.median(runs) * 1e3:8.1f} ms")


if __name__ == "__main__":
    main()
