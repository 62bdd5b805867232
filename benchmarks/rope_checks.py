"""Each check of the ropes against what nobody here wrote, and its largest error.

    python benchmarks/rope_checks.py

The checks of tests/test_ropes.py (which hold them to their bounds), measured: the lengthening
pendulum's closed form in Bessel functions (LeCornu 1895; Boas, "The lengthening pendulum"),
sympy's own KanesMethod with the rope's length a function of time, the adiabatic invariant
(amplitude ~ l^(-3/4)) under slow hoisting, and energy less the books. Prints one line per
check and writes benchmarks/results/rope_checks.csv.
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
import test_ropes as checks
from conical_pendulum.analysis.simulate import simulate
from results_csv import write_rows


def bessel(l0, v):
    times = np.arange(1201) / 60.0
    run = simulate(
        checks.LOAD,
        times,
        parameters={"v_hoist0": v, "g": checks.G},
        state={"alpha0": 0.0, "beta0": 1e-3, "omega0": 0.0, "delta0": 2e-4, "l0": l0},
        rtol=1e-13,
        atol=1e-15,
    )
    closed = checks.lengthening(l0, v, 1e-3, 2e-4, times)
    return float(np.abs(run["beta0"] - closed).max())


def kane(scene):
    (mass, forcing), (kane_mass, kane_forcing) = checks.sympy_functions(scene)
    rng = np.random.default_rng(41)
    worst = 0.0
    for _ in range(20):
        x = rng.uniform(-1.5, 1.5, 4 * scene.n + len(scene.ropes()))
        x[4 * scene.n :] = rng.uniform(1.0, 20.0, len(scene.ropes()))
        p = rng.uniform(0.5, 4.0, len(scene.core_parameter_names()))
        p[len(scene.parameter_names()) :] = rng.uniform(-3.0, 3.0, len(scene.input_names()))
        for ours, theirs in ((mass, kane_mass), (forcing, kane_forcing)):
            a, b = np.asarray(ours(x, p), float), np.asarray(theirs(x, p), float)
            worst = max(worst, float(np.abs(a - b).max() / np.abs(a).max()))
    return worst


def books():
    inputs = {"v_hoist0": -0.4, "a_pivot_x": 0.6, "v_pivot_x": 0.2, "wind_x": 3.0, "F_bob0_z": 40.0}
    run = simulate(
        checks.SLUNG,
        np.linspace(0, 10, 201),
        parameters=inputs,
        state={"beta0": 0.2, "alpha1": 0.3, "omega2": 0.2},
        rtol=1e-12,
        atol=1e-12,
    )
    kept = run["energy"] - sum(run[name] for name in checks.SLUNG.work_names())
    return float(np.abs(kept - kept[0]).max() / np.abs(run["energy"]).max())


def main():
    rows = []

    def report(check, case, error, unit):
        rows.append({"check": check, "case": case, "largest_error": f"{error:.3g}", "unit": unit})
        print(f"{check:<42} {case:<28} {error:.3g} {unit}")

    for case, (l0, v) in {"lengthening 5 -> 9 m": (5.0, 0.2), "shortening 9 -> 5 m": (9.0, -0.2)}.items():
        report("Bessel closed form, 20 s at 60 Hz", case, bessel(l0, v), "rad")
    scenes = {
        "rope and load": checks.LOAD,
        "rope below a link, coupled": checks.Scene(
            links=(checks.Link(length=2.0), checks.rope(length=6.0)), coupling=True
        ),
        "slung, damped, dragged, forced": checks.Scene(
            links=checks.SLUNG.links[:2], joint_damping=True, air_drag=True, coupling=True
        ),
    }
    for case, scene in scenes.items():
        report("sympy KanesMethod, M and F", case, kane(scene), "relative")
    for l0, direction, what in ((5.0, 1.0, "lengthening"), (20.0, -1.0, "shortening")):
        for speed in (0.04, 0.02):
            amplitude, predicted = checks.swing_amplitude(l0, direction * speed, 15.0 / speed)
            report(
                "adiabatic invariant, amplitude ~ l^-3/4",
                f"{what} at {speed} m/s",
                float(np.abs(amplitude / predicted - 1).max()),
                "relative",
            )
    report("energy less the books, 10 s", "slung, every force, hoisted", books(), "of the energy")
    write_rows("rope_checks", rows)


if __name__ == "__main__":
    main()
