"""What more than one command needs: positive numbers, the scene an FMU was built from,
and the report of an FMU run against the native reference (build and check)."""

from __future__ import annotations

import time
from pathlib import Path

from ..analysis import compare as comparison
from ..builder import fmu as fmus
from ..errors import UserError

ANGLE_TOLERANCE = 1e-8  # rad: the FMU against the native reference, for build and check


def positive(option: str, value: float) -> float:
    if not (value > 0 and value != float("inf")):
        raise UserError(f"{option}: must be a positive number, got {value:g}")
    return value


def fmu_scene(path: Path):
    """The scene the FMU at `path` was built from; UserError when it is not such an FMU."""
    try:
        return fmus.fmu_scene(path)
    except ValueError as exc:
        raise UserError(str(exc)) from None


def compare(fmu: Path, scene, stop_time: float = 10.0, interval: float = 1.0 / 60.0, rtol: float = 1e-12):
    """Run the FMU against the native reference and print the report: (comparison, angles agree)."""
    start = time.perf_counter()
    result = comparison.compare(
        fmu, scene, stop_time=stop_time, output_interval=interval, rtol=rtol, atol=rtol
    )
    print(
        f"fmpy.simulate_fmu, {stop_time:g} s at {1 / interval:g} outputs/s, DOP853 rtol = atol = {rtol:g}, "
        f"against native scipy DOP853 ({time.perf_counter() - start:.1f} s):"
    )
    print(result.report())
    error = result.angle_error()
    ok = error <= ANGLE_TOLERANCE
    print(f"angles agree to {error:.2e} rad: {'OK' if ok else 'FAILED'}")
    return result, ok
