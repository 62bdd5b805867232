"""An elastic rope that can go slack, in MuJoCo: a model nobody here wrote, to check ours against.

A point load (mass m, a free body with a tiny inertia, no contacts) hangs from a support on a
massless rope of unstretched length l(t), paid out by a winch, l' = v_hoist(t). Its tension is
EA (r - l) / l when the rope is stretched (r > l, r the distance from the support to the load)
and 0 when it is slack. The rope is MuJoCo's own mechanism for that: a spatial tendon between a
site on the support and one on the load whose spring acts only beyond its length,
springlength="0 l" stiffness="EA/l" (a dead band: no force for a length in [0, l]).

The winch: l is a state of MuJoCo's, the activation of an actuator (of no force) with
dyntype="user" whose mjcb_act_dyn returns v_hoist(t), so that RK4 integrates l with the load.
MuJoCo's RK4 calls mj_passive at each of its stages with that stage's time and state (act
included); the mjcb_passive sets tendon_lengthspring and tendon_stiffness from the stage's l and
calls mj_passive again, once, so that the tendon's force is MuJoCo's at that l: the rope's
changing length costs nothing beyond RK4's own error (freezing l over a step, at its middle,
would cost O(h^2)).

The support: a body on three slide joints (x, y, z) of unit mass, so that its block of the mass
matrix is the identity, coupled to nothing (the load is a child of the world). The same
mjcb_passive sets the support's passive forces to a_support(t) - gravity at each stage, in place
of the tendon's pull on it: its acceleration is exactly a_support(t) at every stage, so RK4
moves it as it moves the load and the motion relative to the support is exact to RK4's error. A
mocap body would be moved only between steps, its position frozen over the stages (an O(h)
error), and its velocity is not MuJoCo's (no matter here: the rope has no damping).

Accuracy, at the default step of 1e-5 s (m = 100 kg, EA = 1e6 N, l = 10 m): taut, RK4's own
(the vertical frequency sqrt(k/m) to 1e-12); each switch between slack and taut puts a kink of
the force inside a step, which RK4 crosses at a lower order: a drop onto the rope peaks to some
3e-9 of its tension, and 3 s of swinging, 3D, with 12 to 21 switches, stays within some 4e-9 m
and 1e-7 m/s of a tight DOP853 restarted at each switch (l: 1e-11 m, the support: 1e-10 m).
"""

import numpy as np


def mjcf(m: float, g: float, l0: float, timestep: float) -> str:
    """The support (three slides), the load (a free body), the rope (a tendon whose length and
    stiffness the mjcb_passive sets at every stage) and the winch (an actuator of no force)."""
    slides = "".join(
        f'<joint name="support_{x}" type="slide" axis="{a}"/>'
        for x, a in zip("xyz", ("1 0 0", "0 1 0", "0 0 1"))
    )
    return (
        f'<mujoco><option gravity="0 {-g!r} 0" integrator="RK4" timestep="{timestep!r}">'
        '<flag contact="disable"/></option><worldbody>'
        f'<body name="support"><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>{slides}'
        '<site name="support"/></body>'
        f'<body name="load"><freejoint/><inertial pos="0 0 0" mass="{m!r}" '
        'diaginertia="1e-12 1e-12 1e-12"/><site name="load"/></body></worldbody>'
        f'<tendon><spatial name="rope" springlength="0 {l0!r}"><site site="support"/><site site="load"/>'
        '</spatial></tendon><actuator><general name="winch" joint="support_x" dyntype="user" '
        'gainprm="0" biastype="none"/></actuator></mujoco>'
    )


def simulate(
    m,
    EA,
    g,
    l0,
    load_position,
    load_velocity,
    times,
    v_hoist=lambda t: 0.0,
    support_acceleration=lambda t: (0, 0, 0),
    timestep=1e-5,
):
    """Arrays at `times` (multiples of timestep from 0): "load" and "load_velocity" (N x 3,
    relative to the support), "tension" (N, the tendon's force on the load), "length" (l, N),
    "support" (N x 3, inertial). load_position, load_velocity: relative to the support, which is
    at rest at the origin at t = 0."""
    import mujoco

    model = mujoco.MjModel.from_xml_string(mjcf(m, g, l0, timestep))
    data = mujoco.MjData(model)
    data.qpos[3:6], data.qvel[3:6], data.act[0] = load_position, load_velocity, l0
    inner = False

    def passive(model, data):
        nonlocal inner
        if inner:
            return
        model.tendon_lengthspring[0] = (0.0, data.act[0])
        model.tendon_stiffness[0] = EA / data.act[0]
        inner = True
        try:
            mujoco.mj_passive(model, data)
        finally:
            inner = False
        data.qfrc_passive[:3] = np.asarray(support_acceleration(data.time), float) - model.opt.gravity

    mujoco.set_mjcb_passive(passive)
    mujoco.set_mjcb_act_dyn(lambda model, data, i: v_hoist(data.time))
    try:
        return _run(model, data, times, timestep)
    finally:
        mujoco.set_mjcb_passive(None)
        mujoco.set_mjcb_act_dyn(None)


def _run(model, data, times, timestep):
    import mujoco

    names = ("load", "load_velocity", "tension", "length", "support")
    out = {name: [] for name in names}
    done = 0
    for target in np.rint(np.asarray(times) / timestep).astype(int):
        while done < target:
            mujoco.mj_step(model, data)
            done += 1
        mujoco.mj_forward(model, data)  # the tendon's force at the state reached, not at RK4's last stage
        out["load"].append(data.qpos[3:6] - data.qpos[:3])
        out["load_velocity"].append(data.qvel[3:6] - data.qvel[:3])
        out["tension"].append(np.linalg.norm(data.qfrc_spring[3:6]))
        out["length"].append(data.act[0])
        out["support"].append(data.qpos[:3].copy())
    return {name: np.array(values) for name, values in out.items()}
