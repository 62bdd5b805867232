"""sympy's own KanesMethod on the seed's construction, generalized to n links.

With kinematics="pydy-example" this is the published model: the seed's
set_ang_vel(I, omega*I.z + delta*I.x) contradicts its orient calls, and what sympy then
derives depends on the frames it happens to express vectors in, so the only faithful
reproduction is to run the same derivation. Its expressions grow exponentially with n.
With kinematics="consistent" it is the reference the fast derivation is tested against.
"""
import sympy as sm
import sympy.physics.mechanics as me


def kanes_method(scene):
    """Mass matrix and forcing (M u' = F) of the scene from sympy's KanesMethod.

    Bodies the scene leaves out are not created. Returns (M, F) in plain symbols named
    as Scene.state_names() and Scene.parameter_names().
    """
    n = scene.n
    alpha = me.dynamicsymbols(f"alpha0:{n}")
    beta = me.dynamicsymbols(f"beta0:{n}")
    omega = me.dynamicsymbols(f"omega0:{n}")
    delta = me.dynamicsymbols(f"delta0:{n}")
    p = {name: sm.Symbol(name) for name in scene.parameter_names()}
    I = me.ReferenceFrame("I")
    O = me.Point("O")
    O.set_vel(I, 0)
    parent, joint, bodies, loads = I, O, [], []
    for i, link in enumerate(scene.links):
        F = me.ReferenceFrame(f"F{i}")
        F.orient(parent, "Space", [alpha[i], beta[i], 0], "ZXY")
        if scene.kinematics == "pydy-example":
            F.set_ang_vel(I, omega[i] * I.z + delta[i] * I.x)
        length = p[f"l{i}"]
        P = joint.locatenew(f"P{i}", -length * F.y)
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
        parent, joint = F, P
    kd = [omega[i] - alpha[i].diff() for i in range(n)] + [delta[i] - beta[i].diff() for i in range(n)]
    kane = me.KanesMethod(I, q_ind=alpha + beta, u_ind=omega + delta, kd_eqs=kd)
    kane.kanes_equations(bodies, loads)
    to_plain = {s: sm.Symbol(name) for s, name in zip(alpha + beta + omega + delta, scene.state_names())}
    return me.msubs(kane.mass_matrix, to_plain), me.msubs(kane.forcing, to_plain)
