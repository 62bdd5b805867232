"""Work against precision: every FMU solver and the native alternatives, in one run.

    python benchmarks/work_precision.py [--quick] [--points-only]

Scenarios: "seed" (3 links, the seed's start, 10 s, 601 samples) and "hard" (5 links,
angles up to 120 degrees and spinning, 10 s). For each solver and setting: the largest
angle error and bob-position error over the output grid and the final-state error
against a reference (scipy DOP853 at 1e-13, whose own error is estimated against
1e-12), the wall time (median of repeats), right-hand-side evaluations, and the
relative energy drift over 1000 s.

The FMU's solvers ending every integration on the point (across_points = 0) are driven
exactly as the FMU drives them (the compiled core's Stepper, one call per 1/60 s
communication step), without the FMI interface; one row measures the FMU itself through
fmpy.simulate_fmu at its default settings.

Across communication points (issue 37): the seed's native FMU (FMI 2.0, fmpy's low-level
API, stop time declared) at 60 Hz and at 1 ms, RK45 and DOP853 at rtol = atol from 1e-4
to 1e-12 (with 3e-11 and 1e-11, around the default), across_points 1 and 0, beside the
core's uninterrupted dense-output run of the same method and tolerance on the same points
(core.integrate_grid): right-hand sides, the ratio to the uninterrupted run's, the largest
angle error over the points against the reference (scipy DOP853 at 1e-13 on the same
points), and the seconds of the FMU's run (one run; fmpy's Python loop included, which
dominates at 1 ms). Writes benchmarks/results/work_precision_points.csv. What a restart
costs (an input set to a new value at every point, the coupled seed):
benchmarks/results/work_precision_restarts.csv.

PyDy's pipeline of the seed integrates the published (pydy-example) equations, so its
error is taken against the reference of that model.
Writes benchmarks/results/work_precision.csv and work_precision_<scenario>.png.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import odeint, solve_ivp

from conical_pendulum import Scene
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.builder.fmu import DEFAULT_SETTINGS
from results_csv import RESULTS, write_rows

STEP = 1.0 / 60.0


def scenarios():
    hard_state = {}
    for i in range(5):
        hard_state[f"alpha{i}"] = math.radians(120.0) * (-1) ** i
        hard_state[f"beta{i}"] = math.radians(40.0 + 10 * i)
        hard_state[f"delta{i}"] = 1.0
    return {"seed": (Scene.uniform(3), {}), "hard": (Scene.uniform(5), hard_state)}


def median_time(run, repeats):
    times, out = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        out = run()
        times.append(time.perf_counter() - start)
    return float(np.median(times)), out


def fmu_solver(core, p, x0, method, rtol, atol, max_step, t_end, sample_every=1):
    """The FMU's stepping: one Stepper.step per communication step of 1/60 s."""
    values = np.zeros(core.NSTATE + core.NOUTPUT)
    values[: core.NSTATE] = x0
    stepper = core.Stepper(p.copy(), values)
    stepper.update_outputs()
    steps = round(t_end / STEP)
    rows = [values.copy()]
    for k in range(steps):
        status = stepper.step(core.METHODS[method], k * STEP, STEP, rtol, atol, max_step, 10**7)
        if status:
            raise RuntimeError(f"{method} failed: {core.STATUS[status]}")
        if (k + 1) % sample_every == 0:
            rows.append(values.copy())
    return np.array(rows)[:, : core.NSTATE].copy(), stepper.nfev


def native(rhs, x0, times, method, tol, core=None, p=None):
    if method == "core":  # the compiled core's DOP853 with dense output, no Python per step
        return core.integrate_grid(x0, p, times, tol, tol)
    if method == "odeint":
        states, info = odeint(
            lambda x, t: rhs(x), x0, times, rtol=tol, atol=tol, full_output=True, mxstep=10**7
        )
        return states, int(info["nfe"][-1])
    sol = solve_ivp(
        lambda t, x: rhs(x), (times[0], times[-1]), x0, method=method, t_eval=times, rtol=tol, atol=tol
    )
    if not sol.success:
        raise RuntimeError(sol.message)
    return np.ascontiguousarray(sol.y.T), sol.nfev


def errors(core, p, states, reference, ref_outputs, n, bob_index):
    angles = np.abs(states[:, : 2 * n] - reference[:, : 2 * n]).max()
    outputs = np.array([core.outputs(x, p) for x in states])
    bobs = np.abs(outputs[:, bob_index] - ref_outputs[:, bob_index]).max()
    final = np.abs(states[-1] - reference[-1]).max()
    return angles, bobs, final


def energy_drift(core, p, states):
    energy = np.array([core.outputs(x, p)[-1] for x in states])
    return float(np.abs(energy - energy[0]).max() / abs(energy[0]))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true", help="fewer settings, no 1000 s runs")
    parser.add_argument(
        "--points-only", action="store_true", help="only the runs across communication points"
    )
    args = parser.parse_args()
    if args.points_only:
        write_rows("work_precision_points", across_points_rows(args.quick))
        write_rows("work_precision_restarts", restart_rows())
        return
    tolerances = [1e-4, 1e-6, 1e-8, 1e-10] if not args.quick else [1e-6, 1e-9]
    long_horizon = 0.0 if args.quick else 1000.0
    rows = []
    for name, (scene, state) in scenarios().items():
        core = load_core(scene)
        n = scene.n
        p = np.array(scene.parameters())
        x0 = np.array(scene.initial_state(state))
        times = np.arange(601) * STEP
        rhs = lambda x, core=core, p=p: core.rhs(x, p)  # noqa: E731
        reference, _ = native(rhs, x0, times, "DOP853", 1e-13)
        second, _ = native(rhs, x0, times, "DOP853", 1e-12)
        ref_outputs = np.array([core.outputs(x, p) for x in reference])
        names = scene.output_names()
        bob_index = [k for k, v in enumerate(names) if v.startswith("bob")]
        print(
            f"\n{name}: reference DOP853 1e-13; its own error (against 1e-12): "
            f"{np.abs(reference - second).max():.1e}"
        )
        candidates = []
        for max_step in (STEP, STEP / 2, STEP / 4, STEP / 8):
            candidates.append(("FMU rk4", f"max_step={max_step:.4g}", "rk4", 1.0, max_step))
        for method in ("rk45", "dop853"):
            for tol in tolerances + ([1e-12] if method == "dop853" else []):
                candidates.append((f"FMU {method}", f"tol={tol:g}", method, tol, 0.0))
        for tol in tolerances + [1e-12]:
            candidates.append(("core DOP853 dense", f"tol={tol:g}", "core", tol, None))
        for name_ in ("RK45", "DOP853", "LSODA", "Radau", "odeint"):
            for tol in tolerances:
                if name_ == "Radau" and tol < 1e-8:
                    continue  # minutes per run
                candidates.append((f"scipy {name_}", f"tol={tol:g}", name_, tol, None))
        candidates.append(("scipy odeint", "defaults (1.49e-8)", "odeint", 1.49012e-8, None))

        for label, setting, method, tol, max_step in candidates:
            if max_step is not None:
                run = lambda: fmu_solver(core, p, x0, method, tol, tol, max_step, 10.0)  # noqa: E731
            else:
                run = lambda: native(rhs, x0, times, method, tol, core, p)  # noqa: E731
            try:
                seconds, (states, nfev) = median_time(run, 5 if "Radau" not in label else 1)
            except (RuntimeError, core.CoreError) as exc:
                print(f"  {label:<14} {setting:<20} failed: {exc}", flush=True)
                rows.append(
                    {
                        "scenario": name,
                        "solver": label,
                        "setting": setting,
                        "seconds": math.nan,
                        "nfev": 0,
                        "angle_error": math.nan,
                        "bob_error": math.nan,
                        "final_error": math.nan,
                        "energy_drift_1000s": math.nan,
                    }
                )
                continue
            angle, bob, final = errors(core, p, states, reference, ref_outputs, n, bob_index)
            drift = float("nan")
            if long_horizon:
                try:
                    if max_step is not None:
                        long_states, _ = fmu_solver(core, p, x0, method, tol, tol, max_step, long_horizon, 60)
                    else:
                        long_states, _ = native(
                            rhs, x0, np.arange(0.0, long_horizon + 0.5, 1.0), method, tol, core, p
                        )
                    drift = energy_drift(core, p, long_states)
                except (RuntimeError, core.CoreError) as exc:
                    print(f"  {label:<14} {setting:<20} 1000 s run failed: {exc}", flush=True)
            rows.append(
                {
                    "scenario": name,
                    "solver": label,
                    "setting": setting,
                    "seconds": seconds,
                    "nfev": nfev,
                    "angle_error": angle,
                    "bob_error": bob,
                    "final_error": final,
                    "energy_drift_1000s": drift,
                }
            )
            print(
                f"  {label:<14} {setting:<20} {seconds * 1e3:9.2f} ms {nfev:>8} rhs  "
                f"angle {angle:8.1e}  bob {bob:8.1e}  final {final:8.1e}  drift {drift:8.1e}",
                flush=True,
            )
        if name == "seed":
            rows += seed_pipeline_rows(times, tolerances, long_horizon)
            rows.append(fmu_row(scene, core, p, reference, ref_outputs, bob_index))
    write_rows("work_precision", rows)
    plot(rows)
    write_rows("work_precision_points", across_points_rows(args.quick))
    write_rows("work_precision_restarts", restart_rows())


def fmu_points_run(path, solver, tol, across, interval, steps, names, push=None):
    """The native FMU from 0 through steps points: the states at every point, n_rhs, seconds."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipped = extract(str(path))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier)
    fmu.instantiate()
    fmu.setInteger([vr["solver"], vr["across_points"]], [solver, across])
    fmu.setReal([vr["rtol"], vr["atol"]], [tol, tol])
    times = list(_added(interval, steps))
    fmu.setupExperiment(startTime=0.0, stopTime=times[-1])
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    refs = [vr[n] for n in names]
    start = time.perf_counter()
    rows = [fmu.getReal(refs)]
    for k in range(steps):
        if push:
            fmu.setReal([vr[push]], [0.01 * (k % 7)])  # a new value at every point
        fmu.doStep(times[k], interval)
        rows.append(fmu.getReal(refs))
    seconds = time.perf_counter() - start
    nfev = int(fmu.getReal([vr["n_rhs"]])[0])
    fmu.terminate()
    fmu.freeInstance()
    return np.array(times), np.array(rows), nfev, seconds


def across_points_rows(quick):
    """The seed's native FMU at 60 Hz and 1 ms, across points and on them, beside the core's
    uninterrupted run of the same method and tolerance."""
    import tempfile

    from conical_pendulum.builder.fmu import build_fmu

    scene = Scene.uniform(3)
    core = load_core(scene)
    p, x0 = np.array(scene.parameters()), np.array(scene.initial_state())
    tolerances = [1e-4, 1e-6, 1e-8, 1e-10, 3e-11, 1e-11, 1e-12] if not quick else [1e-6, 1e-10]
    rows = []
    print("\nseed, the native FMU across communication points (n_rhs, ratio to the uninterrupted run)")
    with tempfile.TemporaryDirectory() as tmp:
        path = build_fmu(scene, Path(tmp) / "ConicalPendulum.fmu", backend="native").path
        for label, interval, steps in (("60 Hz", STEP, 600), ("1 ms", 1e-3, 10_000)):
            times = np.array(list(_added(interval, steps)))
            sol = solve_ivp(
                lambda t, x: core.rhs(x, p),
                (0.0, times[-1]),
                x0,
                "DOP853",
                t_eval=times,
                rtol=1e-13,
                atol=1e-13,
            )
            reference = sol.y.T
            for method, solver in (("rk45", 1), ("dop853", 2)):
                for tol in tolerances:
                    grid, grid_nfev = core.integrate_grid(x0, p, times, tol, tol, method=method)
                    grid_error = float(np.abs(grid[:, :6] - reference[:, :6]).max())
                    found = {"points": label, "solver": method, "rtol": tol, "core_nfev": grid_nfev}
                    found["core_angle_error"] = grid_error
                    for across in (1, 0):
                        _, states, nfev, seconds = fmu_points_run(
                            path, solver, tol, across, interval, steps, scene.state_names()
                        )
                        key = "across" if across else "on_points"
                        found[f"{key}_nfev"] = nfev
                        found[f"{key}_ratio"] = nfev / grid_nfev
                        found[f"{key}_angle_error"] = float(np.abs(states[:, :6] - reference[:, :6]).max())
                        found[f"{key}_seconds"] = seconds
                    rows.append(found)
                    print(
                        f"  {label:>5} {method:<6} {tol:7.0e}  core {grid_nfev:>7} ({grid_error:7.1e})  "
                        f"across {found['across_nfev']:>7} x{found['across_ratio']:.2f} "
                        f"({found['across_angle_error']:7.1e}, {found['across_seconds']:.2f} s)  "
                        f"on points {found['on_points_nfev']:>7} x{found['on_points_ratio']:.1f} "
                        f"({found['on_points_angle_error']:7.1e}, {found['on_points_seconds']:.2f} s)",
                        flush=True,
                    )
    return rows


def restart_rows():
    """What a restart costs: the coupled seed (a_pivot inputs), 10 s, its native FMU with
    a_pivot_x set to a new value at every point or never, across the points and on them."""
    import tempfile

    from conical_pendulum.builder.fmu import build_fmu

    scene = Scene.uniform(3, coupling=True)
    rows = []
    print("\ncoupled seed, a_pivot_x new at every point or never: n_rhs, accepted steps")
    with tempfile.TemporaryDirectory() as tmp:
        path = build_fmu(scene, Path(tmp) / "ConicalPendulum.fmu", backend="native").path
        for label, interval, steps in (("60 Hz", STEP, 600), ("1 ms", 1e-3, 10_000)):
            for method, solver in (("rk45", 1), ("dop853", 2)):
                for tol in (1e-6, 1e-8, 1e-11):
                    found = {"points": label, "solver": method, "rtol": tol}
                    for across in (1, 0):
                        for push in (None, "a_pivot_x"):
                            key = ("across" if across else "on_points") + ("_changing" if push else "_held")
                            _, states, nfev, _ = fmu_points_run(
                                path, solver, tol, across, interval, steps, ["n_steps"], push
                            )
                            found[f"{key}_nfev"], found[f"{key}_steps"] = nfev, int(states[-1][0])
                    rows.append(found)
                    print(
                        f"  {label:>5} {method:<6} {tol:7.0e}  across: held {found['across_held_nfev']:>7} "
                        f"changing {found['across_changing_nfev']:>7} ({found['across_changing_steps']} steps)  "
                        f"on points: held {found['on_points_held_nfev']:>7} changing "
                        f"{found['on_points_changing_nfev']:>7}",
                        flush=True,
                    )
    return rows


def _added(interval, steps):
    """The communication points as a master reaches them: one addition per step."""
    t = 0.0
    yield t
    for _ in range(steps):
        t += interval
        yield t


def seed_pipeline_rows(times, tolerances, long_horizon):
    """PyDy's own pipeline (Cython RHS from the seed + odeint) on the published model."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # a test reference
    from references.seed_pipeline import seed_right_hand_side

    scene = Scene.uniform(3, kinematics="pydy-example")
    core = load_core(scene)
    p = np.array(scene.parameters())
    x0 = np.array(scene.initial_state())
    rhs = lambda x: core.rhs(x, p)  # noqa: E731
    reference, _ = native(rhs, x0, times, "DOP853", 1e-13)
    ref_outputs = np.array([core.outputs(x, p) for x in reference])
    bob_index = [k for k, v in enumerate(scene.output_names()) if v.startswith("bob")]
    seed_rhs, values = seed_right_hand_side()
    pv = np.array(values)
    rows = []
    for setting, tol in [("defaults (1.49e-8)", None)] + [(f"tol={t:g}", t) for t in tolerances]:
        kwargs = {} if tol is None else {"rtol": tol, "atol": tol}

        def run(grid=times):
            states, info = odeint(seed_rhs, x0, grid, args=(pv,), full_output=True, mxstep=10**7, **kwargs)
            return states, int(info["nfe"][-1])

        seconds, (states, nfev) = median_time(run, 5)
        angle, bob, final = errors(core, p, states, reference, ref_outputs, 3, bob_index)
        drift = (
            energy_drift(core, p, run(np.arange(0.0, long_horizon + 0.5, 1.0))[0])
            if long_horizon
            else float("nan")
        )
        rows.append(
            {
                "scenario": "seed",
                "solver": "PyDy seed pipeline",
                "setting": setting,
                "seconds": seconds,
                "nfev": nfev,
                "angle_error": angle,
                "bob_error": bob,
                "final_error": final,
                "energy_drift_1000s": drift,
            }
        )
        print(
            f"  {'PyDy pipeline':<14} {setting:<20} {seconds * 1e3:9.2f} ms {nfev:>8} rhs  "
            f"angle {angle:8.1e}  bob {bob:8.1e}  final {final:8.1e}  drift {drift:8.1e}  "
            "(published model)",
            flush=True,
        )
    return rows


def fmu_row(scene, core, p, reference, ref_outputs, bob_index):
    """The FMU itself through fmpy at its default settings: the interface included."""
    import tempfile

    import fmpy

    from conical_pendulum.builder.fmu import build_fmu

    with tempfile.TemporaryDirectory() as tmp:
        path = build_fmu(scene, Path(tmp) / "ConicalPendulum.fmu").path
        run = lambda: fmpy.simulate_fmu(str(path), stop_time=10.0, output_interval=STEP)  # noqa: E731
        run()
        seconds, result = median_time(run, 5)
    states = np.column_stack([result[v] for v in scene.state_names()])
    angle, bob, final = errors(core, p, states, reference, ref_outputs, scene.n, bob_index)
    setting = f"default: solver {DEFAULT_SETTINGS['solver']}, tol {DEFAULT_SETTINGS['rtol']:g}"
    print(
        f"  {'FMU via fmpy':<14} {setting:<20} {seconds * 1e3:9.2f} ms {int(result['n_rhs'][-1]):>8} rhs  "
        f"angle {angle:8.1e}  bob {bob:8.1e}  final {final:8.1e}",
        flush=True,
    )
    return {
        "scenario": "seed",
        "solver": "FMU via fmpy",
        "setting": setting,
        "seconds": seconds,
        "nfev": int(result["n_rhs"][-1]),
        "angle_error": angle,
        "bob_error": bob,
        "final_error": final,
        "energy_drift_1000s": float("nan"),
    }


def plot(rows):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    for scenario in sorted({r["scenario"] for r in rows}):
        fig, ax = plt.subplots(figsize=(8, 5.5))
        picked = [r for r in rows if r["scenario"] == scenario]
        for solver in dict.fromkeys(r["solver"] for r in picked):
            points = sorted(
                (r["seconds"], max(r["angle_error"], 1e-16))
                for r in picked
                if r["solver"] == solver and not math.isnan(r["seconds"])
            )
            if not points:
                continue
            xs, ys = zip(*points)
            style = "-o" if solver.startswith("FMU") else "--s"
            ax.loglog(np.array(xs) * 1e3, ys, style, label=solver, markersize=4)
        ax.set_xlabel("wall time [ms] (10 s simulated, 601 outputs)")
        ax.set_ylabel("max angle error over the grid [rad]")
        ax.set_title(f"work-precision, {scenario} scenario")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(RESULTS / f"work_precision_{scenario}.png", dpi=110)
        plt.close(fig)


if __name__ == "__main__":
    main()
