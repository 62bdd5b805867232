"""The native reference: the compiled right-hand side integrated by scipy.

This is what the FMU is checked against: solve_ivp (any of its methods) or odeint on
a time grid, with the outputs evaluated by the same compiled core.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import odeint, solve_ivp

from ..builder.compiler import load_core
from ..runtime.rules import check_value
from ..scene import Scene


@dataclass
class Trajectory:
    """States and outputs on a time grid, with their names (rows are times)."""

    times: np.ndarray
    states: np.ndarray
    outputs: np.ndarray
    state_names: list[str]
    output_names: list[str]
    nfev: int

    def __getitem__(self, name: str) -> np.ndarray:
        if name in self.state_names:
            return self.states[:, self.state_names.index(name)]
        if name in self.output_names:
            return self.outputs[:, self.output_names.index(name)]
        raise KeyError(f"no variable {name!r}; have {self.state_names + self.output_names}")


def simulate(
    scene: Scene,
    times,
    *,
    parameters: dict | None = None,
    state: dict | None = None,
    method: str = "DOP853",
    rtol: float = 1e-10,
    atol: float = 1e-10,
    core=None,
) -> Trajectory:
    """Integrate the scene from times[0] through every time in `times`.

    method: a scipy.integrate.solve_ivp method name, "odeint" (LSODA via ODEPACK), or
    "core" (the compiled core's DOP853 with dense output: no Python per step).
    parameters, state: values by name replacing the scene's start values.
    """
    core = core or load_core(scene)
    times = np.asarray(times, dtype=float)
    p = np.array(
        [
            check_value(scalar.name, value, scalar.quantity)
            for scalar, value in zip(scene.core_parameter_scalars(), scene.parameters(parameters))
        ]
    )
    x0 = np.array(
        [
            check_value(scalar.name, value, scalar.quantity)
            for scalar, value in zip(scene.state_scalars(), scene.initial_state(state))
        ]
    )
    rhs = core.rhs
    if method == "core":
        states, nfev = core.integrate_grid(x0, p, times, rtol, atol)
    elif method == "odeint":
        states, info = odeint(
            lambda x, t: rhs(x, p), x0, times, rtol=rtol, atol=atol, full_output=True, mxstep=10**6
        )
        if info["message"] != "Integration successful.":
            raise RuntimeError(f"odeint failed: {info['message']}")
        nfev = int(info["nfe"][-1])
    else:
        sol = solve_ivp(
            lambda t, x: rhs(x, p),
            (times[0], times[-1]),
            x0,
            method=method,
            t_eval=times,
            rtol=rtol,
            atol=atol,
        )
        if not sol.success:
            raise RuntimeError(f"solve_ivp {method} failed: {sol.message}")
        states, nfev = sol.y.T, sol.nfev
    outputs = np.array([core.outputs(x, p) for x in states]).reshape(len(times), core.NOUTPUT)
    return Trajectory(times, states, outputs, scene.state_names(), scene.output_names(), nfev)
