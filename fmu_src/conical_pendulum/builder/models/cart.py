"""The coupled demo's cart, described once: its variables, defaults and native FMU.

A mass on a spring and damper along X that carries the pendulum, whose force on it answers
the cart's acceleration a at once: F_pivot_x = F_free_x - M_pivot_xx a. Its inputs are a
force F_x and the apparent mass M_x of what it carries, and it moves by
(m_cart + M_x) a = F_x - k_cart x - c_cart v; its output `a` is the pendulum's a_pivot_x.
Over a communication step the force is held (F_x_order = 0) or extrapolated linearly
through the last two communication points (1), and the step is solved exactly with the
matrix exponential (runtime/csrc/models/cart_model.c): all the error of the coupled demo is the
coupling's. Its FMU, FMI 2.0 or 3.0, is written by builder.packaging.native's code paths, as the
pendulum's is, and links with the same FMI layers.
"""

from __future__ import annotations

import math
from pathlib import Path

from ...runtime.rules import rule_of
from ...scene import Scalar
from .. import c_literals as c
from ..fmi.contract import NativeModel
from ..fmi.fmu_config import RULE_INDEX
from ..fmi.variables import Group, Member, Variable, per_second, variables_of
from ..packaging.native import write_model_fmu

NAME = "Cart"
DESCRIPTION = (
    "cart on a spring and damper along X carrying an apparent mass M_x; inputs F_x (held or "
    "extrapolated) and M_x (held) over each communication step, or both interpolated from the "
    "derivatives the master sets, solved exactly"
)
# Descriptions with the hole {unit}: UNITS's, the one source of each variable's unit.
PARAMETERS = {
    "m_cart": ("mass of the cart [{unit}]", 100.0),
    "k_cart": ("stiffness of the spring from the ground to the cart [{unit}]", 150.0),
    "c_cart": ("damping from the ground to the cart [{unit}]", 20.0),
}
START = {"x": 1.0, "v": 0.0}  # the cart's state at t = 0 [m, m/s]
STATES = {"x": "position of the cart along X [{unit}]", "v": "velocity of the cart along X [{unit}]"}
UNITS = {
    "m_cart": "kg",
    "k_cart": "N/m",
    "c_cart": "N.s/m",
    "x": "m",
    "v": "m/s",
    "F_x": "N",
    "M_x": "kg",
    "a": "m/s2",
}
# The states' scales (FMI's nominal): the start's distance, and the speed it gives at the
# natural frequency sqrt(k_cart / m_cart) of the default cart.
NOMINAL = {
    "x": abs(START["x"]),
    "v": abs(START["x"]) * math.sqrt(PARAMETERS["k_cart"][1] / PARAMETERS["m_cart"][1]),
}
INPUTS = {
    "F_x": "force on the cart along X [{unit}]: the pendulum's F_pivot_x, or F_free_x with M_x",
    "M_x": "apparent mass along X of what the cart carries [{unit}] (the pendulum's M_pivot_xx), moved "
    "with the cart: (m_cart + M_x) a = F_x - k_cart x - c_cart v; 0 for an explicit exchange; "
    "held over each step, or moving as the derivatives the master sets say",
}
ACCELERATION = (
    "acceleration of the cart along X [{unit}] (the pendulum's a_pivot_x); depends at once on F_x and M_x"
)
F_X_ORDER = (
    "the force over a step: 0 held at its value, 1 extrapolated linearly through the last two "
    "communication points (for F_free_x only: F_pivot_x answers the acceleration and diverges "
    "so); Co-Simulation only"
)
# What a (and so der(v)) depends on: (m_cart + M_x) a = F_x - k_cart x - c_cart v; the cart's
# C is written by hand, so this is declared with it and held to its directional derivatives
# and to differences (tests/test_dependencies.py).
KNOWNS = (*PARAMETERS, *STATES, *INPUTS)


def _members(*members):
    return lambda scene, settings: list(members)


def _member(name, start, text, depends_on=()):
    """A cart variable whose description names its unit (UNITS)."""
    return Member(
        Scalar(name),
        start,
        text.format(unit=UNITS[name]),
        depends_on,
        unit=UNITS[name],
        nominal=NOMINAL.get(name),
    )


# The value-reference order: Reals (parameters, inputs, states, the output), the Integer,
# then the state derivatives (Model Exchange), as the pendulum's groups go.
GROUPS = (
    Group(
        "parameters",
        "Real",
        "parameter",
        "fixed",
        None,
        "PARAMETER",
        _members(*(_member(name, start, text) for name, (text, start) in PARAMETERS.items())),
        named=True,
    ),
    Group(
        "inputs",
        "Real",
        "input",
        "continuous",
        None,
        "INPUT",
        _members(*(_member(name, 0.0, text) for name, text in INPUTS.items())),
        named=True,
    ),
    Group(
        "states",
        "Real",
        "output",
        "continuous",
        "exact",
        "STATE",
        _members(*(_member(name, START[name], text, (name,)) for name, text in STATES.items())),
        named=True,
    ),
    Group(
        "outputs",
        "Real",
        "output",
        "continuous",
        "calculated",
        "OUTPUT",
        _members(_member("a", None, ACCELERATION, KNOWNS)),
        named=True,
    ),
    Group(
        "integer_parameters",
        "Integer",
        "parameter",
        "fixed",
        None,
        "INTEGER_PARAMETER",
        _members(Member(Scalar("F_x_order"), 0, F_X_ORDER)),
        named=True,
    ),
    Group(
        "derivatives",
        "Real",
        "local",
        "continuous",
        "calculated",
        "DERIVATIVE",
        _members(
            Member(Scalar("der(x)"), None, "time derivative of x", ("v",), "x", per_second(UNITS["x"])),
            Member(Scalar("der(v)"), None, "time derivative of v: a", KNOWNS, "v", per_second(UNITS["v"])),
        ),
    ),
)


def _config(data: dict, records: list[Variable]) -> list[str]:
    """The cart's own lines of fmu_config.h: F_x_order's start and rule, the rule a
    tolerance keeps."""
    order = next(v for v in records if v.name == "F_x_order")
    tolerance_rule, tolerance_what = rule_of("atol")
    return [
        c.define("CP_F_X_ORDER_START", order.start),
        c.define("CP_F_X_ORDER_RULE", RULE_INDEX[order.rule]),
        c.define("CP_TOLERANCE_RULE", RULE_INDEX[tolerance_rule]),
        c.define("CP_TOLERANCE_WHAT", c.string(tolerance_what)),
    ]


MODEL = NativeModel(
    NAME,
    ("rules.c", "variable_table.c", "cart_model.c"),
    ("rules.h", "variable_table.h"),
    lambda: list(GROUPS),
    _config,
    0.01,
    (2, 3),
)


def cart_data() -> dict:
    """What the cart's model description and fmu_config.h are written from (and its FMU's
    model.json holds): its variables in value-reference order."""
    return {
        "model": NAME,
        "description": DESCRIPTION,
        "variables": [v.to_dict() for v in variables_of(GROUPS)],
    }


def build_cart(output: Path, platforms: tuple[str, ...] = ("linux64",), fmi_version: int = 2) -> Path:
    """The cart's native FMU (Co-Simulation and Model Exchange) at `output`: FMI 2.0, or FMI 3.0
    (fmi_version=3: its variables all scalars, as in FMI 2.0)."""
    write_model_fmu(MODEL, cart_data(), Path(output), platforms, fmi_version)
    return Path(output)
