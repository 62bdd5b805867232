"""Elastic ropes: what one costs per right-hand side, and which solver a stiff rope needs.

    python benchmarks/elastic_rope.py [--quick]

1. The cost: the crane (scenes/crane.toml) on its inextensible rope against the same crane on an
   elastic one (scenes/crane_elastic.toml), in both formulations, the compiled right-hand side
   timed in a C loop (core.seconds_per_call), at a swinging state with the elastic rope taut.
2. The solvers: the elastic crane with a 1 kg hook under a 20 t load, its rope's EA = 1e6, 1e7
   and 1e8 N (the last a steel wire: the hook's oscillation between rope and sling near
   7,000 rad/s), started at the static stretch and swinging, 10 s with an output every 0.01 s at
   rtol = atol = 1e-6, the rope taut throughout: every solver of the native FMU, fmpy's CVode on
   its Model Exchange interface and scipy's stiff solvers, as benchmarks/stiff_ladder.py runs
   them (the same functions), with the error against the core's DOP853 at 1e-12.

Writes benchmarks/results/elastic_rope.csv; docs/performance.md#elastic-ropes shows it.
--quick: EA = 1e7 only.
"""

import argparse
import tempfile
from pathlib import Path

import numpy as np

from conical_pendulum.builder.compiler import load_core
from conical_pendulum.builder.fmu import build_fmu
from conical_pendulum.scene import load_scene
from results_csv import write_rows
from stiff_ladder import INTERVAL, SOLVERS, STOP, cvode_run, error, fmu_run, scipy_run, split

ROOT = Path(__file__).resolve().parent.parent
G = 9.8


def static_reach(scene, hook, load):
    """The rope's reach at rest: its length stretched by the weight below it."""
    link = scene.links[0]
    return link.length * (1 + (hook + load) * G / link.rope_stiffness)


def cost():
    """Seconds per right-hand side, inextensible against elastic, in both formulations."""
    rows = []
    for formulation in ("expanded", "recursive"):
        times = {}
        for name in ("crane", "crane_elastic"):
            scene = load_scene(ROOT / "scenes" / f"{name}.toml")
            scene = type(scene).from_dict({**scene.to_dict(), "formulation": formulation})
            core = load_core(scene)
            start = {"alpha0": 0.1, "beta1": 0.2, "omega0": 0.1}
            if scene.elastic_ropes():
                start["r0"] = static_reach(scene, 150.0, 2000.0)
            p, x = split(scene, start)
            core.seconds_per_call("rhs", x, p, 10_000)  # warm
            times[name] = min(core.seconds_per_call("rhs", x, p, 200_000) for _ in range(5))
        rows.append(
            {
                "formulation": formulation,
                "inextensible_us": round(1e6 * times["crane"], 4),
                "elastic_us": round(1e6 * times["crane_elastic"], 4),
                "ratio": round(times["crane_elastic"] / times["crane"], 3),
            }
        )
        print(rows[-1], flush=True)
    return rows


def solvers(quick, out):
    rows = []
    base = load_scene(ROOT / "scenes" / "crane_elastic.toml")
    for stiffness in (1e7,) if quick else (1e6, 1e7, 1e8):
        data = base.to_dict()
        data["links"][0]["rope_stiffness"] = stiffness
        scene = type(base).from_dict(data)
        start = {"m0": 1.0, "m1": 20000.0, "alpha0": 0.05, "alpha1": 0.1}
        start["r0"] = static_reach(scene, 1.0, 20000.0)
        path = build_fmu(scene, out / f"elastic_{stiffness:g}.fmu", backend="native").path
        core = load_core(scene)
        names = list(core.STATE_NAMES)
        p, x0 = split(scene, start)
        times = np.linspace(0.0, STOP, round(STOP / INTERVAL) + 1)
        reference, _ = core.integrate_grid(x0, p, times, 1e-12, 1e-12, method="dop853", max_steps=10**8)
        rung = f"EA = {stiffness:g} N, 1 kg hook under 20 t"

        def row(solver, states, counts, seconds, why):
            rows.append(
                {
                    "rung": rung,
                    "solver": solver,
                    "rhs": counts.get("rhs", ""),
                    "jacobians": counts.get("jacobians", ""),
                    "factorizations": counts.get("lu", ""),
                    "seconds": round(seconds, 4),
                    "error": error(states, reference),
                    "outcome": why,
                }
            )
            print(f"{rung:34} {solver:18} {rows[-1]}", flush=True)

        for solver, value in SOLVERS.items():
            row(f"FMU {solver}", *fmu_run(path, start, names, value))
        states, seconds, why = cvode_run(path, start, names)
        row("fmpy CVode (ME)", states, {}, seconds, why)
        for method in ("Radau", "BDF", "LSODA"):
            row(f"scipy {method}", *scipy_run(core, x0, p, times, method))
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="EA = 1e7 N only")
    args = parser.parse_args()
    costs = cost()
    with tempfile.TemporaryDirectory() as folder:
        rows = solvers(args.quick, Path(folder))
    print(write_rows("elastic_rope", rows))
    print(write_rows("elastic_rope_cost", costs))


if __name__ == "__main__":
    main()
