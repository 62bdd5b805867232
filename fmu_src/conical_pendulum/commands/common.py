"""What more than one command needs: positive numbers, lists of steps and cart masses and
an output folder (demo and system), the scene an FMU was built from, and the report of an
FMU run against the native reference (build and check)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from ..analysis import compare as comparison
from ..builder import fmu as fmus
from ..errors import UserError
from ..viz.plots import books_drift

# the check's rule, for the commands' help (analysis/compare.py measures the bound)
CHECK_BOUND = (
    f"{comparison.SAFETY:g} x (the reference's own error + DOP853's at the FMU's rtol), measured\n"
    f"with references at rtol {' and '.join(f'{r:g}' for r in comparison.REFERENCE_RTOL)} (docs/fmu.md#the-check)"
)


def positive(option: str, value: float) -> float:
    if not (value > 0 and value != float("inf")):
        raise UserError(f"{option}: must be a positive number, got {value:g}")
    return value


def start_value(text: str) -> tuple[str, float]:
    """NAME=NUMBER, as argparse's type."""
    name, equals, value = text.partition("=")
    try:
        if name and equals:
            return name, float(value)
    except ValueError:
        pass
    raise argparse.ArgumentTypeError(f"{text!r}: expected NAME=NUMBER")


def numbers(text: str) -> list[float]:
    try:
        return sorted({float(s) for s in text.split(",")})
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected numbers separated by commas, got {text!r}") from None


def choices(text: str, known, what: str, every: str | None = None) -> list[str]:
    """The names of a comma-separated list, in order, once each (`every` alone: all that is
    known); argparse's error naming the unknown ones and what may be chosen."""
    if every is not None and text == every:
        return list(known)
    chosen = list(dict.fromkeys(text.split(",")))
    unknown = [name for name in chosen if name not in known]
    if unknown:
        raise argparse.ArgumentTypeError(
            f"unknown {what}(s) {', '.join(map(repr, unknown))}; choose from {', '.join(known)}"
            + (f" or {every}" if every is not None else "")
        )
    return chosen


def check_steps(option: str, steps: list[float], stop_time: float) -> None:
    """Communication steps (sorted) that each divide the stop time and are multiples of the
    smallest, so every run's points lie on the finest one's; the message names the rule broken."""

    def whole(ratio: float) -> bool:
        return abs(ratio - round(ratio)) < 1e-9

    for dt in steps:
        if not (dt > 0 and dt != float("inf")):
            broken = "must be a positive number"
        elif not whole(stop_time / dt):
            broken = (
                f"does not divide --stop-time {stop_time:g} ({stop_time:g} / {dt:g} = {stop_time / dt:.4g})"
            )
        elif not whole(dt / steps[0]):
            broken = f"is not a multiple of the smallest step {steps[0]:g}"
        else:
            continue
        raise UserError(f"{option}: {dt:g} {broken}")


def check_cart_masses(masses: list[float]) -> None:
    for mass in masses:
        if not (mass > 0 and mass != float("inf")):
            raise UserError(f"--cart-mass: must be a positive number of kg, got {mass!r}")


def output_folder(out: Path) -> Path:
    """The folder `out`, made if needed; UserError when it cannot be."""
    if out.exists() and not out.is_dir():
        raise UserError(f"--out {out}: not a directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:  # a file above the folder, or no permission
        raise UserError(f"--out {out}: {exc.strerror or exc}") from None
    return out


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
        f"against native scipy DOP853 at rtol {comparison.REFERENCE_RTOL[1]:g} "
        f"({time.perf_counter() - start:.1f} s):"
    )
    print(result.report())
    if "energy" in result.names:
        works = scene.work_names()
        run = {name: result.result[name] for name in result.result.dtype.names}
        drift = np.abs(books_drift(run)).max()
        print(
            ("energy" + "".join(f" - {name}" for name in works) if works else "the energy")
            + f" stays constant to {drift:.1e} of the energy (the FMU's run)"
        )
    ok = result.passed()
    print(result.bound.describe())
    print(
        f"angles agree to {result.angle_error():.2e} rad against a bound of {result.bound.value:.2e} rad: "
        + ("OK" if ok else "FAILED")
    )
    return result, ok
