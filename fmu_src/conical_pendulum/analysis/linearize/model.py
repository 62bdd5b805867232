"""The linear model of an FMU, what it says and where it goes: its modes (frequencies, damping,
the states each moves most), how stiff it is (for choosing a solver), and its files (.npz,
.mat) and python-control's StateSpace. Nothing here knows the FMU it came from."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...errors import UserError, needs


@dataclass(frozen=True)
class Mode:
    """One eigenvalue of A (each complex pair once): natural frequency |lambda|, damping ratio
    -Re(lambda) / |lambda|, and the eigenvector's largest components by state name, scaled so
    that the largest is 1. rounding: the size of the eigenvalue's rounding error (eigenvalues
    are computed to about n eps ||A||): a real part below it is no damping, and reads 0."""

    eigenvalue: complex
    components: tuple[tuple[str, complex], ...]
    rounding: float = 0.0

    @property
    def rad_per_s(self) -> float:
        return abs(self.eigenvalue)

    @property
    def hz(self) -> float:
        return self.rad_per_s / (2 * math.pi)

    @property
    def damping_ratio(self) -> float:
        if not self.rad_per_s or abs(self.eigenvalue.real) <= self.rounding:
            return 0.0
        return -self.eigenvalue.real / self.rad_per_s


@dataclass(frozen=True)
class Stiffness:
    """How stiff A is, for choosing a solver. fastest: A's eigenvalue of largest |lambda|,
    whose time scale 1 / |lambda| bounds an explicit solver's step (DOP853's stability ends
    near h |lambda| = 6); ratio: the largest over the smallest |Re lambda| of the decaying
    modes (Re lambda below -1e-9 |fastest|: slower ones count as undamped), None where there
    is none. A ratio of 1e3 or more with a fast decaying mode is a stiff scene."""

    fastest: complex
    ratio: float | None

    @property
    def time_scale(self) -> float:
        return 1.0 / abs(self.fastest) if self.fastest else math.inf

    def describe(self) -> str:
        fastest = (
            f"fastest mode |lambda| = {abs(self.fastest):.3g} 1/s (time scale {self.time_scale:.3g} s; "
            f"DOP853's steps stay below {6.1 * self.time_scale:.3g} s)"
        )
        if self.ratio is None:
            return f"stiffness: {fastest}; no decaying mode, not stiff"
        verdict = "stiff: choose solver radau or auto" if self.ratio >= 1e3 else "not stiff"
        return f"stiffness: {fastest}; stiffness ratio {self.ratio:.3g} ({verdict})"


@dataclass
class LinearModel:
    """x' - dx0 = A (x - x0) + B (u - u0), y - y0 = C (x - x0) + D (u - u0), named.

    method: "directional" or "differences"; calls: the FMU's directional-derivative calls or
    evaluations of f and g that made it; error: the differences' estimate of each entry's
    error in [[A, B], [C, D]] (None from directional derivatives)."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: list[str]
    inputs: list[str]
    outputs: list[str]
    x0: np.ndarray
    u0: np.ndarray
    y0: np.ndarray
    dx0: np.ndarray
    time: float
    method: str
    calls: int
    fmu: str
    error: np.ndarray | None = field(default=None, repr=False)

    def arrays(self) -> dict:
        """What the files carry: the matrices, the names, the operating point."""
        data = {name: getattr(self, name) for name in ("A", "B", "C", "D", "x0", "u0", "y0", "dx0")}
        data |= {name: np.array(getattr(self, name), dtype=str) for name in ("states", "inputs", "outputs")}
        data |= {"time": self.time, "method": self.method, "fmu": self.fmu}
        if self.error is not None:
            data["error"] = self.error
        return data

    def save(self, path) -> Path:
        """.npz (numpy) or .mat (MATLAB, names as cell arrays of strings), by the suffix."""
        path = Path(path)
        data = self.arrays()
        if path.suffix == ".npz":
            np.savez(path, **data)
        elif path.suffix == ".mat":
            from scipy.io import savemat

            names = {
                name: np.array(getattr(self, name), dtype=object) for name in ("states", "inputs", "outputs")
            }
            savemat(path, data | names, oned_as="column")
        else:
            raise UserError(f"{path}: write a linear model to a .npz or a .mat file")
        return path

    def to_control(self):
        """The model as python-control's StateSpace, its signals named."""
        try:
            import control
        except ModuleNotFoundError:
            raise UserError(needs("control", "linear")) from None
        return control.ss(
            self.A, self.B, self.C, self.D, states=self.states, inputs=self.inputs, outputs=self.outputs
        )

    def modes(self, components: int = 3) -> list[Mode]:
        """A's eigenvalues, each complex pair once, by natural frequency, with each mode's
        largest components (above 1e-9 of the largest) among the positions: the states whose
        derivative is another state (A's row a unit vector: alpha0' = omega0), all states where
        there are none or the mode moves none. Modes of one repeated eigenvalue (a chain's two
        planes) are given a basis in which each has zeros where the others are largest, so that
        they do not mix."""
        values, vectors = np.linalg.eig(self.A)
        rounding = len(self.A) * np.finfo(float).eps * np.linalg.norm(self.A, 1) if len(self.A) else 0.0
        order = [k for k in np.argsort(np.abs(values), kind="stable") if values[k].imag >= 0]
        shown, everything = self._positions(), np.arange(len(self.states))
        found = []
        while order:
            value = values[order[0]]
            same = [k for k in order if abs(values[k] - value) <= 1e-8 * max(abs(value), 1e-300)]
            order = [k for k in order if k not in same]
            for vector in _separated(vectors[:, same], shown):
                # a mode that moves no position (the books' W_damping: lambda = 0) by all states
                rows = shown if np.abs(vector[shown]).max() > 1e-12 * np.abs(vector).max() else everything
                largest = rows[np.argsort(-np.abs(vector[rows]), kind="stable")[:components]]
                scaled = vector / vector[largest[0]]
                shown_here = [i for i in largest if abs(scaled[i]) > 1e-9]  # not rounding's noise
                found.append(
                    Mode(
                        complex(value),
                        tuple((self.states[i], complex(scaled[i])) for i in shown_here),
                        float(rounding),
                    )
                )
        return found

    def stiffness(self) -> Stiffness:
        """A's fastest mode and stiffness ratio (Stiffness)."""
        values = np.linalg.eigvals(self.A) if len(self.A) else np.zeros(1)
        fastest = complex(values[np.argmax(np.abs(values))])
        decaying = -values.real[values.real < -1e-9 * abs(fastest)]
        ratio = float(decaying.max() / decaying.min()) if decaying.size else None
        return Stiffness(fastest, ratio)

    def _positions(self) -> np.ndarray:
        """The states whose derivative is another state (their A row a unit vector)."""
        unit = (np.count_nonzero(self.A, axis=1) == 1) & (np.abs(self.A).max(axis=1, initial=0) == 1)
        return np.nonzero(unit)[0] if unit.any() else np.arange(len(self.states))


def _separated(vectors: np.ndarray, rows: np.ndarray) -> list[np.ndarray]:
    """A basis of the columns' span in which each vector is zero at the others' largest
    entries among `rows` (Gauss-Jordan with full pivoting on those rows; on all entries for a
    vector that moves none of them, as the books' W_damping at lambda = 0). A defective
    eigenvalue's columns (a free body's repeated zeros: a Jordan block) are nearly parallel:
    what is left of them once the others are taken out is rounding, and is dropped."""
    basis = [vectors[:, k].copy() for k in range(vectors.shape[1])]
    scale = max((np.abs(v).max() for v in basis), default=0.0)
    everything = np.arange(vectors.shape[0])
    for k in range(len(basis)):
        rest = basis[k:]
        if max(np.abs(v).max() for v in rest) <= 1e-9 * scale:
            return basis[:k]
        sizes = [np.abs(v[rows]).max() for v in rest]
        best = int(np.argmax(sizes))
        basis[k], basis[k + best] = basis[k + best], basis[k]
        among = rows if sizes[best] > 1e-9 * scale else everything
        pivot = among[np.argmax(np.abs(basis[k][among]))]
        for j in range(len(basis)):
            if j != k:
                basis[j] = basis[j] - basis[j][pivot] / basis[k][pivot] * basis[k]
    return basis


def describe_modes(modes: list[Mode]) -> list[str]:
    """Lines of a table of modes: frequency in rad/s and Hz, damping ratio, largest components."""
    lines = [f"{'mode':>4}  {'rad/s':>11}  {'Hz':>11}  {'damping':>9}  largest components (largest = 1)"]
    for k, mode in enumerate(modes, 1):
        parts = ", ".join(f"{name} {_component(value)}" for name, value in mode.components)
        lines.append(f"{k:>4}  {mode.rad_per_s:11.6g}  {mode.hz:11.6g}  {mode.damping_ratio:9.3g}  {parts}")
    return lines


def _component(value: complex) -> str:
    return f"{value.real:+.3f}" if abs(value.imag) < 1e-9 * abs(value) else f"{value:.3f}"
