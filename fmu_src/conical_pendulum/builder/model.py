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

With coupling, the pivot accelerates by a_pivot (inputs, inertial components): every
mass centre's acceleration gains a_pivot. The force on the support is Newton's law for
the whole chain, sum m (g - a), so it needs u' (the symbols `rates`).

The published model (kinematics="pydy-example") cannot be formed this way: its
equations are whatever sympy derives from contradictory kinematics, so they come from
running the seed's own KanesMethod derivation (see build.kane).
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sm
import sympy.physics.mechanics as me

from ..scene import Scene
from .kane import kanes_method

Vec = sm.Matrix


@dataclass
class Equations:
    """M(x, p) u' = F(x, p), with intermediate definitions evaluated in order.

    p holds the parameters, then the inputs; outputs may depend on u' (`rates`)."""

    scene: Scene
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

    def lambdify(self):
        """Numpy functions (x, p) -> M, F and (x, p, u') -> outputs of these very
        expressions (for checks)."""
        cse = lambda exprs: (self.definitions, exprs)  # noqa: E731 - lambdify's hook
        args = [self.states, self.params]
        return (sm.lambdify(args, self.mass_matrix, cse=cse),
                sm.lambdify(args, self.forcing, cse=cse),
                sm.lambdify(args + [self.rates], self.outputs, cse=cse))


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


class _Builder:
    """Collects named intermediate quantities in evaluation order."""

    def __init__(self):
        self.definitions: list[tuple[sm.Symbol, sm.Expr]] = []

    def name(self, label: str, value):
        """Give a scalar or vector (Matrix) value a name unless it is trivial."""
        if isinstance(value, sm.MatrixBase):
            return Vec([self.name(f"{label}_{k}", v) for k, v in enumerate(value)]).reshape(*value.shape)
        value = sm.sympify(value)
        if value.is_Atom or (value.is_Mul and len(value.args) == 2 and value.args[0].is_Number
                             and value.args[1].is_Atom):
            return value
        symbol = sm.Symbol(label)
        self.definitions.append((symbol, value))
        return symbol


def derive(scene: Scene) -> Equations:
    n = scene.n
    alpha = sm.symbols(f"alpha0:{n}")
    beta = sm.symbols(f"beta0:{n}")
    omega = sm.symbols(f"omega0:{n}")
    delta = sm.symbols(f"delta0:{n}")
    speeds = list(omega) + list(delta)
    param_symbols = {name: sm.Symbol(name) for name in scene.core_parameter_names()}
    P = param_symbols.__getitem__
    g = P("g")
    rates = sm.symbols(f"domega0:{n}") + sm.symbols(f"ddelta0:{n}")
    pivot_acc = Vec([P(name) for name in scene.input_names()]) if scene.coupling else None
    zero, unit_x, unit_z = Vec([0, 0, 0]), Vec([1, 0, 0]), Vec([0, 0, 1])
    ja, jb, joint_dcm, joint_jac = joint_kinematics()
    joint_jac_rate = [joint_jac.diff(ja), joint_jac.diff(jb)]

    b = _Builder()
    dim = 2 * n
    rotation = sm.eye(3)              # parent's axes in inertial components
    w_parent = zero                   # parent's angular velocity
    wb_parent = zero                  # parent's angular acceleration at u' = 0
    partial_w_parent = [zero] * dim   # parent's partial angular velocities
    joint = zero                      # position of the joint above the current link
    joint_vel = zero
    joint_acc_bias = zero
    partial_joint = [zero] * dim

    mass_terms = [[0] * dim for _ in range(dim)]
    force_terms = [0] * dim
    kinetic, potential = 0, 0
    support_force = Vec([0, 0, 0])   # sum of m (g - a) over the bodies: force on the support
    momentum = [zero] * dim           # sum of m times the partial velocities: P's columns
    total_mass = 0
    bob_positions, poses = [], []
    quat_parent = (1, 0, 0, 0)

    for i, link in enumerate(scene.links):
        sub = {ja: alpha[i], jb: beta[i]}
        parent_rotation = rotation
        rotation = b.name(f"R{i}", parent_rotation * joint_dcm.xreplace(sub))
        # Angular velocity, its partials and its u'-free derivative.
        if scene.kinematics == "consistent":
            axes = b.name(f"e{i}", parent_rotation * joint_jac.xreplace(sub))
            partial_w = list(partial_w_parent)
            partial_w[i], partial_w[n + i] = axes[:, 0], axes[:, 1]
            w_rel = axes[:, 0] * omega[i] + axes[:, 1] * delta[i]
            w = b.name(f"w{i}", w_parent + w_rel)
            jac_rate = (joint_jac_rate[0] * omega[i] + joint_jac_rate[1] * delta[i]).xreplace(sub)
            wb = b.name(f"wb{i}", wb_parent + w_parent.cross(w_rel)
                        + parent_rotation * jac_rate * Vec([omega[i], delta[i]]))
        else:  # "pydy-example": the published set_ang_vel(I, omega*I.z + delta*I.x)
            partial_w = [zero] * dim
            partial_w[i], partial_w[n + i] = unit_z, unit_x
            w = b.name(f"w{i}", unit_z * omega[i] + unit_x * delta[i])
            wb = zero
        # Points of the link: r from the joint to the bob, centre of mass at r/2.
        r = b.name(f"r{i}", -P(f"l{i}") * rotation[:, 1])
        w_cross_r = w.cross(r)
        acc_rel = b.name(f"ar{i}", wb.cross(r) + w.cross(w_cross_r))
        partial_rel = [b.name(f"vr{i}_{s}", partial_w[s].cross(r)) if partial_w[s] != zero else zero
                       for s in range(dim)]
        centre = joint + r / 2
        poses.append((centre, _quaternion_times(b, i, quat_parent, alpha[i], beta[i])))
        quat_parent = poses[-1][1]
        bodies = []
        if link.has_mass:
            partial_c = [partial_joint[s] + partial_rel[s] / 2 for s in range(dim)]
            bodies.append((P(f"M{i}"), centre, partial_c, joint_vel + w_cross_r / 2,
                           joint_acc_bias + acc_rel / 2))
        bob = b.name(f"p{i}", joint + r)
        partial_bob = [b.name(f"vp{i}_{s}", partial_joint[s] + partial_rel[s])
                       if partial_joint[s] != zero or partial_rel[s] != zero else zero
                       for s in range(dim)]
        bob_vel = b.name(f"v{i}", joint_vel + w_cross_r)
        bob_acc = b.name(f"a{i}", joint_acc_bias + acc_rel)
        if link.has_bob:
            bodies.append((P(f"m{i}"), bob, partial_bob, bob_vel, bob_acc))
            bob_positions.append(bob)
        # Kane: Fr + Fr* = 0 with Fr* = -M u' + (terms at u' = 0).
        for mass, point, partials, vel, acc in bodies:
            if pivot_acc is not None:
                acc = acc + pivot_acc
                full_acc = acc + sum((partials[s] * rates[s] for s in range(dim)), zero)
                support_force += mass * (Vec([0, -g, 0]) - full_acc)
                momentum = [momentum[s] + mass * partials[s] for s in range(dim)]
                total_mass += mass
            for s in range(dim):
                if partials[s] == zero:
                    continue
                force_terms[s] += -mass * (partials[s].dot(acc) + g * partials[s][1])
                for t in range(s, dim):
                    if partials[t] != zero:
                        mass_terms[s][t] += mass * partials[s].dot(partials[t])
            kinetic += mass * vel.dot(vel) / 2
            potential += mass * g * point[1]
        if link.has_mass:
            inertia = Vec([P(f"Ixx{i}"), P(f"Iyy{i}"), P(f"Izz{i}")])
            to_body = rotation.T
            body_w = b.name(f"bw{i}", to_body * w)
            body_h = Vec([inertia[k] * body_w[k] for k in range(3)])
            body_torque = b.name(f"bt{i}", Vec([inertia[k] * v for k, v in enumerate(to_body * wb)])
                                 + body_w.cross(body_h))
            body_partial = [b.name(f"bpw{i}_{s}", to_body * partial_w[s]) if partial_w[s] != zero
                            else zero for s in range(dim)]
            for s in range(dim):
                if body_partial[s] == zero:
                    continue
                force_terms[s] += -body_partial[s].dot(body_torque)
                for t in range(s, dim):
                    if body_partial[t] != zero:
                        mass_terms[s][t] += sum(inertia[k] * body_partial[s][k] * body_partial[t][k]
                                                for k in range(3))
            kinetic += body_w.dot(body_h) / 2
        w_parent, wb_parent, partial_w_parent = w, wb, partial_w
        joint, joint_vel, joint_acc_bias, partial_joint = bob, bob_vel, bob_acc, partial_bob

    if scene.kinematics == "pydy-example":
        mass_matrix, forcing = kanes_method(scene)
    else:
        mass_matrix = sm.Matrix(dim, dim, lambda s, t: mass_terms[min(s, t)][max(s, t)])
        forcing = sm.Matrix(force_terms)
    outputs = []
    if "bobs" in scene.outputs:
        outputs += [c for p in bob_positions for c in p]
    if "poses" in scene.outputs:
        outputs += [c for centre, quat in poses for c in list(centre) + list(quat)]
    if "energy" in scene.outputs:
        outputs.append(kinetic + potential)
    if scene.coupling:
        outputs += list(support_force)
    return Equations(
        scene=scene,
        states=list(alpha) + list(beta) + speeds,
        params=[param_symbols[name] for name in scene.core_parameter_names()],
        rates=list(rates),
        definitions=b.definitions,
        mass_matrix=mass_matrix,
        forcing=forcing,
        outputs=outputs,
        momentum=sm.Matrix.hstack(*momentum) if scene.coupling else None,
        total_mass=total_mass if scene.coupling else None,
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
    product = (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
               w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
               w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
               w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)
    return tuple(b.name(f"q{i}_{k}", v) for k, v in enumerate(product))
