"""What a Jacobian costs the implicit solver, and what the solver's run costs, for the build this
checkout makes: the damped light chain of benchmarks/radau_levers.py at 20, 50 and 100 links.

    python benchmarks/jacobian_cost.py [--links 20,50,100] [--out benchmarks/results/jacobian_cost.csv]

Timed in one process: the core's Jacobian from Python (core.jacobian: directional.h's
cp_jacobian, what both FMUs' Radau calls; best of 15, of 7 at 100 links) at a random state
(angles within +-1 rad, rates within +-2 rad/s), and one right-hand side in a C loop
(seconds_per_call) as its unit; then the core's Radau on the 50-link chain (5 s, an output
every 0.01 s, from alpha0 = 0.5, beta1 = -0.3, as radau_levers.py runs it) at c = 1e2 (rtol 1e-6
and 1e-8) and c = 1e4 (rtol 1e-6), one run each, with its counts. Each lever of issue 55 is a
commit: this script is run in a worktree of each, one after the other on a quiet machine
(docs/performance.md says which), and appends its rows under the commit's name.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from conical_pendulum.builder.compiler import load_core
from radau_levers import light_chain
from results_csv import RESULTS, append_rows, checkout_commit

SOLVER_RUNS = ((50, 1e2, 1e-6), (50, 1e2, 1e-8), (50, 1e4, 1e-6))


def jacobian_row(links: int) -> dict:
    scene = light_chain(links)
    core = load_core(scene)
    rng = np.random.default_rng(0)
    rest = core.NSTATE - 4 * links  # the books
    x = np.concatenate([rng.uniform(-1, 1, 2 * links), rng.uniform(-2, 2, 2 * links), np.zeros(rest)])
    p = np.array(scene.parameters({}))
    core.jacobian(x, p)
    best = np.inf
    for _ in range(15 if links < 100 else 7):
        start = time.perf_counter()
        core.jacobian(x, p)
        best = min(best, time.perf_counter() - start)
    rhs = core.seconds_per_call("rhs", x, p, 5000)
    return {
        "what": "jacobian",
        "links": links,
        "jacobian_ms": round(best * 1e3, 3),
        "rhs_us": round(rhs * 1e6, 2),
    }


def solver_row(links: int, c: float, rtol: float) -> dict:
    scene = light_chain(links)
    core = load_core(scene)
    x0 = np.array(scene.initial_state({"alpha0": 0.5, "beta1": -0.3}))
    p = np.array(scene.parameters({f"c{i}": c for i in range(links)}))
    counts = {}
    start = time.perf_counter()
    core.integrate_grid(x0, p, np.linspace(0.0, 5.0, 501), rtol, rtol, method="radau", counts=counts)
    seconds = time.perf_counter() - start
    return {"what": "radau", "links": links, "c": c, "rtol": rtol, "seconds": round(seconds, 3)} | {
        key: counts[key] for key in ("njev", "nlu", "nfev", "naccept", "nreject")
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--links", type=lambda s: [int(v) for v in s.split(",")], default=[20, 50, 100])
    parser.add_argument("--out", type=Path, default=RESULTS / "jacobian_cost.csv")
    args = parser.parse_args()
    commit = checkout_commit()
    rows = []
    for row in [jacobian_row(links) for links in args.links] + [solver_row(*run) for run in SOLVER_RUNS]:
        rows.append({"commit": commit} | row)
        print(rows[-1], flush=True)
    fields = ["commit", "what", "links", "jacobian_ms", "rhs_us", "c", "rtol", "seconds"]
    append_rows(args.out, rows, fields + ["njev", "nlu", "nfev", "naccept", "nreject"])
    print(f"appended {len(rows)} rows to {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
