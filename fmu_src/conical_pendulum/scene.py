"""What a user wants simulated: links, bobs, outputs, kinematics, the forces on the chain.

The scene is the single input of the build pipeline. Its structure (which bodies
exist, which outputs are wanted, which kinematics, which forces) decides the generated
code; its numbers (lengths, masses, radii, damping, drag) are only start values of FMU parameters.
This module imports no sympy: the FMU and the native simulation use it too. Its value
rules are runtime.rules', the same the FMU applies.
"""

from __future__ import annotations

import hashlib
import json
import math
import tomllib
from dataclasses import asdict, dataclass, field
from pathlib import Path

from .runtime.rules import LINK_RULES, QUANTITIES, RULES, satisfies

KINEMATICS = ("consistent", "pydy-example")
OUTPUT_GROUPS = ("bobs", "poses", "energy")
PIVOT_INPUTS = ("a_pivot_x", "a_pivot_y", "a_pivot_z")
# With coupling and air drag: the support's inertial velocity, which the bobs' drag needs
# (the chain's own velocities are relative to the pivot)
PIVOT_VELOCITY = ("v_pivot_x", "v_pivot_y", "v_pivot_z")
WIND = ("wind_x", "wind_y", "wind_z")  # the air's inertial velocity, with air drag
PIVOT_OUTPUTS = ("F_pivot_x", "F_pivot_y", "F_pivot_z")
# The pivot force split by its dependence on the support's acceleration, F_pivot = F_free -
# M_app a_pivot: the force at a_pivot = 0, and the chain's apparent mass (its upper triangle).
FREE_FORCE = ("F_free_x", "F_free_y", "F_free_z")
APPARENT_MASS = ("M_pivot_xx", "M_pivot_xy", "M_pivot_xz", "M_pivot_yy", "M_pivot_yz", "M_pivot_zz")
# The energy's books: states with the work of each non-conservative force since the start
# (the joints' damping, the air's drag on the bobs, the bobs' applied forces, the moving
# pivot's inertial force, the winches of the ropes), and the energy that changes of the loads'
# masses took or gave
WORKS = ("W_damping", "W_drag", "W_external", "W_pivot", "W_hoist", "W_load")
# A rope's: its tension [N] and its winch's power [W] (-tension * v_hoist)
ROPE_OUTPUTS = ("T_rope", "P_hoist")
FORMULATIONS = ("auto", "expanded", "recursive")
MAX_LINKS = 100
MAX_EXPANDED_LINKS = 20  # the expanded equations' C grows like n^3: minutes to compile at 20
MAX_PUBLISHED_LINKS = 4  # the published derivation grows exponentially with n
RECURSIVE_FROM = 6  # "auto": links from which the recursive formulation is the faster
SEED_ANGLE = math.radians(10.0)
AIR_DENSITY = 1.225  # kg/m3: the ISA's at sea level
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
class Scalar:
    """One scalar of the scene, by its structure: a quantity (stem + suffix: l, alpha, bob_x,
    g, a_pivot_x) of one link or of none. Its name is made from these, never read back."""

    stem: str
    link: int | None = None
    suffix: str = ""

    @property
    def quantity(self) -> str:
        """What the scalar is, whatever its link: its rule's and its FMI 3.0 array's key."""
        return self.stem + self.suffix

    @property
    def name(self) -> str:
        """The FMU's name of it: l0, bob2_x, der(alpha1), g."""
        return self.stem + ("" if self.link is None else str(self.link)) + self.suffix


def _names(scalars: list[Scalar]) -> list[str]:
    return [scalar.name for scalar in scalars]


@dataclass(frozen=True)
class Scene:
    links: tuple[Link, ...] = field(default_factory=lambda: (Link(),) * 3)
    outputs: tuple[str, ...] = OUTPUT_GROUPS
    kinematics: str = "consistent"
    gravity: float = 9.8
    coupling: bool = False  # pivot acceleration inputs and pivot force outputs
    formulation: str = "auto"  # "expanded" equations, "recursive" loops, or by the number of links
    joint_damping: bool = False  # a viscous torque -c w_rel at each joint, c per joint a parameter
    # quadratic drag on every bob, -1/2 rho C_d A |v - w| (v - w) with the wind w an input
    air_drag: bool = False
    air_density: float = AIR_DENSITY  # rho's start value, with air_drag

    def __post_init__(self):
        unknown = [g for g in self.outputs if g not in OUTPUT_GROUPS]
        if unknown:
            raise SceneError(f"outputs: unknown group(s) {unknown}; choose from {list(OUTPUT_GROUPS)}")
        object.__setattr__(self, "links", tuple(self.links))
        object.__setattr__(self, "outputs", tuple(g for g in OUTPUT_GROUPS if g in self.outputs))
        self.validate()

    @classmethod
    def uniform(
        cls,
        n_links: int = 3,
        *,
        massless_links: bool = False,
        bobs: bool = True,
        damping: float | None = None,
        **kwargs,
    ) -> Scene:
        """The seed's chain generalized to n identical links; damping: each joint's
        coefficient, with joint_damping."""
        if isinstance(n_links, bool) or not isinstance(n_links, int):
            raise SceneError(f"links: expected a whole number of links, got {n_links!r}")
        if not 1 <= n_links <= MAX_LINKS:
            raise SceneError(f"links: {n_links} is out of range; a chain has 1 to {MAX_LINKS} links")
        link = Link(has_mass=not massless_links, has_bob=bobs, damping=damping or 0.0)
        if damping is not None:
            kwargs["joint_damping"] = True
        return cls(links=(link,) * n_links, **kwargs)

    @property
    def n(self) -> int:
        return len(self.links)

    def validate(self) -> None:
        if not 1 <= self.n <= MAX_LINKS:
            raise SceneError(f"links: a chain has 1 to {MAX_LINKS} links, got {self.n}")
        if self.kinematics not in KINEMATICS:
            raise SceneError(f"kinematics: {self.kinematics!r} is not one of {KINEMATICS}")
        if self.formulation not in FORMULATIONS:
            raise SceneError(f"formulation: {self.formulation!r} is not one of {FORMULATIONS}")
        if self.formulation == "recursive" and self.kinematics != "consistent":
            raise SceneError(
                "formulation: 'recursive' needs kinematics 'consistent'; the published "
                "equations exist only expanded"
            )
        if self.resolved_formulation() == "expanded" and self.n > MAX_EXPANDED_LINKS:
            raise SceneError(
                f"links: {self.n} with formulation 'expanded'; its equations are offered "
                f"up to {MAX_EXPANDED_LINKS} links (their C grows like n^3): use "
                "'recursive' or 'auto'"
            )
        if self.kinematics == "pydy-example" and self.n > MAX_PUBLISHED_LINKS:
            raise SceneError(
                f"links: {self.n} with kinematics 'pydy-example'; the published derivation is "
                f"only reproduced up to {MAX_PUBLISHED_LINKS} links (its size grows exponentially)"
            )
        for i, link in enumerate(self.links):
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
                    f"link[{i}].inertia: must be three finite numbers >= 0 "
                    f"(Ixx, Iyy, Izz), got {link.moments!r}"
                )
        self._validate_option("coupling", "the pivot's inputs and force need", "have no moving support")
        self._validate_option(
            "joint_damping", "the joints' damping needs", "have no relative angular velocity to damp"
        )
        if not self.joint_damping:
            for i, link in enumerate(self.links):
                if link.damping != 0:
                    raise _given_without(f"link[{i}].damping", link.damping, "joint_damping")
        self._validate_drag()
        self._validate_bob_flags()
        self._validate_ropes()
        if not math.isfinite(self.gravity):
            raise SceneError(f"gravity: must be finite, got {self.gravity!r}")
        # A joint whose angles move no mass has an undetermined acceleration.
        for i in range(self.n):
            if not any(link.has_mass or link.has_bob for link in self.links[i:]):
                if i == 0:
                    raise SceneError("scene has no mass: give at least one link mass or a bob")
                raise SceneError(
                    f"links {i}..{self.n - 1} carry no mass (no link mass, no bob): their angles "
                    "would be undetermined; give one of them mass or a bob, or drop them"
                )

    def _validate_option(self, name: str, what_needs: str, published_lacks: str) -> None:
        """A scene option: true or false, and only with the consistent kinematics."""
        value = getattr(self, name)
        if not isinstance(value, bool):
            raise SceneError(f"{name}: expected true or false, got {value!r}")
        if value and self.kinematics != "consistent":
            raise SceneError(
                f"{name}: {what_needs} kinematics 'consistent'; the published "
                f"{self.kinematics!r} equations {published_lacks}"
            )

    def _validate_drag(self) -> None:
        self._validate_option("air_drag", "the bobs' drag needs", "take no forces")
        if not satisfies(QUANTITIES["rho"][0], self.air_density):
            raise SceneError(
                f"air_density: must be {RULES[QUANTITIES['rho'][0]].wanted}, got {self.air_density!r}"
            )
        if self.air_drag and not self.dragged_bobs():
            raise SceneError("air_drag: the scene has no bob for the air to drag")
        if self.air_drag:
            return
        if self.air_density != AIR_DENSITY:
            raise _given_without("air_density", self.air_density, "air_drag")
        for i, link in enumerate(self.links):
            for name in ("bob_drag_coefficient", "bob_area"):
                if getattr(link, name) is not None:
                    raise _given_without(f"link[{i}].{FILE_NAMES[name]}", getattr(link, name), "air_drag")

    def _validate_ropes(self) -> None:
        """A rope is a massless link with a range for its length, in the consistent kinematics;
        range fields only with a rope."""
        for i, link in enumerate(self.links):
            where = f"link[{i}].rope"
            if not isinstance(link.rope, bool):
                raise SceneError(f"{where}: expected a table {{ min = ..., max = ... }}, got {link.rope!r}")
            if not link.rope:
                for name in ("rope_min", "rope_max"):
                    if getattr(link, name) is not None:
                        raise SceneError(
                            f"{where}.{name.removeprefix('rope_')}: {getattr(link, name)!r} given, but "
                            f"link {i} is no rope: give it rope = {{ min = ..., max = ... }}"
                        )
                continue
            if link.has_mass:
                raise SceneError(f"{where}: a rope is a massless link; give link {i} mass = 0")
            if self.kinematics != "consistent":
                raise SceneError(
                    f"{where}: ropes need kinematics 'consistent'; the published "
                    f"{self.kinematics!r} equations have fixed lengths"
                )
            low, high = link.rope_min, link.rope_max
            for name, value in (("min", low), ("max", high)):
                if value is None or not satisfies(QUANTITIES["l"][0], value):
                    raise SceneError(
                        f"{where}.{name}: must be {RULES[QUANTITIES['l'][0]].wanted}, got {value!r}"
                    )
            if not low <= link.length <= high:
                raise SceneError(
                    f"{where}: link {i}'s length {link.length!r} m is outside its range [{low!r}, {high!r}] m"
                )

    def _validate_bob_flags(self) -> None:
        """A bob's flags (an applied force, a load): true or false, only on a bob, and in the
        consistent kinematics (a force's book and a load's are states of the energy's)."""
        flags = {  # the file's name: the field, what a bob is for, what needs it, what the published lack
            "force": ("bob_force", "to apply a force to", "applied forces need", "take none"),
            "load": ("bob_load", "to be a load", "loads need", "keep no energy's books"),
        }
        for i, link in enumerate(self.links):
            for flag, (name, purpose, needs, lacks) in flags.items():
                where, value = f"link[{i}].bob.{flag}", getattr(link, name)
                if not isinstance(value, bool):
                    raise SceneError(f"{where}: expected true or false, got {value!r}")
                if value and not link.has_bob:
                    raise SceneError(f"{where}: link {i} has no bob {purpose}")
                if value and self.kinematics != "consistent":
                    raise SceneError(
                        f"{where}: {needs} kinematics 'consistent'; the published "
                        f"{self.kinematics!r} equations {lacks}"
                    )

    def loads(self) -> list[int]:
        """The links whose bob is a load (its mass m<i> tunable, the book W_load)."""
        return [i for i, link in enumerate(self.links) if link.bob_load]

    def ropes(self) -> list[int]:
        """The links that are ropes (a state l<i> and an input v_hoist<i> each)."""
        return [i for i, link in enumerate(self.links) if link.rope]

    def resolved_formulation(self) -> str:
        """The formulation the core is generated in: as chosen, or for "auto" the faster one
        at this number of links (benchmarks/chain_scaling.py measures the crossover)."""
        if self.formulation != "auto":
            return self.formulation
        if self.kinematics != "consistent" or self.n < RECURSIVE_FROM:
            return "expanded"
        return "recursive"

    def cache_fields(self) -> dict:
        """What the generated code depends on, and nothing else (an option left out is not
        named, so a scene without options keeps today's key)."""
        options = {name: True for name in ("joint_damping", "air_drag") if getattr(self, name)}
        if self.forced_bobs():
            options["bob_forces"] = self.forced_bobs()
        if self.ropes():  # the ranges are in the generated C
            options["ropes"] = [[i, self.links[i].rope_min, self.links[i].rope_max] for i in self.ropes()]
        if self.loads():
            options["loads"] = self.loads()
        return {
            "links": [[link.has_mass, link.has_bob] for link in self.links],
            "outputs": list(self.outputs),
            "kinematics": self.kinematics,
            "coupling": self.coupling,
            "formulation": self.resolved_formulation(),
            **options,
        }

    def key(self, salt: str = "") -> str:
        text = json.dumps(self.cache_fields(), sort_keys=True) + salt
        return hashlib.sha256(text.encode()).hexdigest()

    # --- names: the FMU's contract, in the order of the compiled core's arrays ---

    def parameter_scalars(self) -> list[Scalar]:
        """Parameters in the seed's order: l (links that are no rope), m (bobs), M (links), Ixx, Iyy, Izz, then the
        joints' damping c (with joint_damping), the bobs' drag coefficients C_d and areas A
        and the air's density rho (with air_drag), then g."""
        n = range(self.n)
        massive = [i for i in n if self.links[i].has_mass]
        bobs = [i for i in n if self.links[i].has_bob]
        dragged = self.dragged_bobs()
        return (
            [Scalar("l", i) for i in n if not self.links[i].rope]
            + [Scalar("m", i) for i in bobs]
            + [Scalar("M", i) for i in massive]
            + [Scalar(axis, i) for axis in ("Ixx", "Iyy", "Izz") for i in massive]
            + ([Scalar("c", i) for i in n] if self.joint_damping else [])
            + [Scalar(quantity, i) for quantity in ("C_d", "A") for i in dragged]
            + ([Scalar("rho")] if dragged else [])
            + [Scalar("g")]
        )

    def parameter_names(self) -> list[str]:
        return _names(self.parameter_scalars())

    def parameter_defaults(self) -> list[float]:
        values = {}
        for i, link in enumerate(self.links):
            values[f"l{i}"] = link.length
            values[f"m{i}"] = link.bob_mass
            values[f"M{i}"] = link.mass
            values[f"Ixx{i}"], values[f"Iyy{i}"], values[f"Izz{i}"] = link.inertia()
            values[f"c{i}"] = link.damping
            values[f"C_d{i}"], values[f"A{i}"] = link.drag()
        values["rho"] = self.air_density
        values["g"] = self.gravity
        return [float(values[name]) for name in self.parameter_names()]

    def forced_bobs(self) -> list[int]:
        """The links whose bob takes an applied force (inputs F_bob<i>_x/y/z)."""
        return [i for i, link in enumerate(self.links) if link.bob_force]

    def dragged_bobs(self) -> list[int]:
        """The links whose bob the air drags (every bob, with air_drag)."""
        return [i for i, link in enumerate(self.links) if link.has_bob] if self.air_drag else []

    def input_scalars(self) -> list[Scalar]:
        """Inputs, held constant over a communication step: the pivot's inertial acceleration
        (first: the core reads it there) and with air drag its velocity, the forces applied to
        the bobs the scene names, the ropes' winch speeds v_hoist<i> (l<i>' [m/s]), then the
        wind (all in inertial components)."""
        pivot = list(PIVOT_INPUTS) + (list(PIVOT_VELOCITY) if self.air_drag else []) if self.coupling else []
        forces = [Scalar("F_bob", i, f"_{c}") for i in self.forced_bobs() for c in "xyz"]
        hoists = [Scalar("v_hoist", i) for i in self.ropes()]
        return (
            [Scalar(name) for name in pivot]
            + forces
            + hoists
            + [Scalar(name) for name in WIND if self.air_drag]
        )

    def input_names(self) -> list[str]:
        return _names(self.input_scalars())

    def core_parameter_scalars(self) -> list[Scalar]:
        """What the compiled core reads from its array p: the parameters, then the inputs."""
        return self.parameter_scalars() + self.input_scalars()

    def core_parameter_names(self) -> list[str]:
        return _names(self.core_parameter_scalars())

    def hoist_acceleration_names(self) -> list[str]:
        """What the core reads after the parameters and inputs (no variable holds them): each
        rope's l<i>'', the rate of its v_hoist<i>, which the native FMUs interpolate (0 where
        the inputs are held)."""
        return [f"a_hoist{i}" for i in self.ropes()]

    def state_scalars(self) -> list[Scalar]:
        """alpha, beta (angles), omega = alpha', delta = beta': the seed's state order; then
        the energy's books, the work of each force a scene adds since the start (work_names);
        then the ropes' lengths l<i>."""
        return (
            [Scalar(s, i) for s in ("alpha", "beta", "omega", "delta") for i in range(self.n)]
            + [Scalar(name) for name in self.work_names()]
            + [Scalar("l", i) for i in self.ropes()]
        )

    def work_names(self) -> list[str]:
        """The energy's books: states integrating the power of each non-conservative force
        the scene has, so that energy minus their sum stays constant."""
        forces = (self.joint_damping, self.air_drag, bool(self.forced_bobs()))
        ropes, loads = bool(self.ropes()), bool(self.loads())
        # the moving pivot's work is kept with the other books (a coupled scene without them
        # stays as it was); a rope's winch always does work, and a load's change moves energy
        kept = (*forces, self.coupling and (any(forces) or ropes or loads), ropes, loads)
        return [name for name, keep in zip(WORKS, kept) if keep]

    def state_names(self) -> list[str]:
        return _names(self.state_scalars())

    def state_defaults(self) -> list[float]:
        return (
            [SEED_ANGLE] * (2 * self.n)
            + [0.0] * (2 * self.n)
            + [0.0] * len(self.work_names())
            + [self.links[i].length for i in self.ropes()]
        )

    def output_scalars(self) -> list[Scalar]:
        """Calculated outputs besides the state, in the compiled core's order."""
        scalars = []
        if "bobs" in self.outputs:
            scalars += [
                Scalar("bob", i, f"_{c}") for i, link in enumerate(self.links) if link.has_bob for c in "xyz"
            ]
        if "poses" in self.outputs:
            scalars += [
                Scalar("link", i, f"_{c}")
                for i in range(self.n)
                for c in ("x", "y", "z", "qw", "qx", "qy", "qz")
            ]
        if "energy" in self.outputs:
            scalars.append(Scalar("energy"))
        if self.coupling:
            scalars += [Scalar(name) for name in PIVOT_OUTPUTS + FREE_FORCE + APPARENT_MASS]
        # each rope's tension and its winch's power (after the pivot's: the core finds those
        # at fixed places)
        scalars += [Scalar(stem, i) for stem in ROPE_OUTPUTS for i in self.ropes()]
        return scalars

    def output_names(self) -> list[str]:
        return _names(self.output_scalars())

    def parameters(self, overrides: dict | None = None) -> list[float]:
        """The core's p: the scene's numbers, then inputs at 0, some replaced by name.

        Values are checked where they are used (runtime.rules.check_value)."""
        defaults = self.parameter_defaults() + [0.0] * len(self.input_names())
        return _merge(self.core_parameter_names(), defaults, overrides, "parameter")

    def initial_state(self, overrides: dict | None = None) -> list[float]:
        """State in core order: the seed's start values, some replaced by name."""
        return _merge(self.state_names(), self.state_defaults(), overrides, "state")

    def split_start(self, start_values: dict) -> tuple[dict, dict]:
        """An FMU's start values as (parameters and inputs, states) by name, for parameters()
        and initial_state(); settings and other names left out."""
        parameters = {k: v for k, v in start_values.items() if k in self.core_parameter_names()}
        states = {k: v for k, v in start_values.items() if k in self.state_names()}
        return parameters, states

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> Scene:
        """The scene to_dict described."""
        links = tuple(
            Link(**{**link, "moments": link["moments"] and tuple(link["moments"])}) for link in data["links"]
        )
        return cls(**{**data, "links": links, "outputs": tuple(data["outputs"])})


def load_scene(path) -> Scene:
    """A scene from a TOML or JSON file (see scenes/seed.toml for the fields)."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise SceneError(f"scene file {str(path)!r}: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise SceneError(f"scene file {str(path)!r}: not text (UTF-8)") from None
    try:
        if path.suffix == ".toml":
            data = tomllib.loads(text)
        elif path.suffix == ".json":
            data = json.loads(text)
        else:
            raise SceneError(f"scene file {str(path)!r}: expected a .toml or .json file")
    except (tomllib.TOMLDecodeError, json.JSONDecodeError) as exc:
        raise SceneError(f"scene file {str(path)!r}: {exc}") from None
    try:
        return scene_from_dict(data)
    except SceneError as exc:
        raise SceneError(f"scene file {str(path)!r}: {exc}") from None


DEFAULT_LINK = Link()
FILE_NAMES = {  # Link fields as a file names them
    "bob_mass": "bob.mass",
    "bob_radius": "bob.radius",
    "bob_drag_coefficient": "bob.drag_coefficient",
    "bob_area": "bob.area",
}
MASSLESS_HINT = " (or 0 for a massless link: has_mass=False)"
SCENE_FIELDS = {
    "link",
    "kinematics",
    "gravity",
    "outputs",
    "coupling",
    "formulation",
    "joint_damping",
    "air_drag",
    "air_density",
}
LINK_FIELDS = {"length", "mass", "radius", "inertia", "bob", "damping", "rope"}
ROPE_FIELDS = {"min", "max"}
BOB_FIELDS = {"mass", "radius", "force", "drag_coefficient", "area", "load"}


def scene_from_dict(data: dict) -> Scene:
    """A scene from the structure of a scene file: [[link]] tables and scene-wide fields."""
    _known(data, SCENE_FIELDS, "scene")
    links = data.get("link")
    if not isinstance(links, list) or not links:
        raise SceneError("link: give one [[link]] table per link, top to bottom")
    made = []
    for i, entry in enumerate(links):
        where = f"link[{i}]"
        if not isinstance(entry, dict):
            raise SceneError(f"{where}: expected a table of fields, got {entry!r}")
        _known(entry, LINK_FIELDS, where)
        mass = entry.get("mass", DEFAULT_LINK.mass)
        bob = entry.get("bob")
        if bob is not None and not isinstance(bob, dict):
            raise SceneError(f"{where}.bob: expected a table {{ mass = ..., radius = ... }}, got {bob!r}")
        _known(bob or {}, BOB_FIELDS, f"{where}.bob")
        fields = {
            "has_mass": mass != 0,
            "has_bob": bob is not None,
            "mass": mass if mass != 0 else DEFAULT_LINK.mass,
        }
        fields.update({name: entry[name] for name in ("length", "radius", "damping") if name in entry})
        fields.update({f"bob_{name}": value for name, value in (bob or {}).items()})
        if "rope" in entry:
            rope = entry["rope"]
            if not isinstance(rope, dict):
                raise SceneError(f"{where}.rope: expected a table {{ min = ..., max = ... }}, got {rope!r}")
            _known(rope, ROPE_FIELDS, f"{where}.rope")
            fields.update(rope=True, rope_min=rope.get("min"), rope_max=rope.get("max"))
        if "inertia" in entry:
            fields["moments"] = (
                tuple(entry["inertia"]) if isinstance(entry["inertia"], list) else entry["inertia"]
            )
        try:
            made.append(Link(**fields))
        except TypeError as exc:
            raise SceneError(f"{where}: {exc}") from None
    scene_fields = {"links": tuple(made)}
    for name in SCENE_FIELDS - {"link"}:
        if name in data:
            scene_fields[name] = tuple(data[name]) if name == "outputs" else data[name]
    if "joint_damping" not in data and any("damping" in entry for entry in links):
        scene_fields["joint_damping"] = True  # a link's damping asks for it
    drag_fields = ("drag_coefficient", "area")
    bob_drag = any(name in (entry.get("bob") or {}) for entry in links for name in drag_fields)
    if "air_drag" not in data and ("air_density" in data or bob_drag):
        scene_fields["air_drag"] = True  # the air's density or a bob's drag asks for it
    for name in ("gravity", "air_density"):
        if name in data and (isinstance(data[name], bool) or not isinstance(data[name], (int, float))):
            raise SceneError(f"{name}: expected a number, got {data[name]!r}")
    return Scene(**scene_fields)


def _given_without(where: str, value, option: str) -> SceneError:
    """A value given for an option the scene does not have."""
    return SceneError(
        f"{where}: {value!r} given, but the scene has no {option.replace('_', ' ')}: set {option} = true"
    )


def _known(table: dict, fields: set, where: str) -> None:
    unknown = sorted(set(table) - fields)
    if unknown:
        raise SceneError(f"{where}: unknown field(s) {unknown}; known: {sorted(fields)}")


def _merge(names, defaults, overrides, what):
    values = dict(zip(names, defaults))
    for name, value in (overrides or {}).items():
        if name not in values:
            raise SceneError(f"unknown {what} {name!r}; this scene has {', '.join(names)}")
        values[name] = value
    return [values[name] for name in names]
