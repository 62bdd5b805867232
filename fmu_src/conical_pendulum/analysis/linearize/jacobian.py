"""The Jacobian of an FMU's unknowns (the state derivatives, then the outputs that are not
states) by its knowns (the states, then the inputs) at a session's operating point.

Columns come in groups that share no row by the ModelStructure's dependencies (Curtis, Powell
and Reid's grouping, greedy, in the ModelStructure's order), one call per group, and a column
nothing depends on costs no call: from the FMU's directional derivatives, exact to its own
accuracy, or from central differences of fmi2GetDerivatives / fmi3GetContinuousStateDerivatives
and the outputs at the steps h and 2h, extrapolated (Richardson), with an error estimate per
entry."""

from __future__ import annotations

import ctypes
import math

import numpy as np

DIFFERENCE_STEP = 1e-3  # relative to max(|value|, nominal): central differences' h^2 and h^4 terms


def jacobian_at(
    session, method: str, grouped: bool, step: float
) -> tuple[np.ndarray, np.ndarray | None, int]:
    """The Jacobian of the unknowns by the knowns at the session's operating point (rows and
    columns as sparsity() has them), the differences' error estimate of each entry (None from
    directional derivatives), and the calls it cost; the operating point set again after."""
    pattern = sparsity(session)
    n_knowns = pattern.shape[1]
    groups = color_columns(pattern) if grouped else [[j] for j in range(n_knowns) if pattern[:, j].any()]
    if method == "directional":
        jacobian, error = _directional(session, pattern, groups), None
        calls = len(groups)
    else:
        jacobian, error = _differences(session, pattern, groups, step)
        calls = 4 * len(groups)
    session.call("restoring the operating point", session.at, session.x0, session.u0)
    return jacobian, error, calls


def color_columns(pattern: np.ndarray) -> list[list[int]]:
    """Columns of a boolean pattern (rows x columns) in groups whose columns share no row
    (greedy, in order); columns with no row are in no group: they are zero."""
    groups: list[list[int]] = []
    taken: list[int] = []  # each group's rows as the bits of one integer
    for j in range(pattern.shape[1]):
        rows = int.from_bytes(np.packbits(pattern[:, j]).tobytes(), "big")
        if not rows:
            continue
        for k, used in enumerate(taken):
            if not used & rows:
                groups[k].append(j)
                taken[k] |= rows
                break
        else:
            groups.append([j])
            taken.append(rows)
    return groups


def sparsity(session) -> np.ndarray:
    """Which unknowns (derivatives, then the outputs that are not states) the ModelStructure
    says depend on which knowns (states, then inputs), element by element."""
    knowns = dict(session.states.columns)
    offset = len(session.states.names)
    knowns |= {vr: range(r.start + offset, r.stop + offset) for vr, r in session.inputs.columns.items()}
    n_knowns = offset + len(session.inputs.names)
    computed = set(session.computed.vrs)
    unknowns = list(session.md.derivatives) + [
        u for u in session.unknown_outputs if u.variable.valueReference in computed
    ]
    sizes = [math.prod(tuple(u.variable.shape or ())) if session.fmi3 else 1 for u in unknowns]
    pattern = np.zeros((sum(sizes), n_knowns), dtype=bool)
    row = 0
    for unknown, size in zip(unknowns, sizes):
        if unknown.dependencies is None:  # no list: every known
            pattern[row : row + size] = True
        else:
            columns = [
                k
                for variable in unknown.dependencies
                if variable.valueReference in knowns
                for k in knowns[variable.valueReference]
            ]
            pattern[row : row + size, columns] = True
        row += size
    return pattern


def _directional(session, pattern, groups) -> np.ndarray:
    """One fmi2GetDirectionalDerivative / fmi3GetDirectionalDerivative per group, its seed 1
    on the group's columns (FMI 2.0: only the group's knowns are passed; FMI 3.0: every
    known, an array whole), into ctypes arrays made once."""
    from ctypes import c_double, c_uint

    knowns = list(session.states.vrs) + list(session.inputs.vrs)
    unknowns = list(session.derivatives.vrs) + list(session.computed.vrs)
    n_rows, n_columns = pattern.shape
    unknown_refs = (c_uint * len(unknowns))(*unknowns)
    sensitivity = (c_double * n_rows)()
    jacobian = np.zeros(pattern.shape)
    if session.fmi3:
        known_refs = (c_uint * len(knowns))(*knowns)
        seed = (c_double * n_columns)()
    for group in groups:
        if session.fmi3:
            ctypes.memset(seed, 0, ctypes.sizeof(seed))
            for j in group:
                seed[j] = 1.0
            arguments = (unknown_refs, len(unknowns), known_refs, len(knowns), seed, n_columns)
            session.call(
                "fmi3GetDirectionalDerivative",
                session.fmu.fmi3GetDirectionalDerivative,
                session.fmu.component,
                *arguments,
                sensitivity,
                n_rows,
            )
        else:
            group_refs = (c_uint * len(group))(*(knowns[j] for j in group))
            ones = (c_double * len(group))(*([1.0] * len(group)))
            session.call(
                "fmi2GetDirectionalDerivative",
                session.fmu.fmi2GetDirectionalDerivative,
                session.fmu.component,
                unknown_refs,
                len(unknowns),
                group_refs,
                len(group),
                ones,
                sensitivity,
            )
        _scatter(jacobian, pattern, group, np.ctypeslib.as_array(sensitivity))
    return jacobian


def _differences(session, pattern, groups, step) -> tuple[np.ndarray, np.ndarray]:
    """Central differences at h and 2h per group, extrapolated: R = (4 D(h) - D(2h)) / 3.
    The error estimate of each entry: |D(h) - D(2h)| / 3 (D(h)'s own truncation error,
    which bounds R's where the h^2 term dominates) plus rounding, 4 eps s / h, with s the
    size of what f is made of: its largest value, or the terms J_ik x_k where they cancel
    to a smaller f (y = C x + D u can be near 0 with every term of order 1)."""
    point = np.concatenate([session.x0, session.u0])
    nominal = np.array(
        [session.nominal(name) for name in session.states.names + session.inputs.names] if len(point) else []
    )
    h = step * np.maximum(np.abs(point), nominal)
    jacobian, truncation = np.zeros(pattern.shape), np.zeros(pattern.shape)
    largest = np.zeros(pattern.shape[0])  # each unknown's largest value met
    n = len(session.x0)

    def values(at):
        session.at(at[:n], at[n:])
        return np.concatenate(session.evaluate())

    for group in groups:
        direction = np.zeros(len(point))
        direction[group] = h[group]
        scale = np.zeros(pattern.shape[0])
        for j in group:
            scale[pattern[:, j]] = h[j]
        fs = [session.call("evaluating a difference", values, point + k * direction) for k in (1, -1, 2, -2)]
        largest = np.maximum(largest, np.max(np.abs(fs), axis=0))
        with np.errstate(divide="ignore", invalid="ignore"):
            near = np.where(scale > 0, (fs[0] - fs[1]) / (2 * scale), 0.0)
            far = np.where(scale > 0, (fs[2] - fs[3]) / (4 * scale), 0.0)
        _scatter(jacobian, pattern, group, (4 * near - far) / 3)
        _scatter(truncation, pattern, group, np.abs(near - far) / 3)
    size = np.maximum(largest, np.abs(jacobian) @ np.abs(point))
    rounding = 4 * np.finfo(float).eps * np.outer(size, 1 / np.where(h > 0, h, 1.0))
    return jacobian, np.where(pattern, truncation + rounding, 0.0)


def _scatter(matrix, pattern, group, values) -> None:
    """A group's values into its columns: each row to the one column of the group it depends on."""
    for j in group:
        rows = pattern[:, j]
        matrix[rows, j] = values[rows]
