"""Richardson-extrapolated central differences, (4 D(h) - D(2h)) / 3 = J + O(h^4), for the
FMI 2.0 FMU's directional derivatives (test_directional), and one check that an adjoint
(w^T J) and a directional derivative (J v) are the derivatives of a model's values, for the
model contract (test_adjoint_and_early_return) and the FMI 3.0 FMU (test_fmi3_derivatives)
alike; the value references both kinds of derivative refuse, and the bisection both kinds of
early return use to put a solver's stage on a singularity."""

import itertools

import numpy as np


def richardson(values, point, direction, h=2e-3):
    """The derivative of values(p) at `point` along `direction`."""

    def central(h):
        return (values(point + h * direction) - values(point - h * direction)) / (2 * h)

    return (4 * central(h) - central(2 * h)) / 3


def ridders(values, point, direction, steps=(2e-2, 1e-2, 5e-3, 2e-3, 1e-3)):
    """richardson at the step where it changes least to the next smaller one (Ridders' choice):
    its truncation falls and its rounding grows as the step shrinks, and which wins depends
    on how small a derivative is beside the values it is the difference of."""
    estimates = [richardson(values, point, direction, h) for h in steps]
    changes = [np.abs(a - b).max() for a, b in itertools.pairwise(estimates)]
    return estimates[int(np.argmin(changes))]


def assert_adjoint_and_directional_match_differences(values, adjoint, directional, point, n_unknowns):
    """adjoint(w) and directional(v), asked at `point` before any difference moves it, against
    the differences of values(p) (which sets p), for a random seed w and direction v: within
    1e-8 of the largest entry (fmi2's test bound)."""
    rng = np.random.default_rng(8)
    w, v = rng.standard_normal(n_unknowns), rng.standard_normal(len(point))
    sensitivity, along = adjoint(w), directional(v)
    differences = np.array([w @ richardson(values, point, e) for e in np.eye(len(point))])
    assert np.abs(sensitivity - differences).max() < 1e-8 * np.abs(sensitivity).max()
    assert np.abs(along - richardson(values, point, v)).max() < 1e-8 * np.abs(along).max()


def bad_reference_cases(vr: dict, der: int) -> list:
    """(unknowns, knowns, seed, message) that a directional or adjoint derivative refuses, by
    the variables' value references vr and a state derivative's der: a parameter or a setting
    as an unknown, an output as a known, value references of no variable."""
    unknown, known = (
        ": only outputs and state derivatives are",
        ": only states, inputs and Real parameters are",
    )
    return [
        ([vr["l0"]], [vr["alpha0"]], [1.0], f"value reference {vr['l0']} (l0) as an unknown{unknown}"),
        ([vr["rtol"]], [vr["alpha0"]], [1.0], f"value reference {vr['rtol']} (rtol) as an unknown{unknown}"),
        ([der], [vr["energy"]], [1.0], f"value reference {vr['energy']} (energy) as a known{known}"),
        ([der], [vr["bob2_x"]], [1.0], f"value reference {vr['bob2_x']} (bob2_x) as a known{known}"),
        ([10_000], [vr["alpha0"]], [1.0], f"value reference 10000 (?) as an unknown{unknown}"),
        ([der], [10_000], [1.0], f"value reference 10000 (?) as a known{known}"),
    ]


def bisection(miss, low: float, high: float, halvings: int = 60) -> float:
    """The low end of [low, high] narrowed by halvings around the sign change of miss, which
    must be negative at low and positive at high."""
    assert miss(low) < 0 < miss(high)
    for _ in range(halvings):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if miss(middle) < 0 else (low, middle)
    return low
