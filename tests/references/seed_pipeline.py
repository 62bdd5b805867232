"""The seed document's own pipeline (PyDy's three-link example, as published).

Kept verbatim in substance so that the published model can be checked number for
number and benchmarked: sympy's KanesMethod with the seed's kinematics, then pydy's
Cython code generation. Needs pydy (the test extra); used by tests and benchmarks only.
"""


def seed_right_hand_side(linear_sys_solver="sympy"):
    """The seed document's derivation and code generation, as published (n = 3).

    Returns pydy's Cython right-hand side f(x, t, p) and the parameter values of the
    seed in its parameter order. linear_sys_solver="numpy" solves M numerically instead
    of pydy's symbolic LU.
    """
    import sympy.physics.mechanics as me
    from pydy.codegen.ode_function_generators import generate_ode_function
    from sympy import symbols

    n = 3
    alpha = me.dynamicsymbols(f"alpha:{n}")
    beta = me.dynamicsymbols(f"beta:{n}")
    omega = me.dynamicsymbols(f"omega:{n}")
    delta = me.dynamicsymbols(f"delta:{n}")
    m_bob = symbols(f"m:{n}")
    l = symbols(f"l:{n}")
    m_link = symbols(f"M:{n}")
    Ixx = symbols(f"Ixx:{n}")
    Iyy = symbols(f"Iyy:{n}")
    Izz = symbols(f"Izz:{n}")
    g = symbols("g")
    I = me.ReferenceFrame("I")
    A = me.ReferenceFrame("A")
    A.orient(I, "Space", [alpha[0], beta[0], 0], "ZXY")
    B = me.ReferenceFrame("B")
    B.orient(A, "Space", [alpha[1], beta[1], 0], "ZXY")
    C = me.ReferenceFrame("C")
    C.orient(B, "Space", [alpha[2], beta[2], 0], "ZXY")
    kinematic_differentials = []
    for i in range(n):
        kinematic_differentials.append(omega[i] - alpha[i].diff())
        kinematic_differentials.append(delta[i] - beta[i].diff())
    A.set_ang_vel(I, omega[0] * I.z + delta[0] * I.x)
    B.set_ang_vel(I, omega[1] * I.z + delta[1] * I.x)
    C.set_ang_vel(I, omega[2] * I.z + delta[2] * I.x)
    O = me.Point("O")
    O.set_vel(I, 0)
    P1 = O.locatenew("P1", -l[0] * A.y)
    P2 = P1.locatenew("P2", -l[1] * B.y)
    P3 = P2.locatenew("P3", -l[2] * C.y)
    P1.v2pt_theory(O, I, A)
    P2.v2pt_theory(P1, I, B)
    P3.v2pt_theory(P2, I, C)
    points = [P1, P2, P3]
    Pa1 = me.Particle("Pa1", points[0], m_bob[0])
    Pa2 = me.Particle("Pa2", points[1], m_bob[1])
    Pa3 = me.Particle("Pa3", points[2], m_bob[2])
    particles = [Pa1, Pa2, Pa3]
    P_link1 = O.locatenew("P_link1", -l[0] / 2 * A.y)
    P_link2 = P1.locatenew("P_link2", -l[1] / 2 * B.y)
    P_link3 = P2.locatenew("P_link3", -l[2] / 2 * C.y)
    P_link1.v2pt_theory(O, I, A)
    P_link2.v2pt_theory(P1, I, B)
    P_link3.v2pt_theory(P2, I, C)
    inertia_link1 = (me.inertia(A, Ixx[0], Iyy[0], Izz[0]), P_link1)
    inertia_link2 = (me.inertia(B, Ixx[1], Iyy[1], Izz[1]), P_link2)
    inertia_link3 = (me.inertia(C, Ixx[2], Iyy[2], Izz[2]), P_link3)
    link1 = me.RigidBody("link1", P_link1, A, m_link[0], inertia_link1)
    link2 = me.RigidBody("link2", P_link2, B, m_link[1], inertia_link2)
    link3 = me.RigidBody("link3", P_link3, C, m_link[2], inertia_link3)
    links = [link1, link2, link3]
    forces = []
    for particle in particles:
        forces.append((particle.point, -particle.mass * g * I.y))
    for link in links:
        forces.append((link.masscenter, -link.mass * g * I.y))
    total_system = links + particles
    q = alpha + beta
    u = omega + delta
    kane = me.KanesMethod(I, q_ind=q, u_ind=u, kd_eqs=kinematic_differentials)
    kane.kanes_equations(total_system, loads=forces)
    param_syms = []
    for par_seq in [l, m_bob, m_link, Ixx, Iyy, Izz, (g,)]:
        param_syms += list(par_seq)
    rhs = generate_ode_function(
        kane.forcing_full,
        q,
        u,
        param_syms,
        mass_matrix=kane.mass_matrix_full,
        generator="cython",
        linear_sys_solver=linear_sys_solver,
    )
    link_length, link_mass, link_radius, particle_mass = 10.0, 10.0, 0.5, 5.0
    link_ixx = 1.0 / 12.0 * link_mass * (3.0 * link_radius**2 + link_length**2)
    link_iyy = link_mass * link_radius**2
    param_vals = (
        [link_length] * n
        + [particle_mass] * n
        + [link_mass] * n
        + [link_ixx] * n
        + [link_iyy] * n
        + [link_ixx] * n
        + [9.8]
    )
    return rhs, param_vals
