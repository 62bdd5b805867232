"""Each check of the ropes against what nobody here wrote, and its largest error.

    python benchmarks/rope_checks.py

The checks of tests/test_ropes.py (which hold them to their bounds), measured: the lengthening
pendulum's closed form in Bessel functions (LeCornu 1895; Boas, "The lengthening pendulum"),
sympy's own KanesMethod with the rope's length a function of time, the adiabatic invariant
(amplitude ~ l^(-3/4)) under slow hoisting, energy less the books, and the native FMI 2.0 FMU's
step with the winch's speed given as derivatives against scipy with l'' their rate, and the
crane's load lifted from rest by a winch ramping up, whose rope holds m (g + a). Prints one
line per check and writes benchmarks/results/rope_checks.csv.
"""

import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
import test_ropes as checks
from conical_pendulum.analysis.simulate import simulate
from conical_pendulum.builder.fmu import build_fmu
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


def winch(path):
    """The hoisted FMU's step of 1 s, v_hoist a line and a parabola as derivatives: the states'
    largest error relative to max(|x|, 1) against scipy with l'' its rate, and with l'' left
    out; then energy less the books over 3 s along the parabola, relative to the energy."""
    states = checks.HOISTED.state_names()
    errors = {}
    for order in (1, 2):
        inst = checks.winch_instance(lambda backend: path, order)
        parameters = np.array(inst.get(*checks.HOISTED.parameter_names()))
        start = np.array(inst.get(*states))
        inst.step(1.0)
        got = np.array(inst.get(*states))
        for accelerating in (True, False):
            _, expected, _ = checks.winch_reference(start, parameters, 1.0, order, accelerating)
            error = float((np.abs(got - expected) / np.maximum(np.abs(expected), 1.0)).max())
            errors[order, accelerating] = error
        inst.close()
    errors["books"] = checks.accelerating_winch_books(path)[0]
    return errors


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
        report("sympy KanesMethod, M and F", case, checks.kane_difference(scene), "relative")
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
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "Hoisted.fmu"
        build_fmu(checks.HOISTED, path, backend="native", fmi_version=2)
        errors = winch(path)
        crane = Path(folder) / "Crane.fmu"
        build_fmu(checks.CRANE, crane, backend="native", fmi_version=2)
        ramp, after, _ = checks.winch_ramp(crane)
    lifting = checks.CRANE_MASS * (checks.G + checks.RAMP)
    ramp_error = max(float(np.abs(ramp / lifting - 1).max()), abs(after / (checks.CRANE_MASS * checks.G) - 1))
    for order, shape in ((1, "line"), (2, "parabola")):
        for accelerating, what in ((True, "l'' its rate"), (False, "l'' left out")):
            report(
                "FMU step vs scipy, v_hoist moving, 1 s",
                f"a {shape}, {what}",
                errors[order, accelerating],
                "relative",
            )
    report("energy less the books, winch accelerating", "3 s, 10 -> 7.6 m", errors["books"], "of the energy")
    report("tension m (g + a), winch ramping up", "crane, 0 to 0.5 m/s in 1 s", ramp_error, "relative")
    write_rows("rope_checks", rows)


if __name__ == "__main__":
    main()
