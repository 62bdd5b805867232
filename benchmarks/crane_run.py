"""The crane scene's run: a load hoisted while its trolley travels, in both FMUs.

    python benchmarks/crane_run.py [--out DIR]

Builds scenes/crane.toml (a rope from the trolley to a 150 kg hook, a 2000 kg load slung 4 m
below it, the trolley a moving support) as the pythonfmu FMU and the native FMU (FMI 2.0), and
runs each with fmpy.simulate_fmu for 30 s at 50 Hz with DOP853 at 1e-10, from rest hanging
straight, through a trolley move and a hoist: the trolley accelerates at 0.4 m/s2 for 2.5 s
(to 1 m/s), travels, and brakes at 0.4 m/s2 from 12.5 s to 15 s (a_pivot_x); the winch hoists
at 0.5 m/s from 3 s to 17 s, the rope from 12 m to 5 m (v_hoist0); at 25 s the load is set
down, its mass m1 (a load's, tunable) from 2000 kg to the 20 kg of the sling that stays on the
hook, set at that communication point (fmpy's step_finished). The inputs change at
communication points and are held over each step (fmpy's input table, two rows at each edge).

Prints what the run measured: each FMU's wall time, the two FMUs' largest difference, the
rope's tension (its range until the load is set down, the static weight), the load's largest
swing, the winch's work (W_hoist, with the work of its impulses at its start and stop:
docs/model.md), the energy the load took away (W_load), and energy less the books across the
whole run, the winch's start and stop and the set-down included; writes
benchmarks/results/crane_run.csv and the picture docs/results/crane.png (the load's path seen
from the side, the rope's tension over time).
"""

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
from fmpy import read_model_description

from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.builder.fmu import build_fmu
from conical_pendulum.scene import load_scene
from results_csv import write_rows

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "crane.toml"
PICTURE = ROOT / "docs" / "results" / "crane.png"
STOP, INTERVAL, G = 30.0, 0.02, 9.8
START = {"solver": 2, "rtol": 1e-10, "atol": 1e-10, "alpha0": 0.0, "alpha1": 0.0, "beta0": 0.0, "beta1": 0.0}
# (start, end, value) of each input, 0 elsewhere
SCHEDULE = {
    "a_pivot_x": [(0.0, 2.5, 0.4), (12.5, 15.0, -0.4)],
    "v_hoist0": [(3.0, 17.0, -0.5)],
}


# the load set down: when, and its mass after (the sling's, which stays on the hook)
SET_DOWN, SLING = 25.0, 20.0


def set_down(path):
    """fmpy's step_finished callback: at the communication point SET_DOWN, after its outputs are
    recorded, the load's mass m1 becomes SLING's (a tunable parameter)."""
    vr = next(v.valueReference for v in read_model_description(str(path)).modelVariables if v.name == "m1")

    def finished(t, recorder):
        if abs(t - SET_DOWN) < 0.5 * INTERVAL:
            recorder.fmu.setReal([vr], [SLING])
        return True

    return finished


def inputs():
    """fmpy's input table: piecewise constant, two rows at each edge (the value before it, then
    the value after it)."""

    def value(spans, t, after):
        return next((v for a, b, v in spans if (a <= t < b if after else a < t <= b)), 0.0)

    edges = sorted({0.0, STOP} | {t for spans in SCHEDULE.values() for a, b, _ in spans for t in (a, b)})
    sides = [(0.0, True)] + [(t, side) for t in edges[1:-1] for side in (False, True)] + [(STOP, False)]
    rows = [(t, *(value(spans, t, after) for spans in SCHEDULE.values())) for t, after in sides]
    dtype = [("time", np.float64)] + [(name, np.float64) for name in SCHEDULE]
    return np.array(rows, dtype=dtype)


def trolley(times):
    """The trolley's position: the schedule's a_pivot_x integrated twice."""
    acceleration = np.zeros_like(times)
    for a, b, value in SCHEDULE["a_pivot_x"]:
        acceleration[(times >= a) & (times < b)] = value
    dt = np.diff(times, prepend=times[0])
    velocity = np.cumsum(acceleration * dt)
    return np.cumsum(velocity * dt)


def picture(run, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (side, tension) = plt.subplots(1, 2, figsize=(11, 4.2))
    x_trolley = trolley(run["time"])
    side.plot(x_trolley + run["bob1_x"], run["bob1_y"], label="load")
    side.plot(x_trolley + run["bob0_x"], run["bob0_y"], label="hook", lw=0.8)
    side.plot(x_trolley, np.zeros_like(x_trolley), "k", lw=3, label="trolley")
    side.set(xlabel="x [m]", ylabel="y [m]", title="the load's path, side view", aspect="equal")
    side.legend(loc="lower right")
    loaded = run["time"] <= SET_DOWN
    tension.plot(run["time"][loaded], run["T_rope0"][loaded] / 1e3, label="rope tension T_rope0")
    tension.axhline(2150 * G / 1e3, color="grey", ls=":", label="weight of hook and load")
    tension.set(
        xlabel="t [s]", ylabel="kN", title=f"the rope's tension until the load is set down at {SET_DOWN:g} s"
    )
    length = tension.twinx()
    length.plot(run["time"], run["l0"], color="C2", lw=0.8)
    length.set_ylabel("rope length l0 [m]", color="C2")
    tension.legend(loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, help="where the FMUs go (default: a temporary folder)")
    args = parser.parse_args()
    scene = load_scene(SCENE)
    out = args.out or Path(tempfile.mkdtemp())
    runs, rows = {}, []
    for backend in ("pythonfmu", "native"):
        path = out / f"Crane_{backend}.fmu"
        build_fmu(scene, path, backend=backend)
        begin = time.perf_counter()
        runs[backend] = run_fmu(path, STOP, INTERVAL, START, input=inputs(), step_finished=set_down(path))
        seconds = time.perf_counter() - begin
        run = runs[backend]
        # across the whole run: W_hoist takes the work of the winch's impulses where v_hoist0 is
        # set, W_load the energy's jump where m1 is
        kept = run["energy"] - run["W_hoist"] - run["W_pivot"] - run["W_load"]
        drift = float(np.abs(kept - kept[0]).max())
        loaded, after = run["time"] <= SET_DOWN, run["time"] > SET_DOWN
        swing = np.degrees(
            np.abs(np.arctan2(run["bob1_x"] - run["bob0_x"], run["bob0_y"] - run["bob1_y"]))[loaded].max()
        )
        rows.append(
            {
                "fmu": backend,
                "wall_s": round(seconds, 3),
                "final_l0_m": round(float(run["l0"][-1]), 9),
                "tension_min_kN": round(float(run["T_rope0"][loaded].min()) / 1e3, 3),
                "tension_max_kN": round(float(run["T_rope0"][loaded].max()) / 1e3, 3),
                "tension_set_down_kN": round(float(run["T_rope0"][after].mean()) / 1e3, 3),
                "load_swing_max_deg": round(float(swing), 3),
                "W_hoist_kJ": round(float(run["W_hoist"][-1]) / 1e3, 3),
                "W_load_kJ": round(float(run["W_load"][-1]) / 1e3, 3),
                "books_drift_J": drift,
                "books_drift_relative": drift / float(np.abs(run["energy"]).max()),
            }
        )
        print(", ".join(f"{k} = {v}" for k, v in rows[-1].items()))
    names = [n for n in runs["native"].dtype.names if n != "time"]
    difference = max(np.abs(runs["native"][n] - runs["pythonfmu"][n]).max() for n in names)
    print(f"largest difference between the two FMUs: {difference:.3g}; static weight {2150 * G / 1e3:.3f} kN")
    for row in rows:
        row["fmus_differ_by"] = float(difference)
    write_rows("crane_run", rows)
    picture(runs["native"], PICTURE)
    print(f"wrote {PICTURE}")


if __name__ == "__main__":
    main()
