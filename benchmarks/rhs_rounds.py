"""Right-hand sides timed against each other (force_cost.py, hoist_cost.py): each scene's core
at a state off equilibrium with nonzero inputs, and the C loop's seconds per call
(core.seconds_per_call) taken in rounds, every case once a round so that the machine's load
falls on all alike; medians reported."""

import numpy as np

from conical_pendulum import Scene
from conical_pendulum.builder.compiler import load_core


def prepared(scene: Scene, inputs: tuple[float, float]):
    """(core, x, p, number of states) of scene: x its initial state plus 0.1 to 0.3, its
    inputs spread from inputs[0] to inputs[1]."""
    core = load_core(scene)
    x = np.array(scene.initial_state()) + np.linspace(0.1, 0.3, core.NSTATE)
    p = np.array(scene.parameters())
    p[len(scene.parameter_names()) :] = np.linspace(*inputs, len(scene.input_names()))
    return core, x, p, len(scene.state_names())


def rhs_medians(cases: dict, calls: int, repeats: int) -> dict[str, float]:
    """The median seconds per right-hand side of each case (label: prepared(...))."""
    seconds = {label: [] for label in cases}
    for _ in range(repeats):
        for label, (core, x, p, _) in cases.items():
            seconds[label].append(core.seconds_per_call("rhs", x, p, calls))
    return {label: float(np.median(values)) for label, values in seconds.items()}
