"""The FMU's variables, described once: what every backend and file says about them.

GROUPS is the one ordered list of variable groups, each with its type, causality,
variability and initial; `variables(scene, settings, backend)` makes from it the records
of one FMU, in value-reference order (a variable's value reference is its place in the
list). model.json carries these records to the pythonfmu slave, which registers its
variables from them; the pythonfmu FMU's model description is checked against them and
completed from them (model_description.complete); the native FMU's model descriptions
(builder.fmi.fmi2, builder.fmi.fmi3) and fmu_config.h (builder.fmi.fmu_config) are written from them.
Adding a group of variables is one entry in GROUPS (and the code that computes its values).

A record carries what its variable is as fields (its quantity and link, from the scene's
Scalar; its unit and description, from DESCRIBED by quantity; its FMI 3.0 array and index;
its rule): everything written about it is made from these, nothing parsed from its name.

The statistics' order is runtime.rules.STATISTICS's, which the C indexes by name
(CP_STAT_*, generated into model.h by codegen).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, fields, replace

from ...runtime.rules import RULES, SETTINGS, STATISTICS, rule_of
from ...scene import WORKS, Scalar, Scene
from ..core.dependencies import dependencies

BACKENDS = ("pythonfmu", "native")


@dataclass(frozen=True)
class Variable:
    """One variable of an FMU, as its model description, model.json and fmu_config.h say;
    what it is (its quantity and link, its FMI 3.0 array, unit and rule) are fields, made once
    here and never read back out of its name or description."""

    name: str
    type: str  # "Real" or "Integer"
    causality: str  # FMI 2.0's: parameter, input, output, local
    variability: str  # fixed, tunable, continuous, discrete
    initial: str | None  # exact, calculated, or None (FMI's default for the causality)
    value_reference: int
    start: float | int | None
    rule: str  # runtime.rules.RULES's key: the values it takes
    description: str
    depends_on: tuple[str, ...] = ()  # an unknown's knowns (parameters, inputs, states): ModelStructure
    group: str = ""  # the GROUPS entry it belongs to
    derivative_of: str | None = None  # der(x): the state x
    quantity: str = ""  # what it is whatever its link (l for l0, bob_x for bob2_x): its rule's key
    link: int | None = None  # the link it belongs to, if any
    unit: str | None = None  # SI, as the description writes it (m, rad/s, kg.m2): builder.fmi.units's
    nominal: float | None = None  # a continuous state's scale (FMI's nominal), if it is one
    array: str | None = None  # the FMI 3.0 FMU's array holding it (one element per link), if any
    index: int | None = None  # its 0-based place in that array
    what: str = ""  # what a refusal of a value calls it ("a length"): its rule's words

    def start_text(self) -> str:
        """The start as a model description writes it: a Real with the digits that round-trip."""
        return repr(float(self.start)) if self.type == "Real" else str(self.start)

    def bounds(self) -> dict[str, str]:
        """min and max as a model description declares them, from its rule: FMI's are
        inclusive (min <= value <= max), so an open low end (a "positive" value) declares its
        bound, min = 0, which the FMU still refuses, and an open high end the largest value
        below it; an enumeration's range is its items."""
        rule = RULES[self.rule]
        if rule.items:
            return {}
        whole = self.type == "Integer" or rule.whole
        found = {}
        if math.isfinite(rule.low):
            found["min"] = rule.low
        if math.isfinite(rule.high):
            found["max"] = rule.high - 1 if whole else math.nextafter(rule.high, -math.inf)
        return {
            key: str(int(value)) if self.type == "Integer" else repr(float(value))
            for key, value in found.items()
        }

    def to_dict(self) -> dict:
        data = asdict(self)
        data["depends_on"] = list(self.depends_on)
        return data

    @classmethod
    def from_dict(cls, data: dict) -> Variable:
        """The record model.json holds (to_dict)."""
        known = {field.name for field in fields(cls)}
        return cls(
            **{k: v for k, v in data.items() if k in known} | {"depends_on": tuple(data["depends_on"])}
        )


def records(data: dict) -> list[Variable]:
    """The variables of model.json's data (builder.fmu.model_data, builder.models.cart.cart_data)."""
    return [Variable.from_dict(v) for v in data["variables"]]


@dataclass(frozen=True)
class Member:
    """What a group's function gives per variable; the group gives the rest."""

    scalar: Scalar
    start: float | int | None = None
    description: str = ""
    depends_on: tuple[str, ...] = ()
    derivative_of: str | None = None
    unit: str | None = None
    nominal: float | None = None
    variability: str | None = None  # the group's, unless given (a load's mass: tunable)

    @property
    def name(self) -> str:
        return self.scalar.name


@dataclass(frozen=True)
class Group:
    name: str
    type: str
    causality: str
    variability: str
    initial: str | None
    c_name: str  # fmu_config.h: CP_VR_<c_name> is the group's first value reference
    members: Callable[[Scene, dict], list[Member]]
    backends: tuple[str, ...] = BACKENDS
    named: bool = False  # fmu_config.h also defines CP_VR_<NAME> for each of its variables


@dataclass(frozen=True)
class Described:
    """How the scene's variables of one quantity are described: their unit, and a text with
    the holes {link} (the link, or k for an FMI 3.0 array), {unit} and {of} (the variable
    it is the rate of: `of` of the same link, or that array)."""

    unit: str | None
    text: str
    of: str = ""


def _axes(text: str, unit: str, quantities: dict[str, str]) -> dict[str, Described]:
    return {
        quantity: Described(unit, text.format(axis=axis, unit="{unit}"))
        for quantity, axis in quantities.items()
    }


# What every continuous input of the pendulum does over a communication step
HELD_INPUT = (
    "held over each communication step, or (native FMUs) moving as the derivatives the master sets say"
)

# The scene's quantities: a unit and a description each (the settings and statistics describe
# themselves in runtime.rules).
DESCRIBED = {
    "l": Described("m", "length of link {link} [{unit}]"),
    "m": Described("kg", "mass of bob {link} [{unit}]"),
    "M": Described("kg", "mass of link {link} [{unit}]"),
    "Ixx": Described("kg.m2", "central inertia of link {link} about its x axis [{unit}]"),
    "Iyy": Described("kg.m2", "central inertia of link {link} about its own (y) axis [{unit}]"),
    "Izz": Described("kg.m2", "central inertia of link {link} about its z axis [{unit}]"),
    "alpha": Described("rad", "angle of joint {link} about the parent's z axis [{unit}]"),
    "beta": Described("rad", "angle of joint {link} about the parent's x axis [{unit}]"),
    "omega": Described("rad/s", "{of}' [{unit}]", "alpha"),
    "delta": Described("rad/s", "{of}' [{unit}]", "beta"),
    "g": Described("m/s2", "gravitational acceleration along -Y [{unit}]"),
    "c": Described(
        "N.m.s/rad",
        "viscous damping coefficient of joint {link}: a torque -c w_rel on link {link}, w_rel its "
        "angular velocity relative to its parent (and +c w_rel on the parent) [{unit}]",
    ),
    "C_d": Described(
        "1",
        "drag coefficient of bob {link}: the air drags it by -1/2 rho C_d A |v_air| v_air, v_air its "
        "velocity through the air (0: no drag) [{unit}]",
    ),
    "A": Described("m2", "frontal area of bob {link}, in its air drag [{unit}]"),
    "rho": Described("kg/m3", "density of the air, in the bobs' drag [{unit}]"),
    **_axes(
        "velocity of the air (the wind), inertial {axis} (Y up) [{unit}]; " + HELD_INPUT,
        "m/s",
        {f"wind_{c}": c for c in "xyz"},
    ),
    **_axes(
        "velocity of the pivot (the support), inertial {axis} (Y up) [{unit}], which the bobs' air "
        "drag needs (the chain's own velocities are relative to the pivot), connected with a_pivot; "
        + HELD_INPUT,
        "m/s",
        {f"v_pivot_{c}": c for c in "xyz"},
    ),
    "W_drag": Described(
        "J",
        "work done on the chain by the air's drag on the bobs since the start, with velocities "
        "relative to the pivot (<= 0 in still air and at a fixed pivot); energy minus the W_ outputs' "
        "sum stays constant [{unit}]",
    ),
    "W_damping": Described(
        "J",
        "work done on the chain by the joints' damping since the start (<= 0); energy minus the "
        "W_ outputs' sum stays constant [{unit}]",
    ),
    "W_external": Described(
        "J",
        "work done on the chain by the forces applied to the bobs (F_bob) since the start, with "
        "velocities relative to the pivot; energy minus the W_ outputs' sum stays constant [{unit}]",
    ),
    "W_pivot": Described(
        "J",
        "work done on the chain by the moving pivot since the start: of the inertial force -m a_pivot "
        "on every mass, relative to the pivot as the energy is; energy minus the W_ outputs' sum "
        "stays constant [{unit}]",
    ),
    "W_hoist": Described(
        "J",
        "work done on the chain by the ropes' winches since the start (the sum of the P_hoist outputs' "
        "integrals, and the impulses' work where a v_hoist is set anew); energy minus the W_ outputs' "
        "sum stays constant [{unit}]",
    ),
    "W_load": Described(
        "J",
        "energy the loads' changes of mass gave the chain since the start: at each new value of a "
        "load's mass, the energy's jump at the same state; energy minus the W_ outputs' sum stays "
        "constant [{unit}]",
    ),
    "v_hoist": Described(
        "m/s",
        "speed of rope {link}'s winch: the rate of the rope's length l{link} (> 0 pays out, < 0 hoists) "
        "[{unit}]; held over each communication step in every FMU (the rope's equations take l{link}'' "
        "= 0, so its derivatives must be 0)",
    ),
    "T_rope": Described(
        "N",
        "tension of rope {link}: the force along it that holds what hangs below it (an inextensible "
        "rope cannot push: a negative tension discards the step; an elastic one's follows its law, "
        "EA{link} stretch{link} / l{link} plus its damping while taut, never negative) [{unit}]",
    ),
    "P_hoist": Described(
        "W",
        "power rope {link}'s winch puts into the chain, -T_rope{link} v_hoist{link} (an elastic "
        "rope's with the strain energy its rope paid out carries, -(T_rope{link} + EA{link} "
        "(stretch{link} / l{link})^2 / 2) v_hoist{link} while taut) [{unit}]",
    ),
    "EA": Described(
        "N",
        "axial stiffness of elastic rope {link}, its Young's modulus times its cross-section: its "
        "tension is EA{link} stretch{link} / l{link} while taut [{unit}]",
    ),
    "zeta_rope": Described(
        "1",
        "damping ratio of elastic rope {link}'s stretch with everything hanging from it (1: "
        "critical): its damping force is 2 zeta_rope{link} sqrt(EA{link} / l{link} m) (v_r{link} - "
        "v_hoist{link}), m that mass, while the rope pulls [{unit}]",
    ),
    "r": Described(
        "m",
        "reach of elastic rope {link}: the distance from its top to its bob; stretch{link} = "
        "r{link} - l{link} [{unit}]",
    ),
    "v_r": Described("m/s", "{of}' [{unit}]", "r"),
    "stretch": Described(
        "m",
        "stretch of elastic rope {link}, r{link} - l{link}: > 0 taut, <= 0 slack [{unit}]",
    ),
    "taut_margin": Described(
        "N",
        "taut margin of elastic rope {link}: the tension it would carry if a rope could push, "
        "EA{link} stretch{link} / l{link} plus its damping while the stretch shrinks; > 0 taut, "
        "<= 0 slack. Its zeros are the rope's snap and slack events: Co-Simulation ends an "
        "internal step on them, Model Exchange declares it an event indicator [{unit}]",
    ),
    "T_rope_peak": Described(
        "N",
        "largest tension of elastic rope {link} since the last communication point, found on "
        "the solver's dense output between its steps: the snap load a master sampling T_rope"
        "{link} misses (Model Exchange, which has no steps of its own: T_rope{link} at the last "
        "event) [{unit}]",
    ),
    "snaps": Described(
        "1",
        "times elastic rope {link} went from slack to taut since the start (Co-Simulation: the "
        "located events inside each step; Model Exchange: the events the host handled)",
    ),
    "taut": Described(
        "1",
        "1 while elastic rope {link} is taut (taut_margin{link} > 0), 0 while slack; changes at its events",
    ),
    "W_rope": Described(
        "J",
        "work done on the chain by the elastic ropes' damping since the start (<= 0: with the "
        "strain energy a rope recoiling faster than it can pull loses); energy minus the W_ "
        "outputs' sum stays constant [{unit}]",
    ),
    **_axes(
        "force applied to bob {{link}}, inertial {axis} (Y up) [{unit}]; " + HELD_INPUT,
        "N",
        {f"F_bob_{c}": c for c in "xyz"},
    ),
    "energy": Described(
        "J",
        "total mechanical energy relative to the pivot (kinetic + potential, zero at Y = 0, with "
        "the elastic ropes' strain energy) [{unit}]",
    ),
    **_axes(
        "acceleration of the pivot (the support), inertial {axis} (Y up) [{unit}]; " + HELD_INPUT,
        "m/s2",
        {f"a_pivot_{c}": c for c in "xyz"},
    ),
    **_axes(
        "apparent mass of the chain at the pivot, entry {axis} of the symmetric M_app in F_pivot = "
        "F_free - M_app a_pivot [{unit}]; depends on the state only",
        "kg",
        {f"M_pivot_{ij}": ij for ij in ("xx", "xy", "xz", "yy", "yz", "zz")},
    ),
    **_axes(
        "force the pendulum would exert on a support at rest (a_pivot = 0), inertial {axis} (Y up) "
        "[{unit}]: F_pivot = F_free - M_app a_pivot; depends on the state (and the bobs' applied "
        "forces) only",
        "N",
        {f"F_free_{c}": c for c in "xyz"},
    ),
    **_axes(
        "force the pendulum exerts on its support, inertial {axis} (Y up) [{unit}]; depends at once on "
        "the a_pivot inputs",
        "N",
        {f"F_pivot_{c}": c for c in "xyz"},
    ),
    **_axes(
        "bob {{link}} position relative to the pivot, inertial {axis} (Y up) [{unit}]",
        "m",
        {f"bob_{c}": c for c in "xyz"},
    ),
    **_axes(
        "link {{link}} mass-centre position relative to the pivot, inertial {axis} [{unit}]",
        "m",
        {f"link_{c}": c for c in "xyz"},
    ),
    **{
        f"link_q{c}": Described("1", f"link {{link}} orientation quaternion, {c} component")
        for c in ("w", "x", "y", "z")
    },
}


def per_second(unit: str | None) -> str | None:
    """The unit of a rate of change: m -> m/s, m/s -> m/s2."""
    if unit is None:
        return None
    return unit + ("2" if unit.endswith("/s") else "/s")


def describe(quantity: str, link: int | None = None, every_link: bool = False) -> str:
    """The description of the scene's variable of `quantity` and `link`; every_link: of the
    FMI 3.0 array of that quantity (link k)."""
    if quantity.startswith("der("):
        state = quantity[4:-1]
        return f"time derivative of {state if every_link else Scalar(state, link).name}"
    described = DESCRIBED[quantity]
    of = described.of if every_link else Scalar(described.of, link).name
    return described.text.format(link="k" if every_link else link, unit=described.unit, of=of)


def unit_of(quantity: str) -> str | None:
    """The unit of the scene's variable of `quantity`."""
    if quantity.startswith("der("):
        return per_second(unit_of(quantity[4:-1]))
    return DESCRIBED[quantity].unit


def _described(scalars, starts=None, depends=lambda scalar: ()):
    starts = starts if starts is not None else [None] * len(scalars)
    return [
        Member(s, start, describe(s.quantity, s.link), depends(s), unit=unit_of(s.quantity))
        for s, start in zip(scalars, starts)
    ]


# What a load's mass is besides a bob's
LOAD = (
    "; a load: tunable, set at a communication point (Model Exchange: in event mode) as when the "
    "load is set down, picked up or released, the velocities kept and the energy's jump booked in W_load"
)


def _parameters(scene, settings):
    loads = {f"m{i}" for i in scene.loads()}
    return [
        replace(member, description=member.description + LOAD, variability="tunable")
        if member.name in loads
        else member
        for member in _described(scene.parameter_scalars(), scene.parameter_defaults())
    ]


def _inputs(scene, settings):  # at rest; held over each communication step
    return _described(scene.input_scalars(), [0.0] * len(scene.input_scalars()))


def _states(scene, settings):  # a state is an output of its own value
    return [
        replace(member, nominal=NOMINAL[member.scalar.quantity](scene))
        for member in _described(scene.state_scalars(), scene.state_defaults(), lambda s: (s.name,))
    ]


def _frequency(scene: Scene) -> float:
    """The chain's natural angular frequency, hanging straight at the scene's numbers
    (sqrt(g / total length)): the scale of its rates (1 where g = 0)."""
    return math.sqrt(abs(scene.gravity) / sum(link.length for link in scene.links)) or 1.0


def _rope_length(scene: Scene) -> float:
    """The scale of the ropes' lengths: the longest a rope may be."""
    return max(scene.links[i].rope_max for i in scene.ropes())


def _weight_times_length(scene: Scene) -> float:
    """The scale of the energy's books: the chain's weight lifted by its length (1 where g = 0)."""
    mass = sum(link.bob_mass * link.has_bob + link.mass * link.has_mass for link in scene.links)
    return abs(scene.gravity) * mass * sum(link.length for link in scene.links) or 1.0


# The states' nominal values (FMI's scale, e.g. absoluteTolerance = nominal * tolerance * 0.01):
# an angle's scale is a radian; a rate's, a radian at the chain's natural frequency (one value
# per quantity, so that an FMI 3.0 array has one).
NOMINAL = {
    "alpha": lambda scene: 1.0,
    "beta": lambda scene: 1.0,
    "omega": _frequency,
    "delta": _frequency,
    "l": _rope_length,  # a rope's length, a state
    "r": _rope_length,  # an elastic rope's reach
    "v_r": lambda scene: _rope_length(scene) * _frequency(scene),
    **dict.fromkeys(WORKS, _weight_times_length),
}


def _in_order(scene: Scene, names) -> tuple[str, ...]:
    """The knowns `names` in value-reference order (parameters, inputs, states)."""
    order = scene.core_parameter_names() + scene.state_names()
    return tuple(sorted(names, key=order.index))


def _outputs(scene, settings):  # what each depends on, read from the model (builder.core.dependencies)
    found = dependencies(scene)
    return _described(scene.output_scalars(), None, lambda s: _in_order(scene, found[s.name]))


def _rope_events(scene, settings):  # what the integration saw, not functions of the knowns
    return _described(scene.rope_event_scalars())


def _statistics(scene, settings):  # counts of what the solver did, not functions of the knowns
    return [Member(Scalar(name), None, text, unit="1") for name, text in STATISTICS.items()]


def _settings(integer):
    def members(scene, settings):
        return [
            Member(Scalar(name), settings[name], setting.description, unit=setting.unit)
            for name, setting in SETTINGS.items()
            if setting.integer == integer
        ]

    return members


def _derivatives(scene, settings):  # what each depends on, read from the model (builder.core.dependencies)
    found = dependencies(scene)
    return [
        Member(
            scalar,
            None,
            describe(f"der({s.quantity})", s.link),
            _in_order(scene, found[scalar.name]),
            s.name,
            per_second(unit_of(s.quantity)),
        )
        for s in scene.state_scalars()
        for scalar in [Scalar(f"der({s.stem}", s.link, f"{s.suffix})")]
    ]


# The value-reference order of every FMU: Reals, then Integers, then (native FMU, Model
# Exchange) the state derivatives. The Reals are one array in both FMUs: the core's p
# (parameters, then inputs), its state and outputs, the statistics, what the integration saw
# of the elastic ropes, the real settings.
GROUPS = [
    Group("parameters", "Real", "parameter", "fixed", None, "PARAMETER", _parameters),
    Group("inputs", "Real", "input", "continuous", None, "INPUT", _inputs),
    Group("states", "Real", "output", "continuous", "exact", "STATE", _states),
    Group("outputs", "Real", "output", "continuous", "calculated", "OUTPUT", _outputs),
    Group("statistics", "Real", "output", "discrete", "calculated", "STATISTICS", _statistics),
    Group("rope_events", "Real", "output", "discrete", "calculated", "ROPE_EVENTS", _rope_events),
    Group("real_settings", "Real", "parameter", "fixed", None, "SETTINGS", _settings(False), named=True),
    Group(
        "integer_settings",
        "Integer",
        "parameter",
        "fixed",
        None,
        "INTEGER_SETTINGS",
        _settings(True),
        named=True,
    ),
    Group(
        "derivatives",
        "Real",
        "local",
        "continuous",
        "calculated",
        "DERIVATIVE",
        _derivatives,
        backends=("native",),
    ),
]


def groups(backend: str = "pythonfmu") -> list[Group]:
    """The groups of a backend's FMU, in value-reference order."""
    if backend not in BACKENDS:
        raise ValueError(f"backend: {backend!r} is not one of {BACKENDS}")
    return [group for group in GROUPS if backend in group.backends]


def variables(scene: Scene, settings: dict, backend: str = "pythonfmu") -> list[Variable]:
    """Every variable of the scene's FMU for `backend`, in value-reference order.

    settings: every solver setting's start value (builder.fmu.checked_settings)."""
    return variables_of(groups(backend), scene, settings)


def variables_of(in_order, scene: Scene | None = None, settings: dict | None = None) -> list[Variable]:
    """The variables of groups in_order, in value-reference order (a variable's value
    reference is its place): the pendulum's (variables), or another model's (builder.models.cart).
    The Reals of one quantity in a group with one per link of the scene (each link present)
    are an FMI 3.0 array, element k the link k's."""
    result = []
    for group in in_order:
        members = group.members(scene, settings)
        arrays = _arrays(members, scene) if group.type == "Real" else set()
        for member in members:
            scalar = member.scalar
            rule, what = rule_of(scalar.quantity)
            in_array = scalar.quantity in arrays
            result.append(
                Variable(
                    name=member.name,
                    type=group.type,
                    causality=group.causality,
                    variability=member.variability or group.variability,
                    initial=group.initial,
                    value_reference=len(result),
                    start=member.start,
                    rule=rule,
                    description=member.description,
                    depends_on=member.depends_on,
                    group=group.name,
                    derivative_of=member.derivative_of,
                    quantity=scalar.quantity,
                    link=scalar.link,
                    unit=member.unit,
                    nominal=member.nominal,
                    array=scalar.quantity if in_array else None,
                    index=scalar.link if in_array else None,
                    what=what,
                )
            )
    return result


def _arrays(members: list[Member], scene: Scene | None) -> set[str]:
    """The quantities of members with one member per link of the scene, link by link, all of
    one variability (an array has one: a chain with a load among fixed bobs has none of m)."""
    links: dict[str, list[int]] = {}
    variabilities: dict[str, set] = {}
    for member in members:
        if member.scalar.link is not None:
            links.setdefault(member.scalar.quantity, []).append(member.scalar.link)
            variabilities.setdefault(member.scalar.quantity, set()).add(member.variability)
    every = list(range(scene.n)) if scene is not None else None
    return {
        quantity
        for quantity, found in links.items()
        if sorted(found) == every and len(variabilities[quantity]) == 1
    }


def first_references(records: list[Variable], in_order) -> dict[str, int]:
    """Each group's first value reference (where it would start when empty), by group name;
    records: the variables of the groups in_order (groups(backend), or another model's:
    builder.models.cart)."""
    first, seen = {}, 0
    for group in in_order:
        first[group.name] = seen
        seen += sum(v.group == group.name for v in records)
    return first


@dataclass(frozen=True)
class Unknown:
    """One entry of a ModelStructure list: the variable and the knowns of that list it depends
    on, in value-reference order."""

    variable: Variable
    dependencies: tuple[Variable, ...]


@dataclass(frozen=True)
class Structure:
    """A model description's ModelStructure, written once for every writer (builder.fmi.fmi2,
    builder.fmi.fmi3, model_description.complete), each list in value-reference order and every
    entry with its dependencies written out (FMI reads none as "every known", OMSimulator as
    "nothing"): of the records' depends_on, those that are knowns of that list."""

    outputs: list[Unknown]
    derivatives: list[Unknown]
    initial_unknowns: list[Unknown]


def model_structure(records: list[Variable]) -> Structure:
    """The unknowns of the variables `records`: the outputs, the state derivatives, and those
    of both calculated at initialization. The knowns of the outputs and derivatives are the
    inputs and the continuous states (none where no derivative is exposed: Co-Simulation
    only); at initialization, the inputs, the parameters and whatever starts exactly at its
    start value (the states)."""
    by_name = {v.name: v for v in records}
    states = {v.derivative_of for v in records if v.derivative_of}
    continuous = {v.name for v in records if v.causality == "input" or v.name in states}
    initial = {v.name for v in records if v.causality in ("input", "parameter") or v.initial == "exact"}

    def unknowns(variables, knowns):
        return [
            Unknown(
                v,
                tuple(
                    sorted((by_name[k] for k in v.depends_on if k in knowns), key=lambda k: k.value_reference)
                ),
            )
            for v in variables
        ]

    return Structure(
        unknowns([v for v in records if v.causality == "output"], continuous),
        unknowns([v for v in records if v.derivative_of], continuous),
        unknowns(
            [
                v
                for v in records
                if v.initial in ("approx", "calculated") and (v.causality == "output" or v.derivative_of)
            ],
            initial,
        ),
    )
