"""A link and what it may carry: its fields, the tables a scene file gives them in, and their checks.

A new kind of link, or a new part on one, is added here: its fields on `Link`, its table in
`PARTS` (a scene file's [link.<table>], filling the fields `<table>_<field>`), its check in
`LINK_CHECKS`. The scene's variables follow in variables.py.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from ..runtime.rules import LINK_RULES, QUANTITIES, RULES, satisfies

SPHERE_DRAG = 0.47  # a sphere's drag coefficient at Reynolds numbers 1e3 to 2e5


class SceneError(ValueError):
    """A scene that cannot be built; the message names the field and its value."""


@dataclass(frozen=True)
class Link:
    """One cylindrical link and the bob at its lower end (the seed's numbers by default)."""

    has_mass: bool = True
    has_bob: bool = True
    length: float = 10.0
    mass: float = 10.0
    radius: float = 0.5
    bob_mass: float = 5.0
    bob_radius: float = 1.0
    moments: tuple[float, float, float] | None = None  # (Ixx, Iyy, Izz); None: a cylinder's
    damping: float = 0.0  # joint damping coefficient c (torque -c w_rel), with Scene.joint_damping
    bob_force: bool = False  # an applied force on the bob: inputs F_bob<i>_x/y/z, inertial
    # with Scene.air_drag: the bob's drag coefficient and frontal area (None: a sphere's,
    # SPHERE_DRAG and pi bob_radius^2)
    bob_drag_coefficient: float | None = None
    bob_area: float | None = None
    # a rope: a massless link whose length l<i> is a state driven by a winch (input v_hoist<i>),
    # kept between rope_min and rope_max (a length leaving them discards the step)
    rope: bool = False
    rope_min: float | None = None
    rope_max: float | None = None
    # an elastic rope: its axial stiffness EA [N] (None: inextensible) and the damping ratio of
    # its stretch with everything hanging below it (0 to 1: a fraction of critical damping);
    # its bob's distance r<i> from the rope's top and its rate v_r<i> are states
    rope_stiffness: float | None = None
    rope_damping: float | None = None
    # a load: the bob's mass m<i> may be changed at a communication point (a tunable
    # parameter; a load set down, picked up or released), its energy's jump booked in W_load
    bob_load: bool = False

    def inertia(self) -> tuple[float, float, float]:
        """Central inertia (Ixx, Iyy, Izz): as given, or a solid cylinder along the link's y axis."""
        if self.moments is not None:
            return tuple(float(m) for m in self.moments)
        transverse = self.mass * (3.0 * self.radius**2 + self.length**2) / 12.0
        return transverse, self.mass * self.radius**2, transverse

    def drag(self) -> tuple[float, float]:
        """The bob's drag coefficient and frontal area: as given, or a sphere's."""
        coefficient = SPHERE_DRAG if self.bob_drag_coefficient is None else self.bob_drag_coefficient
        area = math.pi * self.bob_radius**2 if self.bob_area is None else self.bob_area
        return coefficient, area


@dataclass(frozen=True)
class Part:
    """What a link may carry, as a scene file's table [link.<table>]: its presence sets the
    Link's `flag`, each of its fields the Link's `<table>_<field>`."""

    table: str
    flag: str
    fields: tuple[str, ...]
    shape: str  # the table as a message shows it

    def link_field(self, field: str) -> str:
        return f"{self.table}_{field}"


PARTS = {
    part.table: part
    for part in (
        Part(
            "bob",
            "has_bob",
            ("mass", "radius", "force", "drag_coefficient", "area", "load"),
            "{ mass = ..., radius = ... }",
        ),
        Part(
            "rope",
            "rope",
            ("min", "max", "stiffness", "damping"),
            "{ min = ..., max = ... }",  # an elastic one's stiffness and damping are optional
        ),
    )
}
FILE_NAMES = {  # Link fields as a file names them: bob.mass, rope.min
    part.link_field(field): f"{table}.{field}" for table, part in PARTS.items() for field in part.fields
}
MASSLESS_HINT = " (or 0 for a massless link: has_mass=False)"


def given_without(where: str, value, option: str) -> SceneError:
    """A value given for an option the scene does not have."""
    return SceneError(
        f"{where}: {value!r} given, but the scene has no {option.replace('_', ' ')}: set {option} = true"
    )


def _check_values(scene, i: int, link: Link) -> None:
    """The link's numbers by their rules (runtime.rules'), its inertia three of them."""
    for name, rule in LINK_RULES.items():
        value = getattr(link, name)
        if value is not None and not satisfies(rule, value):
            raise SceneError(
                f"link[{i}].{FILE_NAMES.get(name, name)}: must be "
                f"{RULES[rule].wanted}{MASSLESS_HINT if name == 'mass' else ''}, "
                f"got {value!r}"
            )
    if link.moments is not None and not (
        len(link.moments) == 3 and all(satisfies("non-negative", m) for m in link.moments)
    ):
        raise SceneError(
            f"link[{i}].inertia: must be three finite numbers >= 0 (Ixx, Iyy, Izz), got {link.moments!r}"
        )


def _check_options(scene, i: int, link: Link) -> None:
    """A damping or a bob's drag given only with the scene's option that uses it."""
    if not scene.joint_damping and link.damping != 0:
        raise given_without(f"link[{i}].damping", link.damping, "joint_damping")
    if not scene.air_drag:
        for name in ("bob_drag_coefficient", "bob_area"):
            if getattr(link, name) is not None:
                raise given_without(f"link[{i}].{FILE_NAMES[name]}", getattr(link, name), "air_drag")


def _check_bob_flags(scene, i: int, link: Link) -> None:
    """A bob's flags (an applied force, a load): true or false, only on a bob, and in the
    consistent kinematics (a force's book and a load's are states of the energy's)."""
    flags = {  # the file's name: the field, what a bob is for, what needs it, what the published lack
        "force": ("bob_force", "to apply a force to", "applied forces need", "take none"),
        "load": ("bob_load", "to be a load", "loads need", "keep no energy's books"),
    }
    for flag, (name, purpose, needs, lacks) in flags.items():
        where, value = f"link[{i}].bob.{flag}", getattr(link, name)
        if not isinstance(value, bool):
            raise SceneError(f"{where}: expected true or false, got {value!r}")
        if value and not link.has_bob:
            raise SceneError(f"{where}: link {i} has no bob {purpose}")
        if value and scene.kinematics != "consistent":
            raise SceneError(
                f"{where}: {needs} kinematics 'consistent'; the published "
                f"{scene.kinematics!r} equations {lacks}"
            )


def _check_rope(scene, i: int, link: Link) -> None:
    """A rope is a massless link with a range for its length, in the consistent kinematics;
    range fields only with a rope."""
    where = f"link[{i}].rope"
    if not isinstance(link.rope, bool):
        raise SceneError(f"{where}: expected a table {PARTS['rope'].shape}, got {link.rope!r}")
    if not link.rope:
        for name in ("rope_min", "rope_max", "rope_stiffness", "rope_damping"):
            if getattr(link, name) is not None:
                raise SceneError(
                    f"{where}.{name.removeprefix('rope_')}: {getattr(link, name)!r} given, but "
                    f"link {i} is no rope: give it rope = {PARTS['rope'].shape}"
                )
        return
    if link.has_mass:
        raise SceneError(f"{where}: a rope is a massless link; give link {i} mass = 0")
    if scene.kinematics != "consistent":
        raise SceneError(
            f"{where}: ropes need kinematics 'consistent'; the published "
            f"{scene.kinematics!r} equations have fixed lengths"
        )
    low, high = link.rope_min, link.rope_max
    for name, value in (("min", low), ("max", high)):
        if value is None or not satisfies(QUANTITIES["l"][0], value):
            raise SceneError(f"{where}.{name}: must be {RULES[QUANTITIES['l'][0]].wanted}, got {value!r}")
    if not low <= link.length <= high:
        raise SceneError(
            f"{where}: link {i}'s length {link.length!r} m is outside its range [{low!r}, {high!r}] m"
        )
    _check_elastic(where, i, link)


def _check_elastic(where: str, i: int, link: Link) -> None:
    """An elastic rope: a stiffness EA > 0, a damping ratio >= 0 only with it, and a bob at its
    end, whose distance from the rope's top is the rope's state."""
    stiffness, damping = link.rope_stiffness, link.rope_damping
    if stiffness is None:
        if damping is not None:
            raise SceneError(
                f"{where}.damping: {damping!r} given, but rope {i} is inextensible: give it a "
                "stiffness = EA [N] to make it elastic"
            )
        return
    for name, value, quantity in (("stiffness", stiffness, "EA"), ("damping", damping, "zeta_rope")):
        if value is not None and not satisfies(QUANTITIES[quantity][0], value):
            raise SceneError(
                f"{where}.{name}: must be {RULES[QUANTITIES[quantity][0]].wanted}, got {value!r}"
            )
    if not link.has_bob:
        raise SceneError(f"{where}: an elastic rope holds a bob at its end; give link {i} a bob")


# Each link's checks, in order, once the scene's own fields and options are known good
LINK_CHECKS: tuple[Callable[..., None], ...] = (_check_values, _check_options, _check_bob_flags, _check_rope)
