"""The FMU's variables, described once: what every backend and file says about them.

GROUPS is the one ordered list of variable groups, each with its type, causality,
variability and initial; `variables(scene, settings, backend)` makes from it the records
of one FMU, in value-reference order (a variable's value reference is its place in the
list). model.json carries these records to the pythonfmu slave, which registers its
variables from them; the pythonfmu FMU's model description is checked against them and
completed from them (model_description.complete); the native FMU's model description and
fmu_config.h are written from them (native.py). Adding a group of variables is one
entry in GROUPS (and the code that computes its values).

The statistics' order is runtime.rules.STATISTICS's, which the C indexes by name
(CP_STAT_*, generated into model.h by codegen).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass

from ..runtime.rules import SETTINGS, STATISTICS, rule_of
from ..scene import PIVOT_OUTPUTS, Scene
from .model_description import describe

BACKENDS = ("pythonfmu", "native")


@dataclass(frozen=True)
class Variable:
    """One variable of an FMU, as its model description, model.json and fmu_config.h say."""

    name: str
    type: str  # "Real" or "Integer"
    causality: str  # FMI 2.0's: parameter, input, output, local
    variability: str  # fixed, continuous, discrete
    initial: str | None  # exact, calculated, or None (FMI's default for the causality)
    value_reference: int
    start: float | int | None
    rule: str  # runtime.rules.RULES's key: the values it takes
    description: str
    depends_on: tuple[str, ...] = ()  # an unknown's dependencies on knowns (ModelStructure)
    group: str = ""  # the GROUPS entry it belongs to
    derivative_of: str | None = None  # der(x): the state x

    def to_dict(self) -> dict:
        data = asdict(self)
        data["depends_on"] = list(self.depends_on)
        return data


@dataclass(frozen=True)
class Member:
    """What a group's function gives per variable; the group gives the rest."""

    name: str
    start: float | int | None = None
    description: str = ""
    depends_on: tuple[str, ...] = ()
    derivative_of: str | None = None


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


def _described(names, starts=None):
    starts = starts if starts is not None else [None] * len(names)
    return [Member(name, start, describe(name)) for name, start in zip(names, starts)]


def _parameters(scene, settings):
    return _described(scene.parameter_names(), scene.parameter_defaults())


def _inputs(scene, settings):  # at rest; held over each communication step
    return _described(scene.input_names(), [0.0] * len(scene.input_names()))


def _states(scene, settings):  # a state is an output of its own value
    return [
        Member(name, start, describe(name), (name,))
        for name, start in zip(scene.state_names(), scene.state_defaults())
    ]


def _outputs(scene, settings):  # functions of the state; the pivot force of the inputs too
    states, inputs = tuple(scene.state_names()), tuple(scene.input_names())
    return [
        Member(name, None, describe(name), states + (inputs if name in PIVOT_OUTPUTS else ()))
        for name in scene.output_names()
    ]


def _statistics(scene, settings):  # counts of what the solver did, not functions of the knowns
    return [Member(name, None, text) for name, text in STATISTICS.items()]


def _settings(integer):
    def members(scene, settings):
        return [
            Member(name, settings[name], setting.description)
            for name, setting in SETTINGS.items()
            if setting.integer == integer
        ]

    return members


def _derivatives(scene, settings):  # x = (angles, rates): an angle's derivative is its rate
    states, inputs = scene.state_names(), tuple(scene.input_names())
    n_dof = len(states) // 2
    return [
        Member(
            f"der({name})",
            None,
            f"time derivative of {name}",
            (states[n_dof + k],) if k < n_dof else tuple(states) + inputs,
            name,
        )
        for k, name in enumerate(states)
    ]


# The value-reference order of every FMU: Reals, then Integers, then (native FMU, Model
# Exchange) the state derivatives. The Reals are one array in both FMUs: the core's p
# (parameters, then inputs), its state and outputs, the statistics, the real settings.
GROUPS = [
    Group("parameters", "Real", "parameter", "fixed", None, "PARAMETER", _parameters),
    Group("inputs", "Real", "input", "continuous", None, "INPUT", _inputs),
    Group("states", "Real", "output", "continuous", "exact", "STATE", _states),
    Group("outputs", "Real", "output", "continuous", "calculated", "OUTPUT", _outputs),
    Group("statistics", "Real", "output", "discrete", "calculated", "STATISTICS", _statistics),
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
    reference is its place): the pendulum's (variables), or another model's (builder.cart)."""
    records = []
    for group in in_order:
        for member in group.members(scene, settings):
            records.append(
                Variable(
                    name=member.name,
                    type=group.type,
                    causality=group.causality,
                    variability=group.variability,
                    initial=group.initial,
                    value_reference=len(records),
                    start=member.start,
                    rule=rule_of(member.name)[0],
                    description=member.description,
                    depends_on=member.depends_on,
                    group=group.name,
                    derivative_of=member.derivative_of,
                )
            )
    return records


def first_references(records: list[dict], in_order) -> dict[str, int]:
    """Each group's first value reference (where it would start when empty), by group name;
    records: the variables as dicts (Variable.to_dict, model.json) of the groups in_order
    (groups(backend), or another model's: builder.cart)."""
    first, seen = {}, 0
    for group in in_order:
        first[group.name] = seen
        seen += sum(v["group"] == group.name for v in records)
    return first
