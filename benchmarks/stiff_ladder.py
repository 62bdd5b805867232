"""Stiff scenes: every solver of the native FMU against a host's CVODE and scipy's stiff solvers.

    python benchmarks/stiff_ladder.py [--quick]

The ladder: the damped light chain (links of 1 m and 0.1 kg, Ixx = Izz = 0.1/12, Iyy = 1e-5,
bobs of 0.1 kg; its Jacobian's eigenvalues reach about -69 c) of 3 and of 20 links with joint
damping c = 1, 1e2, 1e4, 1e6, and the crane (scenes/crane.toml) with a 1 kg hook under a 20 t
load: a fast oscillation of the hook between rope and sling (about 250 rad/s), not a stiff
decay. Each rung runs 10 s with an output every 0.01 s at rtol = atol = 1e-6:

- the native FMI 2.0 FMU's Co-Simulation with each solver (rk45, dop853, radau, auto) through
  fmpy.simulate_fmu, stopped after BUDGET seconds of wall time if it has not finished;
- fmpy's CVode on the same FMU's Model Exchange interface;
- scipy's Radau, BDF and LSODA on the compiled core's right-hand side, given its exact Jacobian.

Each row: right-hand sides, Jacobians, factorizations (where the solver says), wall time, and
the largest error at the outputs against the core's Radau at rtol = atol = 1e-12 (DOP853 at
1e-12 for the crane), scaled by max(1, |x|) per state. Also measured: what the automatic
choice costs on the seed against DOP853 (its default tolerance and 1e-6), a master counting
its points as k h against t + h (the coupled seed at 60 Hz, DOP853 1e-10), and a
work-precision sweep of the 3-link chain at c = 1e4 (rtol 1e-3 to 1e-10).

Writes benchmarks/results/stiff_ladder.csv, stiff_work_precision.csv and
stiff_work_precision.png; docs/performance.md#stiff-scenes shows them. --quick: the 3-link
rungs only.
"""

import argparse
import tempfile
import time
from pathlib import Path

import fmpy
import numpy as np
from fmpy import read_model_description
from fmpy.fmi2 import FMU2Slave
from scipy.integrate import solve_ivp

from conical_pendulum.builder.compiler import load_core
from conical_pendulum.builder.fmu import build_fmu
from conical_pendulum.scene import Link, Scene, load_scene
from results_csv import RESULTS, write_rows

ROOT = Path(__file__).resolve().parent.parent
STOP, INTERVAL, TOL, BUDGET = 10.0, 0.01, 1e-6, 60.0
SOLVERS = {"rk45": 1, "dop853": 2, "radau": 3, "auto": 4}
DAMPINGS = (1.0, 1e2, 1e4, 1e6)


def light_chain(links):
    link = Link(length=1.0, mass=0.1, bob_mass=0.1, damping=1.0, moments=(0.1 / 12, 1e-5, 0.1 / 12))
    return Scene(links=(link,) * links, joint_damping=True)


def crane():
    return load_scene(ROOT / "scenes" / "crane.toml")


CRANE_START = {"m0": 1.0, "m1": 20000.0, "alpha0": 0.05, "alpha1": 0.1}


def rungs(quick):
    """(name, scene, start values, reference method) of every rung."""
    found = []
    for links in (3,) if quick else (3, 20):
        for c in DAMPINGS:
            found.append(
                (f"{links} links, c = {c:g}", light_chain(links), {f"c{i}": c for i in range(links)}, "radau")
            )
    if not quick:
        found.append(("crane, 1 kg hook under 20 t", crane(), CRANE_START, "dop853"))
    return found


class Timeout:
    """fmpy's step_finished: stops a run after BUDGET seconds of wall time."""

    def __init__(self):
        self.start, self.stopped_at = time.perf_counter(), None

    def __call__(self, t, recorder):
        if time.perf_counter() - self.start > BUDGET:
            self.stopped_at = t
            return False
        return True


def fmu_run(path, start, names, solver, tol=TOL):
    """One Co-Simulation run: (states at the outputs, counts, seconds, why it stopped)."""
    timeout = Timeout()
    begin = time.perf_counter()
    why = "finished"
    try:
        r = fmpy.simulate_fmu(
            str(path),
            stop_time=STOP,
            output_interval=INTERVAL,
            start_values={**start, "solver": solver, "rtol": tol, "atol": tol},
            output=[*names, "n_rhs", "n_jacobians", "n_factorizations"],
            step_finished=timeout,
        )
    except Exception as exc:  # a discarded step: the FMU's diagnosis
        return None, {}, time.perf_counter() - begin, f"failed: {str(exc)[:120]}"
    seconds = time.perf_counter() - begin
    if timeout.stopped_at is not None or len(r) < round(STOP / INTERVAL) + 1:
        why = f"stopped at t = {r['time'][-1]:.3g} s after {seconds:.0f} s"
    counts = {"rhs": r["n_rhs"][-1], "jacobians": r["n_jacobians"][-1], "lu": r["n_factorizations"][-1]}
    return np.column_stack([r[n] for n in names]), counts, seconds, why


def cvode_run(path, start, names, tol=TOL):
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
        )
    except Exception as exc:
        return None, time.perf_counter() - begin, f"failed: {str(exc)[:120]}"
    return np.column_stack([r[n] for n in names]), time.perf_counter() - begin, "finished"


def scipy_run(core, x0, p, times, method, tol=TOL):
    begin = time.perf_counter()
    sol = solve_ivp(
        lambda t, x: core.rhs(x, p),
        (times[0], times[-1]),
        x0,
        method=method,
        t_eval=times,
        rtol=tol,
        atol=tol,
        jac=lambda t, x: core.jacobian(x, p),
    )
    seconds = time.perf_counter() - begin
    counts = {"rhs": sol.nfev, "jacobians": sol.njev, "lu": sol.nlu}
    return (sol.y.T if sol.success else None), counts, seconds, "finished" if sol.success else sol.message


def split(scene, start):
    """The core's p and x0 of start values."""
    parameters, states = scene.split_start(start)
    return np.array(scene.parameters(parameters)), np.array(scene.initial_state(states))


def error(states, reference):
    if states is None or len(states) != len(reference):
        return float("nan")
    scale = np.maximum(1.0, np.abs(reference).max(axis=0))
    return float((np.abs(states - reference) / scale).max())


def rung(name, scene, start, reference_method, path):
    """One rung's rows: the scene's native FMU (built at path) with each solver, fmpy's CVode
    and scipy's stiff solvers, each against the core's reference_method at 1e-12."""
    rows = []
    path = build_fmu(scene, path, backend="native").path
    core = load_core(scene)
    names = list(core.STATE_NAMES)
    p, x0 = split(scene, start)
    times = np.linspace(0.0, STOP, round(STOP / INTERVAL) + 1)
    reference, _ = core.integrate_grid(x0, p, times, 1e-12, 1e-12, method=reference_method, max_steps=10**8)

    def row(solver, states, counts, seconds, why):
        rows.append(
            {
                "rung": name,
                "solver": solver,
                "rhs": counts.get("rhs", ""),
                "jacobians": counts.get("jacobians", ""),
                "factorizations": counts.get("lu", ""),
                "seconds": round(seconds, 4),
                "error": error(states, reference),
                "outcome": why,
            }
        )
        print(
            f"{name:28} {solver:22} {counts.get('rhs', ''):>10} {counts.get('jacobians', ''):>6} "
            f"{counts.get('lu', ''):>6} {seconds:8.3f} s  error {rows[-1]['error']:.2g}  {why}",
            flush=True,
        )

    for solver, value in SOLVERS.items():
        row(f"FMU {solver}", *fmu_run(path, start, names, value))
    states, seconds, why = cvode_run(path, start, names)
    row("fmpy CVode (ME)", states, {}, seconds, why)
    for method in ("Radau", "BDF", "LSODA"):
        row(f"scipy {method}", *scipy_run(core, x0, p, times, method))
    return rows


def ladder(quick, out):
    rows = []
    for k, (name, scene, start, reference_method) in enumerate(rungs(quick)):
        rows += rung(name, scene, start, reference_method, out / f"stiff_{k}.fmu")
    return rows


def seed_cost():
    """The automatic choice on the seed against DOP853: right-hand sides and the largest
    difference of the states, at the default tolerance and at 1e-6."""
    scene = Scene.uniform(3)
    core = load_core(scene)
    x0, p = np.array(scene.initial_state()), np.array(scene.parameters())
    times = np.linspace(0.0, STOP, 601)
    rows = []
    for tol in (1e-11, 1e-6):
        counts = {}
        for method in ("dop853", "auto"):
            states, _ = core.integrate_grid(
                x0, p, times, tol, tol, method=method, counts=counts.setdefault(method, {})
            )
            counts[method]["states"] = states
        ratio = counts["auto"]["nfev"] / counts["dop853"]["nfev"]
        same = np.array_equal(counts["auto"]["states"], counts["dop853"]["states"])
        print(
            f"seed, tol {tol:g}: auto {counts['auto']['nfev']} / DOP853 {counts['dop853']['nfev']} right-hand sides "
            f"= {ratio:.3f}, states bit for bit the same: {same}"
        )
        rows.append(
            {
                "rung": f"seed, tol {tol:g}",
                "solver": "auto / dop853",
                "rhs": round(ratio, 4),
                "jacobians": counts["auto"]["njev"],
                "factorizations": counts["auto"]["nlu"],
                "seconds": "",
                "error": 0.0
                if same
                else float(np.abs(counts["auto"]["states"] - counts["dop853"]["states"]).max()),
                "outcome": "bit for bit" if same else "differs",
            }
        )
    return rows


def k_h_master(out):
    """The coupled seed at 60 Hz, DOP853 1e-10: right-hand sides with points t + h and k h."""
    scene = Scene.uniform(3, coupling=True)
    path = build_fmu(scene, out / "coupled_seed.fmu", backend="native").path
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipped = fmpy.extract(str(path))
    rows, h, steps = [], 1 / 60, 600
    for how in ("t + h", "k h"):
        fmu = FMU2Slave(
            guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier
        )
        fmu.instantiate()
        fmu.setInteger([vr["solver"]], [2])
        fmu.setReal([vr["rtol"], vr["atol"]], [1e-10, 1e-10])
        fmu.setupExperiment(startTime=0.0, stopTime=steps * h)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        t = 0.0
        for k in range(steps):
            fmu.doStep(t if how == "t + h" else k * h, h)
            t += h
        (rhs,) = fmu.getReal([vr["n_rhs"]])
        fmu.terminate()
        fmu.freeInstance()
        print(f"coupled seed, 60 Hz, DOP853 1e-10, points {how}: {rhs:.0f} right-hand sides")
        rows.append(
            {
                "rung": "coupled seed, 60 Hz, DOP853 1e-10",
                "solver": f"points {how}",
                "rhs": rhs,
                "jacobians": "",
                "factorizations": "",
                "seconds": "",
                "error": "",
                "outcome": "finished",
            }
        )
    return rows


def work_precision(out):
    """The 3-link chain at c = 1e4: error against wall time, rtol = atol from 1e-3 to 1e-10."""
    scene, start = light_chain(3), {f"c{i}": 1e4 for i in range(3)}
    path = build_fmu(scene, out / "stiff_wp.fmu", backend="native").path
    core = load_core(scene)
    names = list(core.STATE_NAMES)
    p, x0 = split(scene, start)
    times = np.linspace(0.0, STOP, round(STOP / INTERVAL) + 1)
    reference, _ = core.integrate_grid(x0, p, times, 1e-12, 1e-12, method="radau")
    rows = []
    for tol in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10):
        for solver in ("radau", "auto"):
            states, counts, seconds, _ = fmu_run(path, start, names, SOLVERS[solver], tol)
            rows.append(
                {
                    "solver": f"FMU {solver}",
                    "tol": tol,
                    "seconds": seconds,
                    "rhs": counts["rhs"],
                    "error": error(states, reference),
                }
            )
        states, seconds, _ = cvode_run(path, start, names, tol)
        rows.append(
            {
                "solver": "fmpy CVode (ME)",
                "tol": tol,
                "seconds": seconds,
                "rhs": "",
                "error": error(states, reference),
            }
        )
        states, counts, seconds, _ = scipy_run(core, x0, p, times, "Radau", tol)
        rows.append(
            {
                "solver": "scipy Radau",
                "tol": tol,
                "seconds": seconds,
                "rhs": counts["rhs"],
                "error": error(states, reference),
            }
        )
        print(
            f"work-precision, tol {tol:g}: "
            + ", ".join(f"{r['solver']} {r['seconds']:.3f} s {r['error']:.2g}" for r in rows[-4:]),
            flush=True,
        )
    return rows


def plot(rows):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for solver in dict.fromkeys(r["solver"] for r in rows):
        mine = [r for r in rows if r["solver"] == solver and np.isfinite(r["error"])]
        ax.loglog([r["seconds"] for r in mine], [r["error"] for r in mine], "o-", label=solver)
    ax.set_xlabel("wall time of 10 s at 100 Hz [s]")
    ax.set_ylabel("largest error at the outputs")
    ax.set_title("3-link damped light chain, c = 1e4 (stiff): rtol = atol 1e-3 .. 1e-10")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    path = RESULTS / "stiff_work_precision.png"
    fig.savefig(path, dpi=110)
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="the 3-link rungs only")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder)
        rows = seed_cost() + k_h_master(out) + ladder(args.quick, out)
        print(f"wrote {write_rows('stiff_ladder', rows)}")
        if not args.quick:
            wp = work_precision(out)
            print(f"wrote {write_rows('stiff_work_precision', wp)} and {plot(wp)}")


if __name__ == "__main__":
    main()
