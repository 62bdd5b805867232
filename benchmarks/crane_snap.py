"""The elastic crane's run: a load set down, the rope going slack, and the load lifted with a snap.

    python benchmarks/crane_snap.py [--out DIR]

Builds scenes/crane_elastic.toml (the crane of crane.toml on a steel wire rope of EA = 2e7 N, 2 %
damping) as the native FMU (FMI 2.0) and runs it with fmpy.simulate_fmu for 12 s at 1 kHz with
DOP853 at 1e-10, hanging at rest at the rope's static stretch: at 2 s the load is set down (its
mass m1 from 2000 kg to the 20 kg of the sling, set at that communication point by fmpy's
step_finished), and the rope, stretched for 2150 kg and now holding 170, throws the hook up: it
goes slack, and the hook bounces on it; at 7 s the load is lifted again (m1 back to 2000 kg at
the hook's speed), and its weight snaps the rope taut. The outputs are sampled every 1 ms: no
output of the FMU yet holds the largest tension between communication points.

Prints and writes to benchmarks/results/crane_snap.csv: the tension before, its peak after the
lift against a suddenly applied weight's m g (1 + ...) from rest (T_hook + 2 m_load g, the
undamped spring's), the slack phases after the set-down, the damping's work and energy less the
books; draws docs/results/crane_snap.png (the tension and the stretch over time).
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
STOP, INTERVAL, G = 12.0, 0.001, 9.8
HOOK, SLING, LOAD = 150.0, 20.0, 2000.0
SET_DOWN, LIFT = 2.0, 7.0


def masses(path):
    """fmpy's step_finished: the load's mass m1 set at SET_DOWN and LIFT, after the point's
    outputs are recorded."""
    vr = next(v.valueReference for v in read_model_description(str(path)).modelVariables if v.name == "m1")

    def finished(t, recorder):
        for when, mass in ((SET_DOWN, SLING), (LIFT, LOAD)):
            if abs(t - when) < 0.5 * INTERVAL:
                recorder.fmu.setReal([vr], [mass])
        return True

    return finished


def picture(run, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (tension, stretch) = plt.subplots(2, 1, figsize=(10, 5.6), sharex=True)
    tension.plot(run["time"], run["T_rope0"] / 1e3, lw=0.8, label="rope tension T_rope0")
    peak = np.argmax(np.where(run["time"] > LIFT, run["T_rope0"], -np.inf))
    tension.plot(run["time"][peak], run["T_rope0"][peak] / 1e3, "o", color="C3")
    tension.annotate(
        f"snap at the lift: {run['T_rope0'][peak] / 1e3:.1f} kN",
        (run["time"][peak], run["T_rope0"][peak] / 1e3),
        xytext=(10, -4),
        textcoords="offset points",
    )
    tension.axhline((HOOK + LOAD) * G / 1e3, color="grey", ls=":", label="weight of hook and load")
    tension.set(ylabel="kN", title=f"the load set down at {SET_DOWN:g} s and lifted at {LIFT:g} s")
    tension.legend(loc="upper left")
    stretch.plot(run["time"], run["stretch0"] * 1e3, lw=0.8, color="C2")
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
    run = run_fmu(path, STOP, INTERVAL, start, step_finished=masses(path))
    t, tension, stretch = run["time"], run["T_rope0"], run["stretch0"]
    down, lifted = (t > SET_DOWN) & (t <= LIFT), t > LIFT
    slack = stretch[down] <= 0
    kept = run["energy"] - sum(run[name] for name in scene.work_names())
    row = {
        "tension_before_kN": round(float(tension[t <= SET_DOWN].mean()) / 1e3, 4),
        "slack_phases_after_set_down": int(np.count_nonzero(np.diff(slack.astype(int)) == 1) + slack[0]),
        "slack_seconds": round(float(np.count_nonzero(slack) * INTERVAL), 3),
        "peak_after_lift_kN": round(float(tension[lifted].max()) / 1e3, 4),
        "peak_time_s": round(float(t[lifted][np.argmax(tension[lifted])]), 4),
        "sudden_weight_from_rest_kN": round((HOOK + SLING + 2 * (LOAD - SLING)) * G / 1e3, 4),
        "W_rope_kJ": round(float(run["W_rope"][-1]) / 1e3, 4),
        "books_drift_relative": float(np.abs(kept - kept[0]).max() / np.abs(run["energy"]).max()),
    }
    print(", ".join(f"{k} = {v}" for k, v in row.items()))
    write_rows("crane_snap", [row])
    picture(run, PICTURE)
    print(f"wrote {PICTURE}")


if __name__ == "__main__":
    main()
