"""The scene's variables: the names and start values of its parameters, inputs, states and
outputs, in the compiled core's order. They are the FMU's contract; every variable the build
declares and every array the core reads comes from here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .links import SceneError

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
# pivot's inertial force, the winches of the ropes), the energy that changes of the loads'
# masses took or gave, and the work of the elastic ropes' damping
WORKS = ("W_damping", "W_drag", "W_external", "W_pivot", "W_hoist", "W_load", "W_rope")
# A rope's: its tension [N] and its winch's power [W] (-tension * v_hoist)
ROPE_OUTPUTS = ("T_rope", "P_hoist")
# An elastic rope's: its stretch r - l [m] (< 0: slack), and its taut margin [N], the tension
# it would carry if a rope could push (> 0: taut), whose sign changes are its slack and snap
# events (an elastic rope's event indicator)
ELASTIC_OUTPUTS = ("stretch", "taut_margin")
# What the integration saw of an elastic rope, which no function of the state gives: its
# largest tension since the last communication point, its snaps (slack to taut) since the
# start, and whether it is taut (1) or slack (0)
ROPE_EVENTS = ("T_rope_peak", "snaps", "taut")
SEED_ANGLE = math.radians(10.0)


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


class SceneVariables:
    """The names of a Scene's variables (a base of Scene: it reads the links and options)."""

    def parameter_scalars(self) -> list[Scalar]:
        """Parameters in the seed's order: l (links that are no rope), m (bobs), M (links), Ixx, Iyy, Izz, then the
        joints' damping c (with joint_damping), the bobs' drag coefficients C_d and areas A
        and the air's density rho (with air_drag), the elastic ropes' stiffnesses EA and damping
        ratios zeta_rope, then g."""
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
            + [Scalar(quantity, i) for quantity in ("EA", "zeta_rope") for i in self.elastic_ropes()]
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
            values[f"EA{i}"], values[f"zeta_rope{i}"] = link.rope_stiffness, link.rope_damping or 0.0
        values["rho"] = self.air_density
        values["g"] = self.gravity
        return [float(values[name]) for name in self.parameter_names()]

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
        """Each rope's l<i>'', the rate of its v_hoist<i>, which the native FMUs interpolate (0
        where the inputs are held)."""
        return [f"a_hoist{i}" for i in self.ropes()]

    def rope_law_names(self) -> list[str]:
        """Each elastic rope's tension T_law<i>, taut stretch s_taut<i> (max(r - l, 0)) and taut
        margin margin<i>, which the core's rope law (runtime/csrc/core/dynamics.c's
        cp_rope_law) computes from the state before every evaluation of the equations."""
        return [f"{name}{i}" for i in self.elastic_ropes() for name in ("T_law", "s_taut", "margin")]

    def core_extra_names(self) -> list[str]:
        """What the core reads after the parameters and inputs, which no variable holds: the
        ropes' l'', then the elastic ropes' law."""
        return self.hoist_acceleration_names() + self.rope_law_names()

    def state_scalars(self) -> list[Scalar]:
        """The generalized coordinates q: alpha, beta (angles), then each elastic rope's reach
        r<i> (its bob's distance from its top); the speeds u = q': omega = alpha', delta = beta',
        v_r<i> = r<i>' (the seed's state order, where the scene has no elastic rope); then the
        energy's books, the work of each force a scene adds since the start (work_names); then
        the ropes' (unstretched) lengths l<i>."""
        n, elastic = range(self.n), self.elastic_ropes()
        return (
            [Scalar(s, i) for s in ("alpha", "beta") for i in n]
            + [Scalar("r", i) for i in elastic]
            + [Scalar(s, i) for s in ("omega", "delta") for i in n]
            + [Scalar("v_r", i) for i in elastic]
            + [Scalar(name) for name in self.work_names()]
            + [Scalar("l", i) for i in self.ropes()]
        )

    def dof(self) -> int:
        """The generalized speeds: two angles' rates a link, and each elastic rope's v_r."""
        return 2 * self.n + len(self.elastic_ropes())

    def work_names(self) -> list[str]:
        """The energy's books: states integrating the power of each non-conservative force
        the scene has, so that energy minus their sum stays constant."""
        forces = (self.joint_damping, self.air_drag, bool(self.forced_bobs()))
        ropes, loads = bool(self.ropes()), bool(self.loads())
        # the moving pivot's work is kept with the other books (a coupled scene without them
        # stays as it was); a rope's winch always does work, a load's change moves energy, and
        # an elastic rope's damping takes it
        pivot = self.coupling and (any(forces) or ropes or loads)
        kept = (*forces, pivot, ropes, loads, bool(self.elastic_ropes()))
        return [name for name, keep in zip(WORKS, kept) if keep]

    def state_names(self) -> list[str]:
        return _names(self.state_scalars())

    def state_defaults(self) -> list[float]:
        reaches = [self.links[i].length for i in self.elastic_ropes()]  # taut, unstretched
        return (
            [SEED_ANGLE] * (2 * self.n)
            + reaches
            + [0.0] * (2 * self.n + len(reaches))
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
        # and each elastic rope's stretch and taut margin
        scalars += [Scalar(stem, i) for stem in ELASTIC_OUTPUTS for i in self.elastic_ropes()]
        return scalars

    def rope_event_scalars(self) -> list[Scalar]:
        """What the integration saw of each elastic rope (ROPE_EVENTS), in the core's order."""
        return [Scalar(stem, i) for stem in ROPE_EVENTS for i in self.elastic_ropes()]

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


def _merge(names, defaults, overrides, what):
    values = dict(zip(names, defaults))
    for name, value in (overrides or {}).items():
        if name not in values:
            raise SceneError(f"unknown {what} {name!r}; this scene has {', '.join(names)}")
        values[name] = value
    return [values[name] for name in names]
