"""sympy's own KanesMethod on the seed's construction, generalized to n links.

With kinematics="pydy-example" this is the published model: the seed's
set_ang_vel(I, omega*I.z + delta*I.x) contradicts its orient calls, and what sympy then
derives depends on the frames it happens to express vectors in, so the only faithful
reproduction is to run the same derivation. Its expressions grow exponentially with n.
With kinematics="consistent" it is the reference the fast derivation is tested against,
with a moving pivot too, and, in `cart_and_pendulum`, the monolithic model of the
coupled demo.
"""
import sympy as sm
import sympy.physics.mechanics as me

CART_PARAMETERS = ("m_cart", "k_cart", "c_cart")


def _chain(scene, I, O, p):
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
    return bodies, loads, alpha + beta, omega + delta, kd


def kanes_method(scene):
    """Mass matrix and forcing (M u' = F) of the scene from sympy's KanesMethod.

    Bodies the scene leaves out are not created. With coupling, the pivot moves with a
    prescribed velocity whose derivative becomes the inputs a_pivot_x/y/z. Returns (M, F)
    in plain symbols named as Scene.state_names() and Scene.core_parameter_names().
    """
    p = {name: sm.Symbol(name) for name in scene.core_parameter_names()}
    I = me.ReferenceFrame("I")
    O = me.Point("O")
    pivot_velocity = me.dynamicsymbols("v_pivot_x v_pivot_y v_pivot_z") if scene.coupling else [0] * 3
    O.set_vel(I, sum((v * axis for v, axis in zip(pivot_velocity, (I.x, I.y, I.z))), me.Vector(0)))
    bodies, loads, q, u, kd = _chain(scene, I, O, p)
    kane = me.KanesMethod(I, q_ind=q, u_ind=u, kd_eqs=kd)
    kane.kanes_equations(bodies, loads)
    plain = {s: sm.Symbol(name) for s, name in zip(q + u, scene.state_names())}
    if scene.coupling:
        plain.update({v.diff(): p[name] for v, name in zip(pivot_velocity, scene.input_names())})
    return me.msubs(kane.mass_matrix, plain), me.msubs(kane.forcing, plain)


def cart_and_pendulum(scene):
    """The coupled demo as one model: the chain hanging from a cart on a spring and damper.

    The cart (mass m_cart) moves along X, held by a spring k_cart and a damper c_cart to
    the ground. Returns (M, F, states, params): M u' = F with states (x_cart, angles,
    v_cart, rates) and params the scene's parameters followed by CART_PARAMETERS, as
    plain symbols.
    """
    p = {name: sm.Symbol(name) for name in scene.parameter_names() + list(CART_PARAMETERS)}
    x, v = me.dynamicsymbols("x_cart v_cart")
    I = me.ReferenceFrame("I")
    O = me.Point("O")
    O.set_pos(me.Point("ground"), x * I.x)
    O.set_vel(I, v * I.x)
    bodies, loads, q, u, kd = _chain(scene, I, O, p)
    bodies.append(me.Particle("cart", O, p["m_cart"]))
    loads.append((O, (-p["k_cart"] * x - p["c_cart"] * v) * I.x))
    kane = me.KanesMethod(I, q_ind=[x] + q, u_ind=[v] + u, kd_eqs=[v - x.diff()] + kd)
    kane.kanes_equations(bodies, loads)
    names = ["x_cart"] + scene.state_names()[:2 * scene.n] + ["v_cart"] + scene.state_names()[2 * scene.n:]
    states = [sm.Symbol(name) for name in names]
    plain = dict(zip([x] + q + [v] + u, states))
    params = [p[name] for name in scene.parameter_names() + list(CART_PARAMETERS)]
    return me.msubs(kane.mass_matrix, plain), me.msubs(kane.forcing, plain), states, params
