"""The scene's chain in MuJoCo, a model nobody here wrote, to check ours against.

As benchmarks/chain_scaling.py builds it (each link a body with hinges about its parent's x
then its own z at its top: the joint's Rx(beta) Rz(alpha)), but with each body's inertia
given exactly (the link's cylinder and a point bob: MuJoCo's sphere geom would give the bob
a radius), no contacts, and MuJoCo's RK4 at a small step. MuJoCo's hinge damping is -c q'
per hinge: with the joint's orthonormal axes, the same torque -c w_rel as the scene's. The
air's drag on the bobs is computed here, in mjcb_passive, which MuJoCo calls at every stage of
its RK4: a force at each bob's site from the site's velocity and the wind, added to the passive
forces with mj_applyFT.
"""

import numpy as np

from conical_pendulum import Scene


def body_inertial(link) -> str:
    """Link and bob as one rigid body: mass, centre (on the link's -y axis) and central
    inertia, diagonal in the link's axes. A bob with an applied force is a body of its own
    (bob_body)."""
    bodies = ([(link.mass, -link.length / 2)] if link.has_mass else []) + (
        [(link.bob_mass, -link.length)] if link.has_bob and not link.bob_force else []
    )
    mass = sum(m for m, _ in bodies)
    centre = sum(m * y for m, y in bodies) / mass
    ixx, iyy, izz = link.inertia() if link.has_mass else (0.0, 0.0, 0.0)
    transverse = sum(m * (y - centre) ** 2 for m, y in bodies)
    return (
        f'<inertial pos="0 {centre!r} 0" mass="{mass!r}" '
        f'diaginertia="{ixx + transverse!r} {max(iyy, 1e-300)!r} {izz + transverse!r}"/>'
    )


def bob_body(i: int, link) -> str:
    """A bob that takes a force: a body welded to its link (no joint) at the link's end, so
    that MuJoCo's xfrc_applied, which acts at a body's centre of mass, acts at the bob. Its
    inertia must be positive in MuJoCo: 1e-12 kg m2, some 1e-15 of the chain's."""
    return (
        f'<body name="bob{i}" pos="0 {-link.length!r} 0"><inertial pos="0 0 0" '
        f'mass="{link.bob_mass!r}" diaginertia="1e-12 1e-12 1e-12"/></body>'
    )


def mjcf(scene: Scene, timestep: float) -> str:
    xml = ""  # built from the lowest link up
    for i in reversed(range(scene.n)):
        link = scene.links[i]
        top = "0 0 0" if i == 0 else f"0 {-scene.links[i - 1].length!r} 0"
        damping = f' damping="{link.damping!r}"' if scene.joint_damping else ""
        site = f'<site name="bob{i}" pos="0 {-link.length!r} 0"/>' if link.has_bob else ""
        xml = (
            f'<body name="link{i}" pos="{top}">{body_inertial(link)}'
            f'<joint type="hinge" axis="1 0 0"{damping}/><joint type="hinge" axis="0 0 1"{damping}/>'
            f"{site}{bob_body(i, link) if link.bob_force else ''}{xml}</body>"
        )
    return (
        f'<mujoco><option gravity="0 {-scene.gravity!r} 0" integrator="RK4" timestep="{timestep!r}">'
        '<flag contact="disable"/></option>'
        f"<worldbody>{xml}</worldbody></mujoco>"
    )


def drag_callback(scene: Scene, wind, parameters: dict | None = None):
    """An mjcb_passive adding the air's drag on every bob, -1/2 rho C_d A |v - w| (v - w), at
    the scene's (or `parameters`') rho, C_d<i> and A<i> and the wind w (3 numbers), at the
    bob's site: its velocity from mj_objectVelocity, the force by mj_applyFT."""
    import mujoco

    values = dict(zip(scene.parameter_names(), scene.parameter_defaults())) | (parameters or {})
    bobs = scene.dragged_bobs()
    scale = [-0.5 * values["rho"] * values[f"C_d{i}"] * values[f"A{i}"] for i in bobs]
    velocity, torque = np.zeros(6), np.zeros(3)

    def passive(model, data):
        for i, k in zip(bobs, scale):
            site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"bob{i}")
            mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_SITE, site, velocity, 0)
            v_air = velocity[3:] - wind
            force = k * np.linalg.norm(v_air) * v_air
            body = model.site_bodyid[site]
            mujoco.mj_applyFT(model, data, force, torque, data.site_xpos[site], body, data.qfrc_passive)

    return passive


def simulate_mujoco(scene: Scene, state: dict, times, timestep=1e-3, applied=None, passive=None):
    """The angles (alpha, beta per link, scene order) at `times` (multiples of timestep from
    0). applied(t, data, bodies): sets data.xfrc_applied before each step (bodies: the body
    id of each bob with a force, by link), if given; passive: MuJoCo's mjcb_passive while it
    runs (drag_callback), if given."""
    import mujoco

    model = mujoco.MjModel.from_xml_string(mjcf(scene, timestep))
    data = mujoco.MjData(model)
    mujoco.set_mjcb_passive(passive)
    try:
        return _run(scene, model, data, state, times, timestep, applied)
    finally:
        mujoco.set_mjcb_passive(None)


def _run(scene, model, data, state, times, timestep, applied):
    import mujoco

    x = dict(zip(scene.state_names(), scene.initial_state(state)))
    n = scene.n
    data.qpos[:] = [x[f"{name}{i}"] for i in range(n) for name in ("beta", "alpha")]
    data.qvel[:] = [x[f"{name}{i}"] for i in range(n) for name in ("delta", "omega")]
    bodies = {i: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"bob{i}") for i in scene.forced_bobs()}
    steps = np.rint(np.asarray(times) / timestep).astype(int)
    angles, done = [], 0
    for target in steps:
        while done < target:
            if applied:
                applied(done * timestep, data, bodies)
            mujoco.mj_step(model, data)
            done += 1
        angles.append(np.concatenate([data.qpos[1::2], data.qpos[0::2]]))
    return np.array(angles)  # columns alpha0.., beta0..
