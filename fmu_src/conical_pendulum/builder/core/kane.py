"""sympy's own KanesMethod on the seed's construction, generalized to n links.

With kinematics="pydy-example" this is the published model: the seed's
set_ang_vel(I, omega*I.z + delta*I.x) contradicts its orient calls, and what sympy then
derives depends on the frames it happens to express vectors in, so the only faithful
reproduction is to run the same derivation. Its expressions grow exponentially with n.
With kinematics="consistent" it is the reference the fast derivation is tested against,
with a moving pivot, ropes (a length that is a function of time, its end sliding along the
rope; then l' = v_hoist and l'' = a_hoist) and the scene's forces too (joint damping, the air's drag
from each bob's inertial velocity, applied forces: sympy's loads on frames and points); the coupled
demo's monolithic model builds on `chain`.
"""

import sympy as sm
import sympy.physics.mechanics as me

from ...scene import PIVOT_VELOCITY, WIND


def chain(scene, I, O, p):
    """Bodies and gravity loads of the scene's links hanging from point O, and its speeds."""
    n = scene.n
    alpha = me.dynamicsymbols(f"alpha0:{n}")
    beta = me.dynamicsymbols(f"beta0:{n}")
    omega = me.dynamicsymbols(f"omega0:{n}")
    delta = me.dynamicsymbols(f"delta0:{n}")
    parent, joint, bodies, loads = I, O, [], []
    for i, link in enumerate(scene.links):
        F = me.ReferenceFrame(f"F{i}")
        F.orient(parent, "Space", [alpha[i], beta[i], 0], "ZXY")
        if scene.kinematics == "pydy-example":
            F.set_ang_vel(I, omega[i] * I.z + delta[i] * I.x)
        length = me.dynamicsymbols(f"l{i}") if link.rope else p[f"l{i}"]
        P = joint.locatenew(f"P{i}", -length * F.y)
        if link.rope:  # a rope's end slides along it as its length changes
            P.set_vel(F, -length.diff() * F.y)
            P.v1pt_theory(joint, I, F)
        else:
            P.v2pt_theory(joint, I, F)
        if link.has_mass:
            G = joint.locatenew(f"G{i}", -length / 2 * F.y)
            G.v2pt_theory(joint, I, F)
            inertia = me.inertia(F, p[f"Ixx{i}"], p[f"Iyy{i}"], p[f"Izz{i}"])
            bodies.append(me.RigidBody(f"L{i}", G, F, p[f"M{i}"], (inertia, G)))
            loads.append((G, -p[f"M{i}"] * p["g"] * I.y))
        if link.has_bob:
            bodies.append(me.Particle(f"B{i}", P, p[f"m{i}"]))
            loads.append((P, -p[f"m{i}"] * p["g"] * I.y))
        loads += _forces(scene, I, parent, F, P, p, i)
        parent, joint = F, P
    kd = [omega[i] - alpha[i].diff() for i in range(n)] + [delta[i] - beta[i].diff() for i in range(n)]
    return bodies, loads, alpha + beta, omega + delta, kd


def _forces(scene, I, parent, F, P, p, i):
    """Link i's share of the scene's forces as sympy loads: its joint's damping torque
    -c w_rel on the link and +c w_rel on its parent, the air's drag on its bob from the bob's
    velocity in I (the pivot's included) less the wind, and the force applied to its bob."""
    loads = []
    if scene.joint_damping:
        torque = -p[f"c{i}"] * F.ang_vel_in(parent)
        loads += [(F, torque), (parent, -torque)]
    if i in scene.dragged_bobs():
        v_air = P.vel(I) - _inertial(I, [p[name] for name in WIND])
        speed = sm.sqrt(v_air.dot(v_air))
        loads.append((P, -p["rho"] * p[f"C_d{i}"] * p[f"A{i}"] / 2 * speed * v_air))
    if scene.links[i].bob_force:
        loads.append((P, _inertial(I, [p[f"F_bob{i}_{c}"] for c in "xyz"])))
    return loads


def _inertial(I, components) -> me.Vector:
    """The vector of these x, y, z components in frame I."""
    return sum((c * axis for c, axis in zip(components, (I.x, I.y, I.z))), me.Vector(0))


def kanes_method(scene):
    """Mass matrix and forcing (M u' = F) of the scene from sympy's KanesMethod.

    Bodies the scene leaves out are not created. With coupling, the pivot moves with a
    prescribed velocity whose derivative becomes the inputs a_pivot_x/y/z. Returns (M, F)
    in plain symbols named as Scene.state_names(), Scene.core_parameter_names() and
    Scene.hoist_acceleration_names().
    """
    p = {name: sm.Symbol(name) for name in scene.core_parameter_names()}
    I = me.ReferenceFrame("I")
    O = me.Point("O")
    pivot_velocity = me.dynamicsymbols("v_pivot_x v_pivot_y v_pivot_z") if scene.coupling else [0] * 3
    O.set_vel(I, _inertial(I, pivot_velocity))
    bodies, loads, q, u, kd = chain(scene, I, O, p)
    kane = me.KanesMethod(I, q_ind=q, u_ind=u, kd_eqs=kd)
    kane.kanes_equations(bodies, loads)
    plain = {s: sm.Symbol(name) for s, name in zip(q + u, scene.state_names())}
    # a rope's length, a function of time: l' = v_hoist, l'' = a_hoist
    for i, acceleration in zip(scene.ropes(), scene.hoist_acceleration_names()):
        length = me.dynamicsymbols(f"l{i}")
        plain.update(
            {length.diff(me.dynamicsymbols._t, 2): sm.Symbol(acceleration), length.diff(): p[f"v_hoist{i}"]}
        )
        plain[length] = sm.Symbol(f"l{i}")
    if scene.coupling:  # the pivot's acceleration, and its velocity where the drag sees it
        plain.update({v.diff(): p[name] for v, name in zip(pivot_velocity, scene.input_names())})
        plain.update({v: p[name] for v, name in zip(pivot_velocity, PIVOT_VELOCITY) if name in p})
    return me.msubs(kane.mass_matrix, plain), me.msubs(kane.forcing, plain)
