"""The coupled demo's truth: cart and pendulum as one sympy model (KanesMethod), integrated by scipy.

The cart (mass m_cart) moves along X, held by a spring k_cart and a damper c_cart to the
ground; the chain hangs from it. Build-time sympy, used here on the host side only.
"""

from __future__ import annotations

import numpy as np
import sympy as sm
import sympy.physics.mechanics as me

from ..builder.core.kane import chain
from ..builder.models.cart import PARAMETERS as CART_DEFAULTS
from ..builder.models.cart import START as CART_START
from ..scene import Scene

CART_PARAMETERS = tuple(CART_DEFAULTS)


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
    bodies, loads, q, u, kd = chain(scene, I, O, p)
    bodies.append(me.Particle("cart", O, p["m_cart"]))
    loads.append((O, (-p["k_cart"] * x - p["c_cart"] * v) * I.x))
    kane = me.KanesMethod(I, q_ind=[x] + q, u_ind=[v] + u, kd_eqs=[v - x.diff()] + kd)
    kane.kanes_equations(bodies, loads)
    names = ["x_cart"] + scene.state_names()[: 2 * scene.n] + ["v_cart"] + scene.state_names()[2 * scene.n :]
    states = [sm.Symbol(name) for name in names]
    plain = dict(zip([x] + q + [v] + u, states))
    params = [p[name] for name in scene.parameter_names() + list(CART_PARAMETERS)]
    return me.msubs(kane.mass_matrix, plain), me.msubs(kane.forcing, plain), states, params


def cart_parameters(**overrides: float) -> dict[str, float]:
    """The cart's parameters in CART_PARAMETERS order: its FMU's starts, or these."""
    return {name: float(overrides.get(name, CART_DEFAULTS[name][1])) for name in CART_PARAMETERS}


def monolithic(
    times, scene: Scene, cart: dict | None = None, rtol: float = 1e-12, atol: float = 1e-12
) -> dict:
    """Cart and pendulum as one sympy model (KanesMethod), integrated by scipy's DOP853.

    Returns {name: array on `times`} for x_cart, v_cart, the pendulum's state, and the
    accelerations: a_cart and d<speed> for each of the pendulum's speeds.
    """
    from scipy.integrate import solve_ivp

    M, F, states, params = cart_and_pendulum(scene)
    mass = sm.lambdify([states, params], M, cse=True)
    forcing = sm.lambdify([states, params], F, cse=True)
    p = np.array(scene.parameter_defaults() + list((cart or cart_parameters()).values()))
    n = len(states) // 2
    pendulum = dict(zip(scene.state_names(), scene.state_defaults()))
    start = {"x_cart": CART_START["x"], "v_cart": CART_START["v"], **pendulum}
    y0 = np.array([start[str(s)] for s in states])

    def rhs(_, y):
        return np.concatenate([y[n:], np.linalg.solve(mass(y, p), np.ravel(forcing(y, p)))])

    solution = solve_ivp(rhs, (times[0], times[-1]), y0, method="DOP853", t_eval=times, rtol=rtol, atol=atol)
    if not solution.success:
        raise RuntimeError(f"monolithic reference failed: {solution.message}")
    result = {str(s): row for s, row in zip(states, solution.y)}
    rates = np.array([rhs(0.0, y)[n:] for y in solution.y.T]).T
    result["a_cart"] = rates[0]
    result.update({f"d{s}": row for s, row in zip(states[n + 1 :], rates[1:])})
    return result
