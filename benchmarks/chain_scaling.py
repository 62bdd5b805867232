"""What a chain costs as it grows: cold build and right-hand side, against MuJoCo's mj_forward.

    pip install -e ".[bench]" && python benchmarks/chain_scaling.py

For n in 1, 2, 3, 5, 10, 20, 50, 100 uniform seed links, in one run: the cold build of
the compiled core (a fresh cache) in the formulation "auto" picks, the right-hand side
timed in a C loop in that formulation and, where they are offered and build in
reasonable time, in both (the crossover); and MuJoCo's mj_forward on the same chain
(two hinges per joint, parent x then child z, a cylinder and a sphere per link), timed
from Python less the cost of an empty call into MuJoCo's bindings. Medians of repeats.
Writes benchmarks/results/chain_scaling.csv and chain_scaling.png.
"""

import tempfile
import time
from pathlib import Path

import numpy as np

from conical_pendulum import Scene
from conical_pendulum.builder.compiler import build_core
from results_csv import RESULTS, write_rows

LINKS = (1, 2, 3, 5, 10, 20, 50, 100)
EXPANDED_UP_TO = 10  # the expanded equations build in minutes beyond (374 s at 20 links)


def rhs_seconds(scene: Scene, core) -> float:
    x, p = scene.initial_state(), scene.parameters()
    calls = max(2_000, int(2e5 / scene.n))
    return float(np.median([core.seconds_per_call("rhs", x, p, calls) for _ in range(5)]))


def mujoco_chain(n: int) -> str:
    """MJCF of the seed chain: each link a body with hinges about x then z at its top."""
    link = Scene.uniform(1).links[0]
    xml = ""  # built from the lowest link up
    for i in reversed(range(n)):
        top = "0 0 0" if i == 0 else f"0 {-link.length} 0"
        xml = (
            f'<body pos="{top}"><joint type="hinge" axis="1 0 0"/><joint type="hinge" axis="0 0 1"/>'
            f'<geom type="cylinder" fromto="0 0 0 0 {-link.length} 0" size="{link.radius}" '
            f'mass="{link.mass}"/><geom type="sphere" pos="0 {-link.length} 0" '
            f'size="{link.bob_radius}" mass="{link.bob_mass}"/>{xml}</body>'
        )
    return f'<mujoco><option gravity="0 -9.8 0" integrator="RK4"/><worldbody>{xml}</worldbody></mujoco>'


def mj_forward_seconds(n: int) -> float:
    import mujoco

    model = mujoco.MjModel.from_xml_string(mujoco_chain(n))
    data = mujoco.MjData(model)
    data.qpos[:] = np.radians(10.0)
    tiny = np.zeros(1)
    calls = max(2_000, int(2e5 / n))

    def per_call(f):
        start = time.perf_counter()
        for _ in range(calls):
            f()
        return (time.perf_counter() - start) / calls

    runs = []
    for _ in range(5):
        forward = per_call(lambda: mujoco.mj_forward(model, data))
        empty = per_call(lambda: mujoco.mju_zero(tiny))
        runs.append(forward - empty)
    return float(np.median(runs))


def main():
    rows = []
    for n in LINKS:
        scene = Scene.uniform(n)
        row = {"links": n, "auto": scene.resolved_formulation()}
        for formulation in ("expanded", "recursive"):
            if formulation == "expanded" and n > EXPANDED_UP_TO:
                row[f"{formulation}_build_s"] = row[f"{formulation}_rhs_us"] = ""
                continue
            variant = Scene.uniform(n, formulation=formulation)
            with tempfile.TemporaryDirectory() as cache:
                start = time.perf_counter()
                build = build_core(variant, Path(cache))
                row[f"{formulation}_build_s"] = round(time.perf_counter() - start, 1)
                row[f"{formulation}_rhs_us"] = round(rhs_seconds(variant, build.load()) * 1e6, 3)
        row["mj_forward_us"] = round(mj_forward_seconds(n) * 1e6, 3)
        auto = row[f"{row['auto']}_rhs_us"]
        row["auto_over_mujoco"] = round(auto / row["mj_forward_us"], 2)
        rows.append(row)
        print(row, flush=True)
    write_rows("chain_scaling", rows)
    plot(rows)


def plot(rows):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    n = [r["links"] for r in rows]
    for key, label, style in (
        ("expanded_rhs_us", "expanded equations (dense LU)", "o-"),
        ("recursive_rhs_us", "recursive (articulated bodies)", "s-"),
        ("mj_forward_us", "MuJoCo mj_forward", "^--"),
    ):
        points = [(k, r[key]) for k, r in zip(n, rows) if r[key] != ""]
        ax.loglog(*zip(*points), style, label=label)
    ax.set(
        xlabel="links", ylabel="cost per evaluation [us]", title="right-hand side against the number of links"
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(RESULTS / "chain_scaling.png", dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
