"""The rules for values and the solver settings, written once for every layer.

The scene checks its numbers with them, the native reference its parameters and start
values, and the build writes them into every FMU's C (fmu_config.h: the rules as numbers,
their words), which applies them to every value a host sets or restores; the messages name
the variable, its value and the rule, so a user reads the same sentence wherever a value is
refused. Standard library only; the scene and the build import it, no slave does.
"""

from __future__ import annotations

import math
import numbers
import sys
from dataclasses import dataclass

# The FMU's `solver`, an enumeration: its item's value is its index, solvers.h's CP_RK4..CP_BDF;
# every FMU has all of them, in the compiled core.
SOLVER_TEXTS = {
    "rk4": "RK4 (fixed step)",
    "rk45": "RK45 (Dormand-Prince 5(4))",
    "dop853": "DOP853",
    "radau": "Radau IIA order 5 (implicit, for stiff scenes)",
    "auto": "automatic: DOP853, Radau while the scene is stiff",
    "bdf": "BDF orders 1 to 5 (implicit, for large stiff scenes at loose tolerances)",
}
SOLVERS = tuple(SOLVER_TEXTS)


@dataclass(frozen=True)
class Rule:
    """A finite value's allowed range, as numbers, so that C glue can apply it too."""

    refusal: str  # what a message says when the value breaks the rule
    wanted: str  # what a scene file's field must be
    low: float = -math.inf
    low_open: bool = False  # the value must exceed low, not only reach it
    high: float = math.inf  # the value must stay below high
    whole: bool = False  # the value must be a whole number (a count carried as a Real)
    items: tuple[tuple[str, str], ...] = ()  # an enumeration's (name, description), valued 0, 1, ...
    type_name: str = ""  # the enumeration's type in a model description

    def holds(self, value: float) -> bool:
        return (
            (value > self.low if self.low_open else value >= self.low)
            and value < self.high
            and (not self.whole or float(value).is_integer())
        )


def solver_description(solvers) -> str:
    """The `solver` variable's description in an FMU that has `solvers`."""
    return ", ".join(f"{k} = {SOLVER_TEXTS[name]}" for k, name in enumerate(solvers))


def _choose(solvers):
    return (
        f"choose 0 to {len(solvers) - 1} ("
        + ", ".join(f"{k} = {name}" for k, name in enumerate(solvers))
        + ")"
    )


RULES = {
    "finite": Rule("must be finite", "a finite number"),
    "positive": Rule("must be positive", "a positive finite number", low=0.0, low_open=True),
    "non-negative": Rule("cannot be negative", "a finite number >= 0", low=0.0),
    "count": Rule("must be at least 1", "a whole number >= 1", low=1.0),
    # scipy's floor for rtol (100 machine epsilons), where it warns and raises the value
    "relative-tolerance": Rule(
        f"must be at least {100 * sys.float_info.epsilon:.3g} (100 "
        "machine epsilons): no solver resolves less",
        f"a finite number >= {100 * sys.float_info.epsilon:.3g}",
        low=100 * sys.float_info.epsilon,
    ),
    "solver": Rule(
        _choose(SOLVERS),
        f"a whole number from 0 to {len(SOLVERS) - 1}",
        low=0.0,
        high=len(SOLVERS),
        items=tuple(SOLVER_TEXTS.items()),
        type_name="Solver",
    ),
    "switch": Rule("choose 0 (off) or 1 (on)", "0 or 1", low=0.0, high=2.0),
    "hold-order": Rule(
        "choose 0 (held over the step) or 1 (extrapolated linearly)", "0 or 1", low=0.0, high=2.0
    ),
    "statistic": Rule(
        "must be a whole number >= 0 and < 2**53",
        "a whole number >= 0 and < 2**53",
        low=0.0,
        high=2.0**53,
        whole=True,
    ),
}

# The rule of a variable by its quantity (builder.fmi.variables' records carry both; a variable
# of no link is its own quantity): (rule, what it is).
QUANTITIES = {
    "l": ("positive", "a length"),
    "m": ("positive", "a bob mass"),
    "M": ("positive", "a link mass"),
    "Ixx": ("non-negative", "a moment of inertia"),
    "Iyy": ("non-negative", "a moment of inertia"),
    "Izz": ("non-negative", "a moment of inertia"),
    "c": ("non-negative", "a joint damping coefficient"),
    "EA": ("positive", "a rope's axial stiffness"),
    "zeta_rope": ("non-negative", "a damping ratio"),  # a negative one would feed energy in
    "r": (
        "positive",
        "a rope's reach",
    ),  # its bob's distance from its top  # a negative one would feed energy in
    "rho": ("non-negative", "an air density"),  # the drag's: negative ones would feed energy in
    "C_d": ("non-negative", "a drag coefficient"),
    "A": ("non-negative", "a frontal area"),
    "rtol": ("relative-tolerance", "a relative tolerance"),
    "atol": ("positive", "a tolerance"),
    "max_step": ("non-negative", "the largest internal step"),
    "max_steps": ("count", ""),
    "across_points": ("switch", ""),
    "solver": ("solver", ""),
    "m_cart": ("positive", "a mass"),
    "k_cart": ("non-negative", "a stiffness"),
    "c_cart": ("non-negative", "a damping coefficient"),
    "M_x": ("non-negative", "an apparent mass"),
    "F_x_order": ("hold-order", ""),
    "h": ("non-negative", "the solver's carried step"),
    # what the integration saw of an elastic rope: restored in FMU states, checked there
    "T_rope_peak": ("non-negative", "a tension"),
    "snaps": ("statistic", "a count"),
    "taut": ("switch", ""),  # no variable: what an FMU state carries
}

# The scene's link fields and their rules: those that are parameters follow the parameter's.
LINK_RULES = {
    "length": QUANTITIES["l"][0],
    "mass": QUANTITIES["M"][0],
    "bob_mass": QUANTITIES["m"][0],
    "damping": QUANTITIES["c"][0],
    "bob_drag_coefficient": QUANTITIES["C_d"][0],  # None: a sphere's (scene.Link.drag)
    "bob_area": QUANTITIES["A"][0],
    "radius": "positive",
    "bob_radius": "positive",
}


@dataclass(frozen=True)
class Setting:
    default: float | int
    integer: bool
    description: str
    unit: str | None = None  # SI, as its description writes it


SETTINGS = {
    "rtol": Setting(
        1e-11,
        False,
        "relative tolerance of the adaptive solvers (setupExperiment's tolerance, when given, "
        "replaces its start value, not a value set)",
        "1",
    ),
    "atol": Setting(1e-11, False, "absolute tolerance of the adaptive solvers"),
    "max_step": Setting(
        0.0,
        False,
        "largest internal step [s]; RK4 splits each communication "
        "step into steps of at most this (0: no limit)",
        "s",
    ),
    "solver": Setting(SOLVERS.index("auto"), True, solver_description(SOLVERS)),
    "max_steps": Setting(100_000, True, "most internal steps per do_step: a step needing more is discarded"),
    "across_points": Setting(
        1,
        True,
        "1: the adaptive solvers step across communication points with their own step size and "
        "answer each point from the step's dense output, restarting there only when an input, "
        "state or setting changes; 0: every do_step ends its integration on the point. RK4 "
        "always does",
    ),
}

STATISTICS = {
    "n_rhs": "right-hand side evaluations so far",
    "n_steps": "accepted internal steps so far",
    "n_rejected": "rejected internal steps so far",
    "n_jacobians": "Jacobians the implicit solver evaluated so far (each one complex-step "
    "right-hand side per state)",
    "n_factorizations": "LU factorizations the implicit solver made so far (one real and one "
    "complex a step size)",
}
QUANTITIES.update(dict.fromkeys(STATISTICS, ("statistic", "a count")))  # restored states


# Why a variable cannot be set: the words every FMU's C says (fmu_config.h).
CALCULATED = "{name} is a calculated output: it cannot be set"
FIXED = (
    "{name} cannot be set after initialization (variability fixed); set it before "
    "exitInitializationMode, or instantiate again"
)
TUNABLE = (
    "{name} is a tunable parameter: it may be set in event mode, not in continuous-time mode "
    "(the state cannot change under the host's integrator)"
)


class BadValue(ValueError):
    """A value a variable cannot take; the message names the variable, the value and the rule."""


def rule_of(quantity: str) -> tuple[str, str]:
    """(rule, what a variable is) for its quantity (l for l0, l1, ...); anything unnamed must
    be finite."""
    return QUANTITIES.get(quantity, ("finite", ""))


def satisfies(rule: str, value) -> bool:
    """Whether value is a finite real number that keeps the rule."""
    return (
        not isinstance(value, bool)
        and isinstance(value, numbers.Real)
        and math.isfinite(value)
        and RULES[rule].holds(value)
    )


def check_value(name: str, value, quantity: str | None = None) -> float:
    """value as a float, or BadValue naming the variable, its value and the rule.

    quantity: whose rule applies (a scene scalar's or a record's), when it is not `name`."""
    return check_rule(name, value, *rule_of(quantity or name))


def check_rule(name: str, value, rule: str = "finite", what: str = "") -> float:
    """value as a float, or BadValue naming the variable, its value and the rule (a key of
    RULES; `what` the variable is, for the message): as a variable's record gives them."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise BadValue(f"{name}: expected a number, got {value!r}")
    try:
        number = float(value)
    except OverflowError:  # an int beyond any double
        number = math.inf
    shown = value if isinstance(value, numbers.Integral) else number  # a count reads as one
    if not math.isfinite(number):
        raise BadValue(f"{name} = {shown!r}: must be finite")
    if not RULES[rule].holds(number):
        raise BadValue(f"{name} = {shown!r}: {what + ' ' if what else ''}{RULES[rule].refusal}")
    return number


def check_setting(name: str, value):
    """A solver setting checked as its rule and type say: an int for Integer settings."""
    if SETTINGS[name].integer:
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise BadValue(f"{name}: expected a whole number, got {value!r}")
        check_value(name, value)
        return int(value)
    return check_value(name, value)
