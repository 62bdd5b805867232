"""Linear models of any FMI 2.0 or 3.0 FMU at an operating point: A, B, C, D from its derivatives.

Around (x0, u0) at time t, x' = f(x, u) and y = g(x, u) give A = df/dx, B = df/du, C = dg/dx,
D = dg/du, rows and columns named in the ModelStructure's order (states as its derivatives
list them, the Float inputs in the model's order, the outputs as it lists them). An FMI 3.0
array is one name per element (`x[2]`; an FMU of this package: the FMI 2.0 FMU's names,
`alpha0`, so that both versions give the same model).

Where the FMU gives directional derivatives (Model Exchange with
providesDirectionalDerivative(s)), the columns come from them, else from extrapolated central
differences with an error estimate per entry, both grouped by the ModelStructure's sparsity.
The state derivatives exist only in Model Exchange: a Co-Simulation-only FMU is refused,
saying so. An output that is a state is its own row of C, exactly.

The package by job: session.py (one Model Exchange instance through fmpy, at the operating
point), variables.py (the states, inputs and outputs as named blocks of values), jacobian.py
(the columns grouped, from directional derivatives or differences) and model.py (LinearModel:
its modes, stiffness and files); here linearize(), which puts them together.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ...errors import UserError
from .jacobian import DIFFERENCE_STEP, color_columns, jacobian_at
from .model import LinearModel, Mode, Stiffness, describe_modes
from .session import NATIVE_BUILD, Session
from .variables import FLOAT_TYPES, Block

__all__ = [
    "DIFFERENCE_STEP",
    "FLOAT_TYPES",
    "NATIVE_BUILD",
    "Block",
    "LinearModel",
    "Mode",
    "Stiffness",
    "color_columns",
    "describe_modes",
    "linearize",
]


def linearize(
    path,
    states: dict | None = None,
    inputs: dict | None = None,
    parameters: dict | None = None,
    time: float = 0.0,
    method: str = "auto",
    grouped: bool = True,
    step: float = DIFFERENCE_STEP,
) -> LinearModel:
    """The linear model of the FMU at `path` around its start (after initialization at
    `time`), or states, inputs and parameters given by name (an FMI 3.0 array by its name
    and all its values, or by its elements' names).

    method: "directional" (the FMU's directional derivatives; refused where it has none),
    "differences", or "auto" (directional where given); grouped=False: one call per column."""
    if method not in ("auto", "directional", "differences"):
        raise UserError(f"method: {method!r} is not one of 'auto', 'directional', 'differences'")
    if not math.isfinite(time):
        raise UserError(f"time: must be finite, got {time!r}")
    if not 0 < step <= 0.1:
        raise UserError(f"step: the differences' relative step must be in (0, 0.1], got {step!r}")
    with Session(Path(path), time, parameters or {}) as session:
        if method == "directional" and not session.directional:
            raise UserError(
                f"{path}: gives no directional derivatives (providesDirectionalDerivative is not "
                "set in its Model Exchange); use method 'differences'"
            )
        session.place(states or {}, inputs or {})
        use = "directional" if method != "differences" and session.directional else "differences"
        jacobian, error, calls = jacobian_at(session, use, grouped, step)
        return _model(session, jacobian, error, use, calls)


def _model(session, jacobian, error, method, calls) -> LinearModel:
    """The Jacobian's rows in [[A, B], [C, D]] (_unknown_rows), an output that is a state its
    own row of C, exactly, and the session's operating point and names."""
    n, m = len(session.states.names), len(session.inputs.names)
    n_out = len(session.outputs.names)
    full = np.zeros((n + n_out, n + m))
    full_error = None if error is None else np.zeros(full.shape)
    rows = _unknown_rows(session)
    full[rows] = jacobian
    if error is not None:
        full_error[rows] = error
    state_of = dict(zip(session.states.vrs, session.states.columns.values()))
    for vr, positions in session.outputs.columns.items():
        if vr in state_of:  # an output that is a state: its own row, exactly
            for row, column in zip(positions, state_of[vr]):
                full[n + row, column] = 1.0
    return LinearModel(
        A=full[:n, :n],
        B=full[:n, n:],
        C=full[n:, :n],
        D=full[n:, n:],
        states=list(session.states.names),
        inputs=list(session.inputs.names),
        outputs=list(session.outputs.names),
        x0=session.x0,
        u0=session.u0,
        y0=session.y0,
        dx0=session.dx0,
        time=session.time,
        method=method,
        calls=calls,
        fmu=str(session.path),
        error=full_error,
    )


def _unknown_rows(session) -> list[int]:
    """Where the unknowns' rows go in [[A, B], [C, D]]: the derivatives, then the outputs
    that are not states at their places among the outputs."""
    n = len(session.states.names)
    places = session.outputs.columns
    return list(range(n)) + [n + row for vr in session.computed.vrs for row in places[vr]]
