"""What the implicit solver's levers buy on long stiff chains: the core's Radau on the damped
light chain, its counts, time and error, for the build this checkout makes.

    python benchmarks/radau_levers.py [--links 10,20,50] [--damping 1e2,1e4] [--rtol 1e-6,1e-8]
                                      [--out benchmarks/results/radau_levers.csv]

The chain is the stiff ladder's (links of 1 m and 0.1 kg, Ixx = Izz = 0.1/12, Iyy = 1e-5, bobs
of 0.1 kg, every joint's damping c), started at alpha0 = 0.5, beta1 = -0.3, 5 s with an output
every 0.01 s through the core's `integrate_grid` (the C loop the FMUs step with, without FMI).
The error is the angles' largest distance from the same core's Radau at rtol 1e-12. Each lever
(a commit) is measured alone by running this script in a worktree of the commit before it and
of the commit itself, one after the other (docs/performance.md says which): the counts are the
build's own and repeat exactly, the times are the best of three on the machine as it was.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from conical_pendulum import Link, Scene
from conical_pendulum.builder.compiler import load_core
from results_csv import RESULTS, append_rows, checkout_commit

REFERENCE_RTOL = 1e-12


def light_chain(links: int) -> Scene:
    link = Link(length=1.0, mass=0.1, bob_mass=0.1, damping=1.0, moments=(0.1 / 12, 1e-5, 0.1 / 12))
    return Scene(links=(link,) * links, joint_damping=True)


def numbers(text: str) -> list[float]:
    return [float(value) for value in text.split(",")]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--links", type=lambda s: [int(v) for v in s.split(",")], default=[10, 20, 50])
    parser.add_argument("--damping", type=numbers, default=[1e2, 1e4])
    parser.add_argument("--rtol", type=numbers, default=[1e-6, 1e-8])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=RESULTS / "radau_levers.csv")
    args = parser.parse_args()
    commit = checkout_commit()
    rows = []
    for links in args.links:
        scene = light_chain(links)
        core = load_core(scene)
        angles = [k for k, name in enumerate(core.STATE_NAMES) if name.startswith(("alpha", "beta"))]
        x0 = np.array(scene.initial_state({"alpha0": 0.5, "beta1": -0.3}))
        times = np.linspace(0.0, 5.0, 501)
        for c in args.damping:
            p = np.array(scene.parameters({f"c{i}": c for i in range(links)}))
            reference, _ = core.integrate_grid(x0, p, times, REFERENCE_RTOL, REFERENCE_RTOL, method="radau")
            for rtol in args.rtol:
                best = np.inf
                for _ in range(args.repeats):
                    counts = {}
                    start = time.perf_counter()
                    states, _ = core.integrate_grid(x0, p, times, rtol, rtol, method="radau", counts=counts)
                    best = min(best, time.perf_counter() - start)
                error = float(np.abs(states[:, angles] - reference[:, angles]).max())
                row = {
                    "commit": commit,
                    "links": links,
                    "c": c,
                    "rtol": rtol,
                    "seconds": round(best, 4),
                    "jacobians": counts["njev"],
                    "factorizations": counts["nlu"],
                    "rhs": counts["nfev"],
                    "steps": counts["naccept"],
                    "error_rad": f"{error:.2e}",
                }
                rows.append(row)
                print(row, flush=True)
    append_rows(args.out, rows)
    print(f"appended {len(rows)} rows to {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
