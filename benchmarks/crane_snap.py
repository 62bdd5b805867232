"""The elastic crane's run: a load set down, the rope going slack, and the load lifted with a snap.

    python benchmarks/crane_snap.py [--out DIR]

Builds scenes/crane_elastic.toml (the crane of crane.toml on a steel wire rope of EA = 2e7 N, 2 %
damping) as the native FMU (FMI 2.0) and runs it with fmpy.simulate_fmu for 12 s with DOP853 at
1e-10, hanging at rest at the rope's static stretch: at 2 s the load is set down (its mass m1
from 2000 kg to the 20 kg of the sling, set at that communication point by fmpy's
step_finished), and the rope, stretched for 2150 kg and now holding 170, throws the hook up: it
goes slack, and the hook bounces on it; at 7 s the load is lifted again (m1 back to 2000 kg at
the hook's speed), and its weight snaps the rope taut. Twice: read at 1 kHz, and at 50 Hz as a
master would, which samples T_rope0 between the snaps' milliseconds but reads T_rope_peak0, the
largest tension the FMU's steps saw since the last point (located on their dense output).

Prints and writes to benchmarks/results/crane_snap.csv: the tension before, its peak after the
lift (T_rope_peak0 at 50 Hz and at 1 kHz, T_rope0 sampled at 50 Hz and at 1 kHz) against a
suddenly applied weight's from rest (T_hook + 2 m_load g, the undamped spring's), the snaps
(snaps0) and slack time after the set-down, the damping's work and energy less the books;
draws docs/results/crane_snap.png (the tension and the stretch over time).
"""

import argparse
import tempfile
from pathlib import Path

import numpy as np
from fmpy import read_model_description

from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.builder.fmu import build_fmu
from conical_pendulum.scene import load_scene
from elastic_rope import static_reach
from results_csv import write_rows

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "crane_elastic.toml"
PICTURE = ROOT / "docs" / "results" / "crane_snap.png"
STOP, FINE, MASTER, G = 12.0, 0.001, 0.02, 9.8
HOOK, SLING, LOAD = 150.0, 20.0, 2000.0
SET_DOWN, LIFT = 2.0, 7.0


def masses(path, interval):
    """fmpy's step_finished: the load's mass m1 set at SET_DOWN and LIFT, after the point's
    outputs are recorded."""
    vr = next(v.valueReference for v in read_model_description(str(path)).modelVariables if v.name == "m1")

    def finished(t, recorder):
        for when, mass in ((SET_DOWN, SLING), (LIFT, LOAD)):
            if abs(t - when) < 0.5 * interval:
                recorder.fmu.setReal([vr], [mass])
        return True

    return finished


def picture(fine, master, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (tension, stretch) = plt.subplots(2, 1, figsize=(10, 5.6), sharex=True)
    tension.plot(fine["time"], fine["T_rope0"] / 1e3, lw=0.8, label="rope tension T_rope0 (1 kHz)")
    tension.plot(
        master["time"],
        master["T_rope_peak0"] / 1e3,
        ".",
        ms=3,
        color="C3",
        label="T_rope_peak0 read at 50 Hz",
    )
    tension.plot(
        master["time"], master["T_rope0"] / 1e3, ".", ms=2, color="C7", label="T_rope0 read at 50 Hz"
    )
    peak = np.argmax(np.where(master["time"] > LIFT, master["T_rope_peak0"], -np.inf))
    tension.annotate(
        f"snap at the lift: {master['T_rope_peak0'][peak] / 1e3:.1f} kN",
        (master["time"][peak], master["T_rope_peak0"][peak] / 1e3),
        xytext=(10, -4),
        textcoords="offset points",
    )
    tension.axhline((HOOK + LOAD) * G / 1e3, color="grey", ls=":", label="weight of hook and load")
    tension.set(ylabel="kN", title=f"the load set down at {SET_DOWN:g} s and lifted at {LIFT:g} s")
    tension.legend(loc="upper left", fontsize=8)
    stretch.plot(fine["time"], fine["stretch0"] * 1e3, lw=0.8, color="C2")
    stretch.axhline(0.0, color="grey", lw=0.5)
    stretch.set(xlabel="t [s]", ylabel="stretch0 [mm]", title="the rope's stretch (< 0: slack)")
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, help="where the FMU goes (default: a temporary folder)")
    args = parser.parse_args()
    scene = load_scene(SCENE)
    path = (args.out or Path(tempfile.mkdtemp())) / "CraneElastic.fmu"
    build_fmu(scene, path, backend="native")
    start = {"solver": 2, "rtol": 1e-10, "atol": 1e-10, "r0": static_reach(scene, HOOK, LOAD)}
    start |= dict.fromkeys(("alpha0", "alpha1", "beta0", "beta1"), 0.0)
    fine, master = (
        run_fmu(path, STOP, every, start, step_finished=masses(path, every)) for every in (FINE, MASTER)
    )
    t, tension, stretch = fine["time"], fine["T_rope0"], fine["stretch0"]
    down = (t > SET_DOWN) & (t <= LIFT)

    def after_lift(run, name):
        return float(run[name][run["time"] > LIFT].max()) / 1e3

    def snaps(run, since, until):
        count = run["snaps0"]
        return int(count[run["time"] <= until][-1] - count[run["time"] <= since][-1])

    kept = fine["energy"] - sum(fine[name] for name in scene.work_names())
    row = {
        "tension_before_kN": round(float(tension[t <= SET_DOWN].mean()) / 1e3, 4),
        "snaps_after_set_down_1kHz": snaps(fine, SET_DOWN, LIFT),
        "snaps_after_set_down_50Hz": snaps(master, SET_DOWN, LIFT),
        "slack_seconds": round(float(np.count_nonzero(stretch[down] <= 0) * FINE), 3),
        "peak_read_at_50Hz_kN": round(after_lift(master, "T_rope_peak0"), 4),
        "peak_read_at_1kHz_kN": round(after_lift(fine, "T_rope_peak0"), 4),
        "tension_sampled_at_1kHz_max_kN": round(after_lift(fine, "T_rope0"), 4),
        "tension_sampled_at_50Hz_max_kN": round(after_lift(master, "T_rope0"), 4),
        "peak_time_s": round(float(t[t > LIFT][np.argmax(tension[t > LIFT])]), 4),
        "sudden_weight_from_rest_kN": round((HOOK + SLING + 2 * (LOAD - SLING)) * G / 1e3, 4),
        "W_rope_kJ": round(float(fine["W_rope"][-1]) / 1e3, 4),
        "books_drift_relative": float(np.abs(kept - kept[0]).max() / np.abs(fine["energy"]).max()),
    }
    print(", ".join(f"{k} = {v}" for k, v in row.items()))
    write_rows("crane_snap", [row])
    picture(fine, master, PICTURE)
    print(f"wrote {PICTURE}")


if __name__ == "__main__":
    main()
