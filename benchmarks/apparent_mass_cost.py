"""What the pivot force's split (F_free and the apparent mass M_app) costs per communication step.

    python benchmarks/apparent_mass_cost.py

With coupling, every output evaluation also evaluates the right-hand side, the apparent
mass and the outputs at a_pivot = 0 (runtime/csrc/core/dynamics.c): one more right-hand side
and outputs. Measured in one run, in the compiled core's C loop, for 3 links (expanded
equations) and 20 (recursive): one right-hand side, the outputs of the coupled scene and
of the same chain without coupling, and one 0.01 s communication step (RK45 at the FMU's
default tolerances, outputs included) of the coupled scene; M_app's share of a step is
the difference of the two outputs over the step. Writes benchmarks/results/apparent_mass_cost.csv.
"""

import time

import numpy as np

from conical_pendulum import Scene
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.runtime.rules import SETTINGS
from results_csv import write_rows

STEP = 0.01
STEPS = 500


def median_of(f, repeats=7):
    return float(np.median([f() for _ in range(repeats)]))


def step_seconds(scene: Scene, core) -> tuple[float, float]:
    """Seconds and right-hand sides per communication step along a swinging run."""
    params = np.array(scene.parameters({"a_pivot_x": 0.3}))
    values = np.zeros(len(scene.state_names()) + len(scene.output_names()))
    values[: len(scene.state_names())] = scene.initial_state({"alpha0": 0.6, "delta1": 0.5})
    stepper = core.Stepper(params, values)
    stepper.configure(1, SETTINGS["rtol"].default, SETTINGS["atol"].default, 0.0, 100000)
    start = time.perf_counter()
    for k in range(STEPS):
        if stepper.advance(k * STEP, STEP):
            raise RuntimeError(f"step {k} failed")
    return (time.perf_counter() - start) / STEPS, stepper.nfev / STEPS


def main():
    rows = []
    for n in (3, 20):
        coupled, plain = Scene.uniform(n, coupling=True), Scene.uniform(n)
        core, plain_core = load_core(coupled), load_core(plain)
        x = np.array(coupled.initial_state()) + np.linspace(0.1, 0.3, 4 * n)
        p, p_plain = np.array(coupled.parameters({"a_pivot_x": 0.3})), np.array(plain.parameters())
        calls = 200000 // n
        rhs = median_of(lambda: core.seconds_per_call("rhs", x, p, calls))
        outputs = median_of(lambda: core.seconds_per_call("outputs", x, p, calls))
        plain_outputs = median_of(lambda: plain_core.seconds_per_call("outputs", x, p_plain, calls))
        step, nfev = min(step_seconds(coupled, core) for _ in range(5))
        rows.append(
            {
                "links": n,
                "formulation": "expanded" if n < 6 else "recursive",
                "rhs_us": f"{rhs * 1e6:.3f}",
                "outputs_coupled_us": f"{outputs * 1e6:.3f}",
                "outputs_uncoupled_us": f"{plain_outputs * 1e6:.3f}",
                "step_us": f"{step * 1e6:.2f}",
                "rhs_per_step": f"{nfev:.1f}",
                "apparent_mass_share_of_step": f"{(outputs - plain_outputs) / step:.3f}",
            }
        )
        print(rows[-1])
    print(f"wrote {write_rows('apparent_mass_cost', rows)}")


if __name__ == "__main__":
    main()
