"""Equations of motion of the n-link conical pendulum, by Kane's method (build time only).

Each joint's kinematics (relative orientation and relative angular velocity of the
seed's 'Space' 'ZXY' two-angle joint) comes from sympy.physics.mechanics. Kane's
equations Fr + Fr* = 0 are then formed with vectors in inertial components, and every
per-link quantity (orientation matrix, partial velocities, bias accelerations) is
named by an intermediate symbol. Expanding them, as KanesMethod does, grows the
expressions exponentially with n (10 million operations at n = 6); naming them keeps
the work O(n^3) and the code small.

Generalized speeds are the angle rates u = (omega, delta) = (alpha', beta'), the state
a user sees, so the kinematic equations are q' = u.

A rope (Link.rope) is a massless link whose length l<i> is a state, l<i>' = v_hoist<i> (an
input, held over an integration: l<i>'' = 0): its lower end moves relative to the link by
-v_hoist e_y, which adds 2 w x (-v_hoist e_y) to its acceleration (Coriolis). Its tension is
Newton's law for everything hanging from it, along the rope; the winch's power is -tension
v_hoist, and the book W_hoist integrates it.

An elastic rope (Link.rope_stiffness) lets its bob's distance r<i> from the rope's top be a
generalized coordinate of its own (speed v_r<i>): the bob slides along the rope's axis at
-v_r e_y, a partial velocity -e_y, and the rope pulls it back with its tension T, a generalized
force -T on v_r (on the angles' speeds the pull on the bob and on the rope's top cancel). T
follows the rope's law, which is not analytic (zero when slack): the core computes it from
the state (cp_rope_law in runtime/csrc/core/dynamics.c) and hands it in p with the taut
stretch s+ = max(r - l, 0), so these equations stay analytic. The rope's elastic energy EA s+^2 / (2 l) is in the
energy; its damping's work, (EA s+ / l - T) (v_r - v_hoist), in the book W_rope; and its
winch's power is -(T + EA s+^2 / (2 l^2)) v_hoist: the tension's work on the rope paid out,
and the strain energy it carries off the drum.

With coupling, the pivot accelerates by a_pivot (inputs, inertial components): every
mass centre's acceleration gains a_pivot. The force on the support is Newton's law for
the whole chain, sum m (g - a), so it needs u' (the symbols `rates`).

The published model (kinematics="pydy-example") cannot be formed this way: its
equations are whatever sympy derives from contradictory kinematics, so they come from
running the seed's own KanesMethod derivation (see builder.core.kane).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sm
import sympy.physics.mechanics as me

from ...scene import PIVOT_INPUTS, PIVOT_VELOCITY, WIND, Scene
from .kane import kanes_method

Vec = sm.Matrix
ZERO, UNIT_X, UNIT_Z = Vec([0, 0, 0]), Vec([1, 0, 0]), Vec([0, 0, 1])


@dataclass
class Equations:
    """M(x, p) u' = F(x, p), with intermediate definitions evaluated in order.

    p holds the parameters, then the inputs, then the ropes' l'' and the elastic ropes' law (Scene.core_extra_names);
    outputs may depend on u' (`rates`)."""

    scene: Scene
    # what the expressions read of the state: angles, rates, the ropes' lengths (named as
    # Scene.state_names; the books, which nothing reads, are not here)
    states: list[sm.Symbol]
    params: list[sm.Symbol]
    rates: list[sm.Symbol]
    definitions: list[tuple[sm.Symbol, sm.Expr]]
    mass_matrix: sm.Matrix
    forcing: sm.Matrix
    outputs: list[sm.Expr]
    # With coupling: the chain's linear momentum per generalized speed (3 x dim) and its
    # total mass, so that F_pivot = F_free - (m I - P M^-1 P^T) a_pivot
    momentum: sm.Matrix | None = None
    total_mass: sm.Expr | None = None
    # The energy's books: the power of each force of Scene.work_names (x' of those states;
    # W_hoist's needs u', the symbols `rates`)
    work_rates: list[sm.Expr] = field(default_factory=list)
    # x' of the ropes' lengths (Scene.ropes' order): their inputs v_hoist
    rope_rates: list[sm.Expr] = field(default_factory=list)
    # the chain's energy, kinetic (relative to the pivot) and potential: the output energy, and
    # what a value set at an event jumps (a rope's winch speed, a load's mass)
    energy: sm.Expr = sm.S.Zero

    def lambdify(self):
        """Numpy functions (x, p) -> M, F and (x, p, u') -> outputs of these very
        expressions (for checks)."""
        cse = lambda exprs: (needed(self.definitions, exprs), exprs)  # noqa: E731 - lambdify's hook
        args = [self.states, self.params]
        return (
            sm.lambdify(args, self.mass_matrix, cse=cse),
            sm.lambdify(args, self.forcing, cse=cse),
            sm.lambdify(args + [self.rates], self.outputs, cse=cse),
        )


def needed(definitions, exprs):
    """The definitions the expressions depend on, in evaluation order."""
    defined = dict(definitions)
    wanted = set()
    stack = [s for e in exprs for s in sm.sympify(e).free_symbols if s in defined]
    while stack:
        s = stack.pop()
        if s not in wanted:
            wanted.add(s)
            stack.extend(t for t in defined[s].free_symbols if t in defined)
    return [(s, e) for s, e in definitions if s in wanted]


def joint_kinematics():
    """Relative DCM and angular-velocity Jacobian of one 'Space' 'ZXY' joint, from sympy.

    Returns (a, b, C, J): child axes in parent components C(a, b) (columns x, y, z) and
    J(a, b) with relative angular velocity = J @ (a', b') in parent components.
    """
    a, b = me.dynamicsymbols("a b")
    parent, child = me.ReferenceFrame("P"), me.ReferenceFrame("C")
    child.orient(parent, "Space", [a, b, 0], "ZXY")
    dcm = parent.dcm(child)
    omega = child.ang_vel_in(parent).to_matrix(parent).applyfunc(sm.trigsimp)
    rates = [a.diff(), b.diff()]
    jac = omega.jacobian(rates)
    sa, sb = sm.symbols("a b")
    plain = {a: sa, b: sb}
    return sa, sb, dcm.xreplace(plain), jac.xreplace(plain)


def joint_damping(scene: Scene) -> tuple[list[sm.Expr], sm.Expr]:
    """The joints' damping torques -c_i w_rel_i (w_rel_i = J_i u_i, link i's angular velocity
    relative to its parent, u_i = (omega_i, delta_i); +c_i w_rel_i on the parent) as
    generalized forces, one per speed, and their power. The torque's partial angular
    velocity is J_i's columns, so the forces are -c_i J_i^T J_i u_i and the power
    -c_i u_i^T J_i^T J_i u_i, with J_i^T J_i from sympy's joint (the identity for 'Space'
    'ZXY': the joint's axes are orthonormal, which runtime/csrc/core/chain.c relies on)."""
    a, b, _, jac = joint_kinematics()
    gram = (jac.T * jac).applyfunc(sm.simplify)
    n = scene.n
    forces, power = [sm.S.Zero] * (2 * n), sm.S.Zero
    for i in range(n):
        c = sm.Symbol(f"c{i}")
        u = Vec(sm.symbols(f"omega{i} delta{i}"))
        torque = -c * gram.xreplace({a: sm.Symbol(f"alpha{i}"), b: sm.Symbol(f"beta{i}")}) * u
        forces[i], forces[n + i] = torque
        power += u.dot(torque)
    return forces, power


def _work_rates(scene: Scene, sym: _Symbols, sums: _Sums) -> list[sm.Expr]:
    """The power of each force of the energy's books (Scene.work_names, in its order): the
    joints' damping, the air's drag, the bobs' applied forces, and the moving pivot's
    inertial force -m a_pivot on every mass (velocities are relative to the pivot, as the
    energy is)."""
    power = {
        "W_damping": lambda: joint_damping(scene)[1],
        "W_drag": lambda: sums.drag_power,
        "W_external": lambda: sums.external_power,
        "W_pivot": lambda: -sym.pivot_acc.dot(sums.linear_momentum),
        "W_hoist": lambda: sum(sums.hoist_power, sm.S.Zero),
        "W_load": lambda: sm.S.Zero,  # it jumps at a load's change (the model's), and stays between
        "W_rope": lambda: sum(sums.rope_damping_power, sm.S.Zero),
    }
    return [power[name]() for name in scene.work_names()]


class _Builder:
    """Collects named intermediate quantities in evaluation order."""

    def __init__(self):
        self.definitions: list[tuple[sm.Symbol, sm.Expr]] = []

    def name(self, label: str, value):
        """Give a scalar or vector (Matrix) value a name unless it is trivial."""
        if isinstance(value, sm.MatrixBase):
            return Vec([self.name(f"{label}_{k}", v) for k, v in enumerate(value)]).reshape(*value.shape)
        value = sm.sympify(value)
        if value.is_Atom or (
            value.is_Mul and len(value.args) == 2 and value.args[0].is_Number and value.args[1].is_Atom
        ):
            return value
        symbol = sm.Symbol(label)
        self.definitions.append((symbol, value))
        return symbol


@dataclass
class _Symbols:
    """The scene's symbols: the state x = (alpha, beta, omega, delta), the parameters and
    inputs p, and the accelerations u' (`rates`), which only the support force uses."""

    n: int
    alpha: tuple
    beta: tuple
    omega: tuple
    delta: tuple
    rates: tuple
    params: dict[str, sm.Symbol]
    pivot_acc: sm.Matrix | None
    lengths: tuple  # l<i>: a parameter, or a rope's state (an elastic one's unstretched length)
    elastic: list[int]  # the links that are elastic ropes (Scene.elastic_ropes)
    reaches: dict[int, sm.Symbol]  # each elastic rope's r<i>
    reach_rates: dict[int, sm.Symbol]  # and its v_r<i>, a generalized speed after the angles'

    def hoist(self, i: int):
        """Link i's rate of lengthening: a rope's v_hoist<i>, else 0."""
        return self.params.get(f"v_hoist{i}", sm.S.Zero)

    def reach(self, i: int):
        """Link i's distance from its top to its lower end: an elastic rope's r<i>, else l<i>."""
        return self.reaches.get(i, self.lengths[i])

    def slide(self, i: int):
        """The speed at which link i's lower end slides away from its top: an elastic rope's
        v_r<i> (a generalized speed), another rope's v_hoist<i>, else 0."""
        return self.reach_rates.get(i, self.hoist(i))

    def slide_acc(self, i: int):
        """That slide's acceleration, where it is prescribed: a rope's a_hoist<i> (l<i>''); 0
        for an elastic rope (v_r<i>' is a rate u') and for other links."""
        return sm.S.Zero if i in self.reaches else self.params.get(f"a_hoist{i}", sm.S.Zero)

    def speed_index(self, i: int) -> int:
        """Where an elastic rope's v_r<i> is among the generalized speeds."""
        return 2 * self.n + self.elastic.index(i)

    @property
    def dim(self) -> int:
        return 2 * self.n + len(self.elastic)

    @property
    def g(self) -> sm.Symbol:
        return self.params["g"]


def _core_p_names(scene: Scene) -> list[str]:
    """Everything the core reads from p, in its order."""
    return scene.core_parameter_names() + scene.core_extra_names()


def _symbols(scene: Scene) -> _Symbols:
    """Symbols named as the FMU's variables, so that the generated C reads like the model."""
    n, elastic = scene.n, scene.elastic_ropes()
    params = {name: sm.Symbol(name) for name in _core_p_names(scene)}
    return _Symbols(
        n=n,
        alpha=sm.symbols(f"alpha0:{n}"),
        beta=sm.symbols(f"beta0:{n}"),
        omega=sm.symbols(f"omega0:{n}"),
        delta=sm.symbols(f"delta0:{n}"),
        rates=sm.symbols(f"domega0:{n}")
        + sm.symbols(f"ddelta0:{n}")
        + tuple(sm.Symbol(f"dv_r{i}") for i in elastic),
        params=params,
        pivot_acc=Vec([params[name] for name in PIVOT_INPUTS]) if scene.coupling else None,
        lengths=sm.symbols(f"l0:{n}"),
        elastic=elastic,
        reaches={i: sm.Symbol(f"r{i}") for i in elastic},
        reach_rates={i: sm.Symbol(f"v_r{i}") for i in elastic},
    )


@dataclass
class _Point:
    """A point of the chain in inertial components: position, partial velocities (one per
    generalized speed; ZERO where the speed does not move it), velocity, and acceleration
    at u' = 0 (the full one adds sum(partials[s] u'_s))."""

    position: sm.Matrix
    partials: list[sm.Matrix]
    velocity: sm.Matrix
    acc_bias: sm.Matrix


@dataclass
class _Frame:
    """A link's frame: axes in inertial components (columns), angular velocity, partial
    angular velocities and angular acceleration at u' = 0."""

    rotation: sm.Matrix
    w: sm.Matrix
    partial_w: list[sm.Matrix]
    wb: sm.Matrix


@dataclass
class _Parent:
    """What link i inherits from the one above it (the pivot for the first): its frame,
    its lower end (link i's joint) and its orientation quaternion."""

    frame: _Frame
    joint: _Point
    quaternion: tuple

    @classmethod
    def pivot(cls, dim: int) -> _Parent:
        """The inertial frame and a fixed pivot at the origin (a moving pivot's
        acceleration is added at the bodies, _add_particle)."""
        return cls(
            _Frame(sm.eye(3), ZERO, [ZERO] * dim, ZERO), _Point(ZERO, [ZERO] * dim, ZERO, ZERO), (1, 0, 0, 0)
        )


@dataclass
class _Sums:
    """Kane's equations accumulated body by body: the upper triangle of the mass matrix M
    and the forcing F (Fr + Fr* = 0 with Fr* = -M u' + terms at u' = 0), the energies,
    and with coupling the force on the support (sum of m (g - a)) and the chain's linear
    momentum per generalized speed (P's columns) and total mass."""

    mass_terms: list[list]
    force_terms: list
    kinetic: sm.Expr
    potential: sm.Expr
    support_force: sm.Matrix
    momentum: list[sm.Matrix]
    total_mass: sm.Expr
    # sum m v: the power of the pivot's inertial force -m a_pivot is -a_pivot . sum m v
    linear_momentum: sm.Matrix = field(default_factory=lambda: ZERO)
    external_power: sm.Expr = sm.S.Zero  # of the forces applied to the bobs
    drag_power: sm.Expr = sm.S.Zero  # of the air's drag on the bobs
    # per link, from the pivot down: the masses' m (a - g) (full accelerations, with u') less
    # the forces applied to them; a rope's tension is the sum of those below it along the rope
    hangs: list[sm.Matrix] = field(default_factory=list)
    tensions: list[sm.Expr] = field(default_factory=list)  # each rope's (Scene.ropes' order)
    hoist_power: list[sm.Expr] = field(default_factory=list)  # each rope's winch's
    rope_damping_power: list[sm.Expr] = field(default_factory=list)  # each elastic rope's

    @classmethod
    def empty(cls, dim: int) -> _Sums:
        return cls([[0] * dim for _ in range(dim)], [0] * dim, 0, 0, ZERO, [ZERO] * dim, 0)


def _link_frame(b: _Builder, scene: Scene, sym: _Symbols, joint, i: int, parent: _Frame) -> _Frame:
    """Link i's frame from its parent's through the two-angle joint: the rotation composed,
    and the angular velocity as the parent's plus the joint's relative one, whose
    Jacobian columns are the partial angular velocities of omega_i and delta_i. With the
    published kinematics the angular velocity is the seed's declared omega*I.z + delta*I.x
    (what it contradicts: model.md)."""
    ja, jb, joint_dcm, joint_jac, joint_jac_rate = joint
    sub = {ja: sym.alpha[i], jb: sym.beta[i]}
    omega, delta = sym.omega[i], sym.delta[i]
    rotation = b.name(f"R{i}", parent.rotation * joint_dcm.xreplace(sub))
    if scene.kinematics == "consistent":
        axes = b.name(f"e{i}", parent.rotation * joint_jac.xreplace(sub))
        partial_w = list(parent.partial_w)
        partial_w[i], partial_w[sym.n + i] = axes[:, 0], axes[:, 1]
        w_rel = axes[:, 0] * omega + axes[:, 1] * delta
        w = b.name(f"w{i}", parent.w + w_rel)
        jac_rate = (joint_jac_rate[0] * omega + joint_jac_rate[1] * delta).xreplace(sub)
        wb = b.name(
            f"wb{i}", parent.wb + parent.w.cross(w_rel) + parent.rotation * jac_rate * Vec([omega, delta])
        )
    else:  # "pydy-example": the published set_ang_vel(I, omega*I.z + delta*I.x)
        partial_w = [ZERO] * sym.dim
        partial_w[i], partial_w[sym.n + i] = UNIT_Z, UNIT_X
        w = b.name(f"w{i}", UNIT_Z * omega + UNIT_X * delta)
        wb = ZERO
    return _Frame(rotation, w, partial_w, wb)


def _link_points(b: _Builder, sym: _Symbols, i: int, parent: _Parent, frame: _Frame):
    """Link i's mass centre (mid-length) and lower end (its bob, and the next link's joint)
    from the joint down the link's -y axis, with their velocities, partial velocities and
    accelerations at u' = 0 by the rigid-body formulas (v = v_joint + w x r, a = a_joint
    + w' x r + w x (w x r)), a rope's sliding end adding its -v_hoist e_y and the Coriolis
    2 w x (-v_hoist e_y) (its centre is only a pose: a rope is massless); and the link's pose
    (centre and quaternion) as an output.
    Returns (centre, lower end, quaternion)."""
    joint, w, dim = parent.joint, frame.w, sym.dim
    r = b.name(f"r{i}", -sym.reach(i) * frame.rotation[:, 1])
    # a rope's lower end moves along it at -v_hoist e_y relative to the link's frame (an
    # elastic rope's at -v_r e_y)
    slide = -sym.slide(i) * frame.rotation[:, 1]
    w_cross_r = w.cross(r) + slide
    # and accelerates along it at -l'' e_y (an elastic rope's -v_r' e_y is its partial's)
    acc_rel = b.name(
        f"ar{i}",
        frame.wb.cross(r)
        + w.cross(w.cross(r))
        + 2 * w.cross(slide)
        - sym.slide_acc(i) * frame.rotation[:, 1],
    )
    partial_rel = [
        b.name(f"vr{i}_{s}", frame.partial_w[s].cross(r)) if frame.partial_w[s] != ZERO else ZERO
        for s in range(dim)
    ]
    if i in sym.reaches:
        partial_rel[sym.speed_index(i)] = -frame.rotation[:, 1]
    centre = _Point(
        joint.position + r / 2,
        [joint.partials[s] + partial_rel[s] / 2 for s in range(dim)],
        joint.velocity + w_cross_r / 2,
        joint.acc_bias + acc_rel / 2,
    )
    quaternion = _quaternion_times(b, i, parent.quaternion, sym.alpha[i], sym.beta[i])
    end = b.name(f"p{i}", joint.position + r)
    partial_end = [
        b.name(f"vp{i}_{s}", joint.partials[s] + partial_rel[s])
        if joint.partials[s] != ZERO or partial_rel[s] != ZERO
        else ZERO
        for s in range(dim)
    ]
    lower = _Point(
        end,
        partial_end,
        b.name(f"v{i}", joint.velocity + w_cross_r),
        b.name(f"a{i}", joint.acc_bias + acc_rel),
    )
    return centre, lower, quaternion


def _add_particle(sums: _Sums, sym: _Symbols, mass, point: _Point) -> None:
    """A mass at a point (a link's centre or a bob) in Kane's equations: its generalized
    inertia force -m v_s . a adds m v_s . v_t to M and -m v_s . a(u' = 0) to F, and gravity
    (along -Y) -m g v_s[Y] to F; its energies; with coupling, its acceleration gains the
    pivot's, its share of the support force uses the full acceleration (with u'), and
    its momentum per speed (m v_s) goes to P; with ropes, m (a - g) to its link's hangs."""
    dim, g, partials, acc = sym.dim, sym.g, point.partials, point.acc_bias
    if sym.pivot_acc is not None:
        acc = acc + sym.pivot_acc
    if sums.hangs:  # with ropes: what the mass asks of what holds it
        full_acc = acc + sum((partials[s] * sym.rates[s] for s in range(dim)), ZERO)
        sums.hangs[-1] += mass * (full_acc - Vec([0, -g, 0]))
    if sym.pivot_acc is not None:
        full_acc = acc + sum((partials[s] * sym.rates[s] for s in range(dim)), ZERO)
        sums.support_force += mass * (Vec([0, -g, 0]) - full_acc)
        sums.momentum = [sums.momentum[s] + mass * partials[s] for s in range(dim)]
        sums.total_mass += mass
        sums.linear_momentum += mass * point.velocity
    for s in range(dim):
        if partials[s] == ZERO:
            continue
        sums.force_terms[s] += -mass * (partials[s].dot(acc) + g * partials[s][1])
        for t in range(s, dim):
            if partials[t] != ZERO:
                sums.mass_terms[s][t] += mass * partials[s].dot(partials[t])
    sums.kinetic += mass * point.velocity.dot(point.velocity) / 2
    sums.potential += mass * g * point.position[1]


def _add_force(sums: _Sums, sym: _Symbols, point: _Point, force: sm.Matrix) -> sm.Expr:
    """A force F (inertial components) on a point of the chain: F . v_s to F, and with
    coupling its share of the force on the support (Newton's law for the chain: sum m (g - a)
    + F), with ropes -F to its link's hangs. Returns its power F . v (v relative to the pivot,
    as the energy's)."""
    for s in range(sym.dim):
        if point.partials[s] != ZERO:
            sums.force_terms[s] += point.partials[s].dot(force)
    if sym.pivot_acc is not None:
        sums.support_force += force
    if sums.hangs:
        sums.hangs[-1] -= force
    return force.dot(point.velocity)


def _applied_force(sym: _Symbols, i: int) -> sm.Matrix:
    """The force applied to bob i: its inputs F_bob<i>_x/y/z."""
    return Vec([sym.params[f"F_bob{i}_{c}"] for c in "xyz"])


def _drag(b: _Builder, sym: _Symbols, i: int, bob: _Point) -> sm.Matrix:
    """The air's quadratic drag on bob i, -1/2 rho C_d A |v_air| v_air, v_air its velocity
    through the air: relative to the pivot, plus the pivot's (inputs v_pivot, with
    coupling), less the wind (inputs wind_x/y/z). |v_air| is a square root, which the
    complex step differentiates exactly, also at v_air = 0 (the force's derivative is 0)."""
    p = sym.params
    moving = Vec([p[name] for name in PIVOT_VELOCITY]) if sym.pivot_acc is not None else ZERO
    v_air = b.name(f"va{i}", bob.velocity + moving - Vec([p[name] for name in WIND]))
    speed = b.name(f"speed{i}", sm.sqrt(v_air.dot(v_air)))
    return b.name(f"fd{i}", -p["rho"] * p[f"C_d{i}"] * p[f"A{i}"] / 2 * speed * v_air)


def _add_link_rotation(b: _Builder, sums: _Sums, sym: _Symbols, i: int, frame: _Frame) -> None:
    """Link i's rotational inertia in Kane's equations, in body axes where the central
    inertia is diagonal: Euler's torque I w' + w x (I w) at u' = 0 projected on the partial
    angular velocities goes to F, I's products of those partials to M; and its kinetic
    energy."""
    inertia = Vec([sym.params[f"Ixx{i}"], sym.params[f"Iyy{i}"], sym.params[f"Izz{i}"]])
    to_body = frame.rotation.T
    body_w = b.name(f"bw{i}", to_body * frame.w)
    body_h = Vec([inertia[k] * body_w[k] for k in range(3)])
    body_torque = b.name(
        f"bt{i}", Vec([inertia[k] * v for k, v in enumerate(to_body * frame.wb)]) + body_w.cross(body_h)
    )
    body_partial = [
        b.name(f"bpw{i}_{s}", to_body * frame.partial_w[s]) if frame.partial_w[s] != ZERO else ZERO
        for s in range(sym.dim)
    ]
    for s in range(sym.dim):
        if body_partial[s] == ZERO:
            continue
        sums.force_terms[s] += -body_partial[s].dot(body_torque)
        for t in range(s, sym.dim):
            if body_partial[t] != ZERO:
                sums.mass_terms[s][t] += sum(
                    inertia[k] * body_partial[s][k] * body_partial[t][k] for k in range(3)
                )
    sums.kinetic += body_w.dot(body_h) / 2


def _add_elastic_rope(sums: _Sums, sym: _Symbols, i: int) -> None:
    """An elastic rope's pull on its bob in Kane's equations, a generalized force -T on its v_r
    (module docstring), with T and s+ as the core hands them in p; its elastic energy, its
    tension and winch's power (outputs) and its damping's power (W_rope)."""
    p, length = sym.params, sym.lengths[i]
    tension, taut, stiffness = p[f"T_law{i}"], p[f"s_taut{i}"], p[f"EA{i}"]
    sums.force_terms[sym.speed_index(i)] -= tension
    sums.potential += stiffness * taut**2 / (2 * length)
    sums.tensions.append(tension)
    sums.hoist_power.append(-(tension + stiffness * taut**2 / (2 * length**2)) * sym.hoist(i))
    stretch_rate = sym.reach_rates[i] - sym.hoist(i)
    sums.rope_damping_power.append((stiffness * taut / length - tension) * stretch_rate)


def _mass_matrix_and_forcing(scene: Scene, sums: _Sums, dim: int) -> tuple[sm.Matrix, sm.Matrix]:
    """M (symmetric: the upper triangle mirrored) and F; the published model's come from
    the seed's own KanesMethod derivation instead (module docstring)."""
    if scene.kinematics == "pydy-example":
        return kanes_method(scene)
    return (
        sm.Matrix(dim, dim, lambda s, t: sums.mass_terms[min(s, t)][max(s, t)]),
        sm.Matrix(sums.force_terms),
    )


def _outputs(scene: Scene, sym: _Symbols, sums: _Sums, bobs: list, poses: list) -> list[sm.Expr]:
    """The calculated outputs the scene asks for, in the FMU's order (Scene.output_names; the
    pivot's F_free and M_app, which dynamics.c computes, left out)."""
    outputs = []
    if "bobs" in scene.outputs:
        outputs += [c for p in bobs for c in p]
    if "poses" in scene.outputs:
        outputs += [c for centre, quat in poses for c in list(centre) + list(quat)]
    if "energy" in scene.outputs:
        outputs.append(sums.kinetic + sums.potential)
    if scene.coupling:
        outputs += list(sums.support_force)
    stretches = [sym.reaches[i] - sym.lengths[i] for i in sym.elastic]
    margins = [sym.params[f"margin{i}"] for i in sym.elastic]  # the law's (cp_rope_law)
    return outputs + sums.tensions + sums.hoist_power + stretches + margins


def derive(scene: Scene) -> Equations:
    """The scene's equations, link by link from the pivot down: each link's frame and
    points from its parent's, then each body's share of Kane's equations; then M, F and
    the outputs. Every per-link quantity is named (_Builder), in this order."""
    sym = _symbols(scene)
    ja, jb, joint_dcm, joint_jac = joint_kinematics()
    joint = (ja, jb, joint_dcm, joint_jac, [joint_jac.diff(ja), joint_jac.diff(jb)])
    b, sums, parent = _Builder(), _Sums.empty(sym.dim), _Parent.pivot(sym.dim)
    bobs, poses, dragged, axes = [], [], scene.dragged_bobs(), []
    for i, link in enumerate(scene.links):
        frame = _link_frame(b, scene, sym, joint, i, parent.frame)
        centre, lower, quaternion = _link_points(b, sym, i, parent, frame)
        axes.append(frame.rotation[:, 1])
        if scene.ropes():
            sums.hangs.append(ZERO)
        poses.append((centre.position, quaternion))
        if link.has_mass:
            _add_particle(sums, sym, sym.params[f"M{i}"], centre)
        if link.has_bob:
            _add_particle(sums, sym, sym.params[f"m{i}"], lower)
            bobs.append(lower.position)
        if link.bob_force:
            sums.external_power += _add_force(sums, sym, lower, _applied_force(sym, i))
        if i in dragged:
            sums.drag_power += _add_force(sums, sym, lower, _drag(b, sym, i, lower))
        if link.has_mass:
            _add_link_rotation(b, sums, sym, i, frame)
        parent = _Parent(frame, lower, quaternion)
    if scene.joint_damping:
        sums.force_terms[: 2 * sym.n] = [f + q for f, q in zip(sums.force_terms, joint_damping(scene)[0])]
    for i in scene.ropes():
        if i in sym.reaches:
            _add_elastic_rope(sums, sym, i)
            continue
        held = sum(sums.hangs[i:], ZERO)  # the rope holds what hangs below its joint, along e_y
        sums.tensions.append(b.name(f"tension{i}", axes[i].dot(held)))
        sums.hoist_power.append(-sums.tensions[-1] * sym.hoist(i))
    mass_matrix, forcing = _mass_matrix_and_forcing(scene, sums, sym.dim)
    return Equations(
        scene=scene,
        states=list(sym.alpha)
        + list(sym.beta)
        + [sym.reaches[i] for i in sym.elastic]
        + list(sym.omega)
        + list(sym.delta)
        + [sym.reach_rates[i] for i in sym.elastic]
        + [sym.lengths[i] for i in scene.ropes()],
        params=[sym.params[name] for name in _core_p_names(scene)],
        rates=list(sym.rates),
        definitions=b.definitions,
        mass_matrix=mass_matrix,
        forcing=forcing,
        outputs=_outputs(scene, sym, sums, bobs, poses),
        momentum=sm.Matrix.hstack(*sums.momentum) if scene.coupling else None,
        total_mass=sums.total_mass if scene.coupling else None,
        work_rates=_work_rates(scene, sym, sums),
        rope_rates=[sym.hoist(i) for i in scene.ropes()],
        energy=sums.kinetic + sums.potential,
    )


def _quaternion_times(b, i, parent, a, c):
    """Orientation quaternion (w, x, y, z) of link i: parent * qx(beta) * qz(alpha).

    'Space' 'ZXY' rotates first about the parent's z by alpha, then about the parent's
    x by beta, so the relative rotation is Rx(beta) Rz(alpha).
    """
    ca, sa, cb, sb = sm.cos(a / 2), sm.sin(a / 2), sm.cos(c / 2), sm.sin(c / 2)
    rel = (cb * ca, sb * ca, -sb * sa, cb * sa)
    w1, x1, y1, z1 = parent
    w2, x2, y2, z2 = rel
    product = (
        w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
        w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
        w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
    )
    return tuple(b.name(f"q{i}_{k}", v) for k, v in enumerate(product))
