"""The runs of a sweep: made (a grid, random samples), held as columns, and checked
against the FMU's variables."""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Mapping, Sequence

import numpy as np
import pandas as pd
from fmpy.simulation import settable_in_initialization_mode, settable_in_instantiated

from ..fmpy_runs import WHOLE_TYPES


class Runs(Sequence):
    """Runs held as columns, one array per variable, every run setting each: 8 bytes a
    value, where a list of dicts takes some 250 bytes a run. A sequence of dicts to the
    reader; `+` with other runs gives a list of dicts."""

    def __init__(self, columns: Mapping[str, Sequence[float]]):
        self.columns = {name: np.asarray(values) for name, values in columns.items()}
        lengths = {len(values) for values in self.columns.values()}
        if len(lengths) > 1:
            raise ValueError(f"runs: columns of different lengths {sorted(lengths)}")
        self._length = lengths.pop() if lengths else 0

    def __len__(self):
        return self._length

    def __getitem__(self, index):
        if isinstance(index, slice):
            return Runs({name: values[index] for name, values in self.columns.items()})
        if not -self._length <= index < self._length:
            raise IndexError(f"run {index} of {self._length}")
        return {name: values[index].item() for name, values in self.columns.items()}

    def __add__(self, other):
        return [*self, *other]

    def __radd__(self, other):
        return [*other, *self]

    def __eq__(self, other):
        return isinstance(other, Sequence) and len(self) == len(other) and all(map(dict.__eq__, self, other))

    def __repr__(self):
        return f"Runs({len(self)} runs of {', '.join(self.columns) or 'nothing'})"


def grid(axes: Mapping[str, Sequence[float]]) -> Runs:
    """Every combination of the values given per variable (the last varies fastest), as runs."""
    empty = [name for name, values in axes.items() if len(values) == 0]
    if not axes:
        raise ValueError("grid: no variables")
    if empty:
        raise ValueError(f"grid: no values for {', '.join(empty)}")
    mesh = np.meshgrid(*(np.asarray(values) for values in axes.values()), indexing="ij")
    return Runs({name: values.ravel() for name, values in zip(axes, mesh)})


def random_samples(ranges: Mapping[str, tuple[float, float]], n: int, seed=None) -> Runs:
    """n runs drawn uniformly from [low, high) per variable; the same seed gives the same runs."""
    if n < 1:
        raise ValueError(f"random samples: n = {n}: must be at least 1")
    if not ranges:
        raise ValueError("random samples: no ranges")
    for name, (low, high) in ranges.items():
        if not (math.isfinite(low) and math.isfinite(high) and low <= high):
            raise ValueError(f"random samples: {name} range {low}:{high} must be finite with low <= high")
    lows, highs = zip(*ranges.values()) if ranges else ((), ())
    draws = np.random.default_rng(seed).uniform(lows, highs, size=(n, len(ranges)))
    return Runs({name: draws[:, column] for column, name in enumerate(ranges)})


def run_table(md, runs: Iterable[Mapping]) -> pd.DataFrame:
    """The runs as one column per variable any run sets, values as the FMU's types, so that
    the client holds 8 bytes a value, not a dict a run; a run that leaves a variable alone
    gets the FMU's start value, what it runs with. Unknown or unsettable names and
    non-numbers are refused, naming the run."""
    if isinstance(runs, Runs):
        columns = dict(runs.columns)
        for name, values in columns.items():
            if values.dtype == bool or not np.issubdtype(values.dtype, np.number):
                raise ValueError(f"runs: {name} holds {values.dtype} values, not numbers")
        count = len(runs)
    else:
        columns, count = {}, 0
        for count, run in enumerate(runs, start=1):
            if not isinstance(run, Mapping):
                raise ValueError(f"run {count - 1}: {run!r} is not a mapping of variable names to values")
            for name, value in run.items():
                if isinstance(value, bool) or not isinstance(value, numbers.Real):
                    raise ValueError(f"run {count - 1}: {name} = {value!r} is not a number")
                columns.setdefault(name, [None] * (count - 1)).append(value)
            for values in columns.values():
                if len(values) < count:
                    values.append(None)
    if not count:
        raise ValueError("no runs to do")
    variables = {v.name: v for v in md.modelVariables}
    unknown = sorted(columns.keys() - variables.keys())
    if unknown:
        raise ValueError(f"unknown variable(s) {', '.join(unknown)}: {md.modelName} has no such variable")
    fixed = sorted(
        name
        for name in columns
        if not (settable_in_instantiated(variables[name]) or settable_in_initialization_mode(variables[name]))
    )
    if fixed:
        raise ValueError(
            f"{', '.join(fixed)} cannot be set (calculated); a run sets parameters and start values"
        )
    table = {}
    for name, values in columns.items():
        variable = variables[name]
        if not isinstance(values, np.ndarray):
            start = float(variable.start)
            values = np.array([start if value is None else value for value in values], dtype=float)
        if variable.type in WHOLE_TYPES:
            fractional = np.flatnonzero(values != np.round(values))
            if len(fractional):
                run = fractional[0]
                raise ValueError(
                    f"run {run}: {name} = {values[run].item()!r}: {name} is an {variable.type} variable"
                )
            table[name] = values.astype(np.int64)
        else:
            table[name] = values.astype(float)
    return pd.DataFrame(table, index=pd.RangeIndex(count, name="run"))


def check_outputs(md, outputs: Sequence[str] | None) -> list[str]:
    """The variables to record: the given ones, known to the FMU, or all its outputs."""
    if outputs is None:
        return [v.name for v in md.modelVariables if v.causality == "output"]
    outputs = list(dict.fromkeys(outputs))
    if not outputs:
        raise ValueError("no outputs chosen")
    known = {v.name for v in md.modelVariables}
    unknown = [name for name in outputs if name not in known]
    if unknown:
        raise ValueError(f"unknown output(s) {', '.join(unknown)}: {md.modelName} has no such variable")
    return outputs


def dataset_inputs(md, table: pd.DataFrame) -> pd.DataFrame:
    """The run table's columns as the dataset names them: a state's start value is
    `<name>_start`, apart from its recorded trajectory."""
    outputs = {v.name for v in md.modelVariables if v.causality == "output"}
    return table.rename(columns={name: f"{name}_start" for name in table.columns if name in outputs})
