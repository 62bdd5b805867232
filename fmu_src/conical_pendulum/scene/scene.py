"""The scene: its links and options, checked whole, and the key of the code they generate.

The scene is the single input of the build pipeline. Its structure (which bodies
exist, which outputs are wanted, which kinematics, which forces) decides the generated
code; its numbers (lengths, masses, radii, damping, drag) are only start values of FMU parameters.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, field

from ..runtime.rules import QUANTITIES, RULES, satisfies
from .links import LINK_CHECKS, Link, SceneError, given_without
from .variables import SceneVariables

KINEMATICS = ("consistent", "pydy-example")
OUTPUT_GROUPS = ("bobs", "poses", "energy")
FORMULATIONS = ("auto", "expanded", "recursive")
MAX_LINKS = 100
MAX_EXPANDED_LINKS = 20  # the expanded equations' C grows like n^3: minutes to compile at 20
MAX_PUBLISHED_LINKS = 4  # the published derivation grows exponentially with n
RECURSIVE_FROM = 6  # "auto": links from which the recursive formulation is the faster
AIR_DENSITY = 1.225  # kg/m3: the ISA's at sea level


@dataclass(frozen=True)
class Scene(SceneVariables):
    """A chain of links and the options that add forces, inputs and outputs to it; checked
    whole when made (a SceneError names the field and its value)."""

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
        self._validate_option("coupling", "the pivot's inputs and force need", "have no moving support")
        self._validate_option(
            "joint_damping", "the joints' damping needs", "have no relative angular velocity to damp"
        )
        self._validate_drag()
        for i, link in enumerate(self.links):
            for check in LINK_CHECKS:
                check(self, i, link)
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
        if not self.air_drag and self.air_density != AIR_DENSITY:
            raise given_without("air_density", self.air_density, "air_drag")

    def forced_bobs(self) -> list[int]:
        """The links whose bob takes an applied force (inputs F_bob<i>_x/y/z)."""
        return [i for i, link in enumerate(self.links) if link.bob_force]

    def dragged_bobs(self) -> list[int]:
        """The links whose bob the air drags (every bob, with air_drag)."""
        return [i for i, link in enumerate(self.links) if link.has_bob] if self.air_drag else []

    def loads(self) -> list[int]:
        """The links whose bob is a load (its mass m<i> tunable, the book W_load)."""
        return [i for i, link in enumerate(self.links) if link.bob_load]

    def ropes(self) -> list[int]:
        """The links that are ropes (a state l<i> and an input v_hoist<i> each)."""
        return [i for i, link in enumerate(self.links) if link.rope]

    def elastic_ropes(self) -> list[int]:
        """The ropes that stretch (a stiffness EA): their bob's distance r<i> from the rope's top
        and its rate v_r<i> are states, a generalized coordinate and speed each."""
        return [i for i in self.ropes() if self.links[i].rope_stiffness is not None]

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
        if self.elastic_ropes():
            options["elastic_ropes"] = self.elastic_ropes()
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

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> Scene:
        """The scene to_dict described."""
        links = tuple(
            Link(**{**link, "moments": link["moments"] and tuple(link["moments"])}) for link in data["links"]
        )
        return cls(**{**data, "links": links, "outputs": tuple(data["outputs"])})
