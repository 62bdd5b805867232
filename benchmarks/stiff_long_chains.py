"""Long stiff chains: the FMU's default solver against a host's CVODE, and the Jacobian against Pinocchio.

    pip install -e ".[bench]" && python benchmarks/stiff_long_chains.py [--quick]
        [--links 20,50,100] [--dampings 1e2,1e4] [--tols 1e-4,1e-5,1e-6,1e-7,1e-8]
        [--budget 60] [--jacobian-links 3,20,50,100] [--no-runs] [--no-jacobians]

The scene is the stiff ladder's damped light chain (benchmarks/stiff_ladder.py: links of 1 m and
0.1 kg, Ixx = Izz = 0.1/12, Iyy = 1e-5, bobs of 0.1 kg, every joint's damping c), made longer:
a cable or a hanging hose modelled as a damped chain. Two measurements (issue 55):

1. Work against precision, for each number of links and c: 10 s with an output every 0.01 s,
   rtol = atol from 1e-4 to 1e-8, through fmpy.simulate_fmu on the scene's native FMI 2.0 FMU:
   - its Co-Simulation with the default solver (`auto`: DOP853, Radau while the scene is
     stiff), its statistics n_rhs, n_jacobians and n_factorizations read at the end;
   - the same with solver = bdf (the core's BDF, orders 1 to 5);
   - fmpy's CVode (BDF, dense direct solver, Jacobians by CVODE's difference quotients, atol =
     rtol x nominal) on the same FMU's Model Exchange interface. fmpy does not report CVODE's
     counts, but its SUNDIALS library does: they are read here through ctypes from the
     solver's cvode_mem (CVodeGetNumRhsEvals, CVodeGetNumLinRhsEvals: the right-hand sides of
     the difference-quotient Jacobians, CVodeGetNumJacEvals, CVodeGetNumLinSolvSetups: each
     setup factors I - gamma J anew, with or without a new Jacobian).
   The runs of a tolerance follow each other, so their wall times share the machine's load
   (take ratios within one run). A run is stopped after --budget seconds of wall time (the
   time it reached is reported). The error is the largest of the angles (alpha_i, beta_i, in
   rad) at the outputs against the core's Radau at rtol = atol = 1e-12 (integrate_grid), whose
   error against scipy's Radau tests/test_stiff.py bounds. "As accurate": for each FMU
   run the cheapest CVode run of the same rung whose error is at most the FMU's.
2. The Jacobian d(x')/d(x) against Pinocchio's analytical derivatives
   (pinocchio.computeABADerivatives: dq''/dq, dq''/dv and M^-1, Carpentier and Mansard, RSS
   2018) on the same chain at 3, 20, 50 and 100 links: two revolute joints per link, about the
   parent's x then the link's own z (the joint's Rx(beta) Rz(alpha), docs/model.md), each link
   a body of the cylinder and its bob. Timed: Pinocchio's aba and computeABADerivatives from
   Python; this core's right-hand side in a C loop (seconds_per_call) and from Python
   (core.rhs), its Jacobian from Python (core.jacobian: what both FMUs' Radau calls,
   directional.h's cp_jacobian: in the recursive formulation inverse dynamics stepped from
   the link each state moves, and M^-1 by the articulated-body factorization) and the native
   FMU's full d(derivatives)/d(states) by fmi2GetDirectionalDerivative, one call per state
   (a complex-step right-hand side each), from C (benchmarks/directional_host.c).
   Pinocchio's chain is checked to be this one: its accelerations and its derivatives (with
   the damping's -c M^-1 added to dq''/dv) against core.rhs and core.jacobian, at a random
   state (the largest difference, relative to the largest entry, in the CSV's "check").

Writes benchmarks/results/stiff_long_chains.csv (the runs), stiff_long_chains_jacobian.csv and
stiff_long_chains.png; docs/performance.md#long-stiff-chains shows them. --quick: 20 links at
c = 1e2, rtol 1e-4, 1e-6 and 1e-8, the Jacobians at 3 and 20 links.
"""

import argparse
import ctypes
import gc
import subprocess
import tempfile
import time
import zipfile
from functools import partial
from pathlib import Path
from typing import ClassVar

import fmpy
import fmpy.sundials
import numpy as np
from fmpy import read_model_description

from conical_pendulum.builder.compiler import load_core
from conical_pendulum.builder.fmu import build_fmu
from conical_pendulum.builder.packaging.native import fmi_headers
from conical_pendulum.runtime.rules import SOLVERS
from conical_pendulum.scene import Link, Scene
from results_csv import RESULTS, write_rows

HERE = Path(__file__).parent
STOP, INTERVAL = 10.0, 0.01
LINKS, DAMPINGS, TOLS = (20, 50, 100), (1e2, 1e4), (1e-4, 1e-5, 1e-6, 1e-7, 1e-8)
JACOBIAN_LINKS = (3, 20, 50, 100)
BUDGET = 60.0


def light_chain(links):
    """The stiff ladder's chain (stiff_ladder.light_chain); c is set by start values."""
    link = Link(length=1.0, mass=0.1, bob_mass=0.1, damping=1.0, moments=(0.1 / 12, 1e-5, 0.1 / 12))
    return Scene(links=(link,) * links, joint_damping=True)


_BUILT = {}


def native_fmu(links, out):
    """The chain's native FMU, built once per run."""
    if links not in _BUILT:
        _BUILT[links] = build_fmu(light_chain(links), out / f"chain{links}.fmu", backend="native").path
    return _BUILT[links]


def dampings(scene, c):
    return {f"c{i}": c for i in range(scene.n)}


def angles(scene):
    return [f"alpha{i}" for i in range(scene.n)] + [f"beta{i}" for i in range(scene.n)]


class Budget:
    """fmpy's step_finished: stops a run after `seconds` of wall time."""

    def __init__(self, seconds):
        self.seconds, self.start, self.stopped_at = seconds, time.perf_counter(), None

    def __call__(self, t, recorder):
        if time.perf_counter() - self.start > self.seconds:
            self.stopped_at = t
            return False
        return True


def outcome(result, budget, seconds):
    """The outcome: finished, or where the run stopped and how long 10 s would take at its pace so far."""
    if budget.stopped_at is not None or len(result) < round(STOP / INTERVAL) + 1:
        reached = result["time"][-1]
        pace = f" (some {seconds * STOP / reached:.0f} s for {STOP:g} s at that pace)" if reached > 0 else ""
        return f"stopped at t = {reached:.3g} s after {seconds:.0f} s{pace}"
    return "finished"


def fmu_run(path, start, names, tol, budget, solver=None):
    """The Co-Simulation with the FMU's default solver (or solver): (angles, counts, seconds, outcome)."""
    stop = Budget(budget)
    chosen = {} if solver is None else {"solver": SOLVERS.index(solver)}
    begin = time.perf_counter()
    try:
        r = fmpy.simulate_fmu(
            str(path),
            stop_time=STOP,
            output_interval=INTERVAL,
            start_values={**start, **chosen, "rtol": tol, "atol": tol},
            output=[*names, "n_rhs", "n_jacobians", "n_factorizations"],
            step_finished=stop,
        )
    except Exception as exc:  # a discarded step: the FMU's diagnosis
        return None, {}, time.perf_counter() - begin, f"failed: {str(exc)[:120]}"
    seconds = time.perf_counter() - begin
    counts = {
        "rhs": int(r["n_rhs"][-1]),
        "jacobians": int(r["n_jacobians"][-1]),
        "factorizations": int(r["n_factorizations"][-1]),
    }
    return np.column_stack([r[n] for n in names]), counts, seconds, outcome(r, stop, seconds)


# CVODE's counters, from the library fmpy loads (its Python wrapper binds none of them).
_CVODE = fmpy.sundials.libraries.sundials_cvode
CVODE_COUNTS = {
    "rhs": "CVodeGetNumRhsEvals",
    "jacobian_rhs": "CVodeGetNumLinRhsEvals",
    "jacobians": "CVodeGetNumJacEvals",
    "factorizations": "CVodeGetNumLinSolvSetups",
    "steps": "CVodeGetNumSteps",
}


class CountingCVode(fmpy.sundials.CVodeSolver):
    """fmpy's CVodeSolver that reads CVODE's counters before it frees the solver."""

    last: ClassVar[dict] = {}

    def __del__(self):
        counts = {}
        for key, function in CVODE_COUNTS.items():
            value = ctypes.c_long()
            getattr(_CVODE, function)(ctypes.c_void_p(self.cvode_mem), ctypes.byref(value))
            counts[key] = value.value
        CountingCVode.last = counts
        super().__del__()


def cvode_run(path, start, names, tol, budget):
    """fmpy's CVode on the Model Exchange interface: (angles, counts, seconds, outcome)."""
    stop = Budget(budget)
    fmpy.sundials.CVodeSolver, original = CountingCVode, fmpy.sundials.CVodeSolver
    CountingCVode.last = {}
    begin = time.perf_counter()
    try:
        r = fmpy.simulate_fmu(
            str(path),
            fmi_type="ModelExchange",
            solver="CVode",
            relative_tolerance=tol,
            stop_time=STOP,
            output_interval=INTERVAL,
            start_values=start,
            output=list(names),
            step_finished=stop,
        )
    except Exception as exc:
        seconds = time.perf_counter() - begin
        gc.collect()
        return None, CountingCVode.last, seconds, f"failed: {str(exc)[:120]}"
    finally:
        fmpy.sundials.CVodeSolver = original
    seconds = time.perf_counter() - begin
    gc.collect()  # the solver's ctypes callbacks hold it in a cycle: its __del__ runs here
    return np.column_stack([r[n] for n in names]), CountingCVode.last, seconds, outcome(r, stop, seconds)


def angle_error(states, reference):
    """The largest angle error at the outputs; of a stopped run, at those it reached."""
    if states is None or not 0 < len(states) <= len(reference):
        return float("nan")
    return float(np.abs(states - reference[: len(states)]).max())


def reference_angles(scene, start, core):
    parameters, states = scene.split_start(start)
    p, x0 = np.array(scene.parameters(parameters)), np.array(scene.initial_state(states))
    times = np.linspace(0.0, STOP, round(STOP / INTERVAL) + 1)
    begin = time.perf_counter()
    x, _ = core.integrate_grid(x0, p, times, 1e-12, 1e-12, method="radau", max_steps=10**8)
    index = [list(core.STATE_NAMES).index(n) for n in angles(scene)]
    return x[:, index], time.perf_counter() - begin


def runs(links_list, damping_list, tols, budget, out):
    rows = []
    for links in links_list:
        scene = light_chain(links)
        path = native_fmu(links, out)
        core = load_core(scene)
        names = angles(scene)
        for c in damping_list:
            start = dampings(scene, c)
            reference, seconds = reference_angles(scene, start, core)
            print(f"{links} links, c = {c:g}: reference (core Radau 1e-12) in {seconds:.1f} s", flush=True)
            for tol in tols:
                for solver, run in RUNS:
                    states, counts, seconds, why = run(path, start, names, tol, budget)
                    row = {
                        "links": links,
                        "c": c,
                        "solver": solver,
                        "rtol": tol,
                        "seconds": round(seconds, 4),
                        "error_rad": angle_error(states, reference),
                        "rhs": counts.get("rhs", ""),
                        "jacobian_rhs": counts.get("jacobian_rhs", ""),
                        "jacobians": counts.get("jacobians", ""),
                        "factorizations": counts.get("factorizations", ""),
                        "outcome": why,
                    }
                    rows.append(row)  # the FMU's Jacobians are no right-hand sides (cp_jacobian)
                    by_differences = f" (+{row['jacobian_rhs']} for J)" if row["jacobian_rhs"] != "" else ""
                    print(
                        f"{links:4} links c = {c:<6g} {solver:20} rtol {tol:<6g} {seconds:8.3f} s "
                        f"error {row['error_rad']:.2g} rad  rhs {row['rhs']}{by_differences} "
                        f"J {row['jacobians']} LU {row['factorizations']}  {why}",
                        flush=True,
                    )
    return rows


RUNS = (
    ("FMU auto (default)", fmu_run),
    ("FMU bdf", partial(fmu_run, solver="bdf")),
    ("fmpy CVode (ME)", cvode_run),
)


def as_accurate(rows):
    """For each FMU run that finished, the cheapest CVode run of its rung at least as accurate,
    and the ratio of their wall times (FMU / CVode)."""
    table = []
    for fmu in (r for r in rows if r["solver"].startswith("FMU")):
        rivals = [
            r
            for r in rows
            if r["solver"].startswith("fmpy")
            and (r["links"], r["c"]) == (fmu["links"], fmu["c"])
            and r["outcome"] == "finished"
            and r["error_rad"] <= fmu["error_rad"]
        ]
        best = min(rivals, key=lambda r: r["seconds"], default=None) if fmu["outcome"] == "finished" else None
        same = next(
            r
            for r in rows
            if r["solver"].startswith("fmpy")
            and (r["links"], r["c"], r["rtol"]) == (fmu["links"], fmu["c"], fmu["rtol"])
        )
        table.append((fmu, same, best))
    return table


def print_table(rows):
    print(
        "| links | c | FMU solver | rtol | FMU: error, time, RHS / J / LU | CVode same rtol: error, time, RHS (+J) / J / LU "
        "| FMU / CVode | CVode as accurate | FMU / that |"
    )
    print("|---|---|---|---|---|---|---|---|---|")

    def cell(r):
        if r["outcome"] != "finished":
            return f"{r['outcome']}"
        return (
            f"{r['error_rad']:.2g} rad, {r['seconds']:.3g} s, {r['rhs']:,.0f} "
            f"{'(+' + format(r['jacobian_rhs'], ',.0f') + ') ' if r['solver'].startswith('fmpy') else ''}"
            f"/ {r['jacobians']:,.0f} / {r['factorizations']:,.0f}"
        )

    for fmu, same, best in as_accurate(rows):
        rival = (
            f"rtol {best['rtol']:g}: {best['error_rad']:.2g} rad, {best['seconds']:.3g} s" if best else "none"
        )
        print(
            f"| {fmu['links']} | {fmu['c']:g} | {fmu['solver'][4:]} | {fmu['rtol']:g} | {cell(fmu)} | {cell(same)} "
            f"| {fmu['seconds'] / same['seconds']:.2f} | {rival} | "
            f"{fmu['seconds'] / best['seconds']:.2f} |"
            if best
            else f"| {fmu['links']} | {fmu['c']:g} | {fmu['solver'][4:]} | {fmu['rtol']:g} | {cell(fmu)} | {cell(same)} "
            f"| {fmu['seconds'] / same['seconds']:.2f} | {rival} | |"
        )


def plot(rows):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rungs = list(dict.fromkeys((r["links"], r["c"]) for r in rows))
    cs = sorted({c for _, c in rungs})
    links = sorted({n for n, _ in rungs})
    fig, axes = plt.subplots(len(cs), len(links), figsize=(4.2 * len(links), 3.6 * len(cs)), squeeze=False)
    for (n, c), ax in ((rung, axes[cs.index(rung[1])][links.index(rung[0])]) for rung in rungs):
        for solver, style in (("FMU auto (default)", "o-"), ("FMU bdf", "^-"), ("fmpy CVode (ME)", "s--")):
            mine = [
                r
                for r in rows
                if (r["links"], r["c"], r["solver"]) == (n, c, solver)
                and r["outcome"] == "finished"
                and np.isfinite(r["error_rad"])
            ]
            ax.loglog([r["seconds"] for r in mine], [r["error_rad"] for r in mine], style, label=solver)
            for r in mine:
                ax.annotate(f"{r['rtol']:.0e}", (r["seconds"], r["error_rad"]), fontsize=6, alpha=0.7)
        ax.set_title(f"{n} links, c = {c:g}", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.set_xlabel("wall time of 10 s at 100 Hz [s]", fontsize=8)
        ax.set_ylabel("largest angle error [rad]", fontsize=8)
        ax.legend(fontsize=7)
    fig.suptitle(
        "Damped light chains: the FMU's default solver and its BDF against fmpy's CVode, rtol 1e-4 .. 1e-8",
        fontsize=10,
    )
    fig.tight_layout()
    path = RESULTS / "stiff_long_chains.png"
    fig.savefig(path, dpi=100)
    return path


# The Jacobian against Pinocchio.


def pinocchio_chain(scene, g):
    """The scene's chain in Pinocchio: per link a joint about the parent's x (beta) then one
    about the link's z (alpha), the link's cylinder and its bob one body on the second."""
    import pinocchio as pin

    model = pin.Model()
    model.gravity = pin.Motion(np.array([0.0, -g, 0.0]), np.zeros(3))
    parent = 0
    for i, link in enumerate(scene.links):
        top = np.array([0.0, -scene.links[i - 1].length, 0.0]) if i else np.zeros(3)
        jx = model.addJoint(parent, pin.JointModelRX(), pin.SE3(np.eye(3), top), f"beta{i}")
        jz = model.addJoint(jx, pin.JointModelRZ(), pin.SE3.Identity(), f"alpha{i}")
        body = pin.Inertia(link.mass, np.array([0.0, -link.length / 2, 0.0]), np.diag(link.inertia()))
        body += pin.Inertia(link.bob_mass, np.array([0.0, -link.length, 0.0]), np.zeros((3, 3)))
        model.appendBodyToJoint(jz, body, pin.SE3.Identity())
        parent = jz
    return model


def median_seconds(call, calls, repeats=7):
    times = []
    for _ in range(repeats):
        begin = time.perf_counter()
        for _ in range(calls):
            call()
        times.append((time.perf_counter() - begin) / calls)
    return float(np.median(times))


def directional_jacobian_us(scene, path, folder, host):
    """The native FMU's d(derivatives)/d(states) by fmi2GetDirectionalDerivative, one call per
    state, timed in C (directional_host.c's jacobian_states less its set)."""
    md = read_model_description(str(path))
    zipfile.ZipFile(path).extractall(folder)
    vr = {v.name: v.valueReference for v in md.modelVariables}

    def listed(names):
        return ",".join(str(vr[n]) for n in names) or "-"

    n_state = len(scene.state_names())
    calls = max(3, 40_000 // (n_state * n_state))
    run = subprocess.run(
        [
            str(host),
            str(folder / "binaries" / "linux64" / "ConicalPendulum.so"),
            md.guid,
            listed(scene.state_names()),
            listed(scene.input_names()),
            listed([u.variable.name for u in md.derivatives]),
            listed(["energy"]),
            str(calls),
            "5",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    us = {name: float(value) for name, value in (line.split() for line in run.stdout.splitlines())}
    return us["jacobian_states"] - us["set"]


def jacobians(links_list, out, c=1e2):
    import pinocchio as pin

    host = out / "directional_host"
    subprocess.run(
        [
            "cc",
            "-std=c99",
            "-O2",
            f"-I{fmi_headers()}",
            str(HERE / "directional_host.c"),
            "-o",
            str(host),
            "-ldl",
            "-lm",
        ],
        check=True,
    )
    rng = np.random.default_rng(55)
    rows = []
    for links in links_list:
        scene = light_chain(links)
        core = load_core(scene)
        parameters, _ = scene.split_start(dampings(scene, c))
        p = np.array(scene.parameters(parameters))
        g = dict(zip(scene.parameter_names(), p))["g"]
        names = list(core.STATE_NAMES)
        x = np.zeros(len(names))
        n = links
        a = [names.index(f"alpha{i}") for i in range(n)]
        b = [names.index(f"beta{i}") for i in range(n)]
        w = [names.index(f"omega{i}") for i in range(n)]
        d = [names.index(f"delta{i}") for i in range(n)]
        x[a + b] = rng.uniform(-0.5, 0.5, 2 * n)
        x[w + d] = rng.uniform(-1.0, 1.0, 2 * n)

        model = pinocchio_chain(scene, g)
        data = model.createData()
        q = np.ravel(np.column_stack([x[b], x[a]]))  # beta0, alpha0, beta1, alpha1, ...
        v = np.ravel(np.column_stack([x[d], x[w]]))
        tau = -c * v  # each hinge's damping: the joint's axes are orthonormal (docs/model.md)
        order = np.ravel(np.column_stack([b, a]))  # Pinocchio's q index -> the core's state index
        rates = np.ravel(np.column_stack([d, w]))
        # the same chain: accelerations and derivatives against the core's
        ddq = pin.aba(model, data, q, v, tau)
        xdot = core.rhs(x, p)
        accel_check = np.abs(ddq - xdot[rates]).max() / np.abs(xdot[rates]).max()
        pin.computeABADerivatives(model, data, q, v, tau)
        minv = np.triu(data.Minv) + np.triu(data.Minv, 1).T
        dq, dv = data.ddq_dq, data.ddq_dv - c * minv
        J = core.jacobian(x, p)
        ours = np.hstack([J[np.ix_(rates, order)], J[np.ix_(rates, rates)]])
        theirs = np.hstack([dq, dv])
        jacobian_check = np.abs(ours - theirs).max() / np.abs(theirs).max()

        calls = max(3, 20_000 // (n * n))
        us = {
            "pinocchio_aba": median_seconds(lambda: pin.aba(model, data, q, v, tau), 20 * calls),
            "pinocchio_aba_derivatives": median_seconds(
                lambda: pin.computeABADerivatives(model, data, q, v, tau), calls
            ),
            "core_rhs_c_loop": float(
                np.median([core.seconds_per_call("rhs", x, p, max(2000, 200_000 // n)) for _ in range(5)])
            ),
            "core_rhs_python": median_seconds(lambda: core.rhs(x, p), 20 * calls),
            "core_jacobian_python": median_seconds(lambda: core.jacobian(x, p), max(1, calls // 20)),
        }
        us = {k: 1e6 * s for k, s in us.items()}
        us["native_fmu_directional_jacobian"] = directional_jacobian_us(
            scene, native_fmu(links, out), out / f"jacobian{links}", host
        )
        for operation, value in us.items():
            rows.append(
                {
                    "links": links,
                    "states": len(names),
                    "operation": operation,
                    "us_per_call": round(value, 3),
                    "over_pinocchio_derivatives": round(value / us["pinocchio_aba_derivatives"], 3),
                    "check": f"{accel_check:.1e} {jacobian_check:.1e}"
                    if operation.startswith("pinocchio")
                    else "",
                }
            )
        print(
            f"{links:4} links: "
            + ", ".join(f"{k} {v:.4g} us" for k, v in us.items())
            + f"; Pinocchio against the core: accelerations {accel_check:.1e}, Jacobian {jacobian_check:.1e}",
            flush=True,
        )
    return rows


def numbers(text, kind=float):
    return tuple(kind(v) for v in text.split(","))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--quick", action="store_true", help="20 links, c = 1e2, rtol 1e-4, 1e-6, 1e-8; J at 3, 20"
    )
    parser.add_argument("--links", type=lambda s: numbers(s, int), default=LINKS)
    parser.add_argument("--dampings", type=numbers, default=DAMPINGS)
    parser.add_argument("--tols", type=numbers, default=TOLS)
    parser.add_argument("--budget", type=float, default=BUDGET, help="seconds of wall time a run may take")
    parser.add_argument("--jacobian-links", type=lambda s: numbers(s, int), default=JACOBIAN_LINKS)
    parser.add_argument("--no-runs", action="store_true", help="only the Jacobians")
    parser.add_argument("--no-jacobians", action="store_true", help="only the runs")
    args = parser.parse_args()
    if args.quick:
        args.links, args.dampings, args.tols, args.jacobian_links = (20,), (1e2,), (1e-4, 1e-6, 1e-8), (3, 20)
    with tempfile.TemporaryDirectory(prefix="stiff_long_chains_") as folder:
        out = Path(folder)
        if not args.no_runs:
            rows = runs(args.links, args.dampings, args.tols, args.budget, out)
            print(f"wrote {write_rows('stiff_long_chains', rows)} and {plot(rows)}")
            print_table(rows)
        if not args.no_jacobians:
            print(f"wrote {write_rows('stiff_long_chains_jacobian', jacobians(args.jacobian_links, out))}")


if __name__ == "__main__":
    main()
