"""Elastic ropes: what one costs per right-hand side, and which solver a stiff rope needs.

    python benchmarks/elastic_rope.py [--quick]

1. The cost: the crane (scenes/crane.toml) on its inextensible rope against the same crane on an
   elastic one (scenes/crane_elastic.toml), in both formulations, the compiled right-hand side
   timed in a C loop (core.seconds_per_call), at a swinging state with the elastic rope taut.
2. The solvers: the elastic crane with a 1 kg hook under a 20 t load, its rope's EA = 1e6, 1e7
   and 1e8 N (the last a steel wire: the hook's oscillation between rope and sling near
   2,900 rad/s, and its stretch, damped at 2 % of the critical damping of all that hangs from
   the rope, decays at some 5e5 /s on the hook alone), hanging at rest at the static stretch as
   the trolley starts at 0.5 m/s2, 10 s with an output every 0.01 s at rtol = atol = 1e-6: every solver of the native FMU, fmpy's CVode on
   its Model Exchange interface and scipy's stiff solvers, as benchmarks/stiff_ladder.py runs
   them (the same functions), with the error against the core's DOP853 at 1e-12.

3. The same steel wire started far from rest (the seed's 10 degree angles): each adaptive solver
   of the core at 1e-6 and 1e-10, finished or stopped.

Writes benchmarks/results/elastic_rope.csv, elastic_rope_cost.csv and
elastic_rope_far_from_rest.csv; docs/performance.md#elastic-ropes shows them.
--quick: EA = 1e7 only.
"""

import argparse
import tempfile
from pathlib import Path

from conical_pendulum.builder.compiler import load_core
from conical_pendulum.scene import load_scene
from results_csv import write_rows
from stiff_ladder import STOP, error, rung, split

ROOT = Path(__file__).resolve().parent.parent
G = 9.8
ANGLES = ("alpha0", "alpha1", "beta0", "beta1")


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
        # hanging at rest, the rope at its static stretch, as the trolley starts (0.5 m/s2)
        start = {"m0": 1.0, "m1": 20000.0, "a_pivot_x": 0.5, **dict.fromkeys(ANGLES, 0.0)}
        start["r0"] = static_reach(scene, 1.0, 20000.0)
        name = f"EA = {stiffness:g} N, 1 kg hook under 20 t"
        rows += rung(name, scene, start, "dop853", out / f"elastic_{stiffness:g}.fmu")
    return rows


def far_from_rest():
    """The steel wire (EA = 1e8 N) from the seed's 10 degree angles (the 1 kg hook flung between
    rope and sling), in the core (integrate_grid) with each adaptive solver at 1e-6 and 1e-10:
    the counts and the error at 10 s against Radau at 1e-12, or why it stopped."""
    data = load_scene(ROOT / "scenes" / "crane_elastic.toml").to_dict()
    data["links"][0]["rope_stiffness"] = 1e8
    scene = type(load_scene(ROOT / "scenes" / "crane_elastic.toml")).from_dict(data)
    core = load_core(scene)
    p, x0 = split(scene, {"m0": 1.0, "m1": 20000.0, "r0": static_reach(scene, 1.0, 20000.0)})
    times = [0.0, STOP]
    reference, _ = core.integrate_grid(x0, p, times, 1e-12, 1e-12, method="radau", max_steps=10**8)
    rows = []
    for method in ("rk45", "dop853", "radau", "auto"):
        for tol in (1e-6, 1e-10):
            counts, states = {}, None
            try:
                states, _ = core.integrate_grid(
                    x0, p, times, tol, tol, method=method, max_steps=10**8, counts=counts
                )
                why = "finished"
            except Exception as exc:  # the core's diagnosis
                why = f"failed: {exc}"
            rows.append(
                {"method": method, "rtol": tol, **counts, "error": error(states, reference), "outcome": why}
            )
            print(rows[-1], flush=True)
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="EA = 1e7 N only")
    args = parser.parse_args()
    costs = cost()
    far = far_from_rest()
    with tempfile.TemporaryDirectory() as folder:
        rows = solvers(args.quick, Path(folder))
    print(write_rows("elastic_rope", rows))
    print(write_rows("elastic_rope_cost", costs))
    print(write_rows("elastic_rope_far_from_rest", far))


if __name__ == "__main__":
    main()
