"""The FMU's variables as a linear model names them: blocks of values (states, inputs,
outputs), an FMI 3.0 array one value and one name per element (this package's FMI 3.0 FMUs
with the FMI 2.0 FMU's names, so that both versions give the same model), and values
replaced by those names."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...errors import UserError
from ..fmi3_arrays import element_names, fmu_data

FLOAT_TYPES = ("Real", "Float64")


@dataclass(frozen=True)
class Block:
    """Variables of one kind (states, inputs, outputs): value references, each one's number of
    values (an FMI 3.0 array's elements), and one name per value."""

    vrs: tuple[int, ...]
    sizes: tuple[int, ...]
    names: tuple[str, ...]

    @property
    def columns(self) -> dict[int, range]:
        """Each value reference's positions among the block's values."""
        found, start = {}, 0
        for vr, size in zip(self.vrs, self.sizes):
            found[vr] = range(start, start + size)
            start += size
        return found


def block_of(variables, fmi3: bool, names: dict[tuple[str, int], str]) -> Block:
    """The variables' block, an FMI 3.0 array element by element, each named by `names`
    (fmi2_names) where it has them."""
    vrs, sizes, found = [], [], []
    for v in variables:
        shape = tuple(v.shape or ()) if fmi3 else ()
        size = math.prod(shape)
        vrs.append(v.valueReference)
        sizes.append(size)
        found += [names.get((v.name, k)) or _indexed(v.name, shape, k) for k in range(size)]
    return Block(tuple(vrs), tuple(sizes), tuple(found))


def continuous_float(variable) -> bool:
    """A continuous Float64 (Real) variable: what a linear model's inputs and outputs are."""
    return variable.type in FLOAT_TYPES and variable.variability == "continuous"


def fmi2_names(path: Path) -> dict[tuple[str, int], str]:
    """(array, 0-based element) -> the FMI 2.0 FMU's name, for an FMI 3.0 FMU of this package."""
    data = fmu_data(path)
    if data is None:
        return {}
    return {(array, k): name for name, (array, k) in element_names(data).items()}


def _indexed(name: str, shape: tuple, k: int) -> str:
    """An FMI 3.0 array element's name (1-based, row-major: A[2,3]); a scalar's own name."""
    if not shape:
        return name
    return f"{name}[{','.join(str(i + 1) for i in np.unravel_index(k, shape))}]"


def replaced(values: np.ndarray, block: Block, given: dict, what: str, fmu: str) -> np.ndarray:
    """values with some replaced by name: an element by its name, a whole FMI 3.0 array by
    its name, or with * and ? every element whose name matches (alpha* = 0: one value for all)."""
    import fnmatch

    values = values.copy()
    index = {name: i for i, name in enumerate(block.names)}
    for name, value in given.items():
        numbers = np.atleast_1d(np.asarray(value, dtype=float))
        if name in index:
            positions = [index[name]]
        elif "*" in name or "?" in name:
            pattern = name.replace("[", "[[]")
            positions = [i for i, n in enumerate(block.names) if fnmatch.fnmatchcase(n, pattern)]
            numbers = np.broadcast_to(numbers, (len(positions),)) if len(numbers) == 1 else numbers
        else:
            positions = [i for i, n in enumerate(block.names) if n.split("[")[0] == name]
        if not positions:
            listed = ", ".join(block.names[:12]) + (", ..." if len(block.names) > 12 else "")
            raise UserError(f"{what} {name!r}: {fmu} has no {what} by that name; it has {listed or 'none'}")
        if len(numbers) != len(positions):
            raise UserError(f"{what} {name!r}: expected {len(positions)} value(s), got {len(numbers)}")
        if not np.isfinite(numbers).all():
            raise UserError(f"{what} {name!r}: must be finite, got {value!r}")
        values[positions] = numbers
    return values
