"""fmpy runs the FMU; the native reference runs the same scene; compare every output, and
judge the angles against a bound made of the errors both runs may make.

The bound is measured, not fixed: the reference runs at two tolerances (REFERENCE_RTOL),
and their difference estimates the error of the looser one (DOP853's error falls about
tenfold with its tolerance: 1e-11, 1e-12 and 1e-13 differ by 8e-7 and 7e-8 at 100 links),
so the tighter one's own error is a tenth of it. What the FMU's solver settings allow is
the same solver's error at the FMU's tolerances, measured against that reference. A long
chain is chaotic and both grow (1e-7 rad at 50 links); a wrong FMU differs from the model
far beyond them (docs/fmu.md#the-check).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..scene import Scene
from .fmpy_runs import run_fmu
from .simulate import simulate

# the reference at two tolerances (rtol = atol): the FMU is compared with the second, their
# difference is the first one's error
REFERENCE_RTOL = (1e-12, 1e-13)
SAFETY = 4.0  # the bound is this many times the estimated errors, each known to a factor, not a digit


def _angles(names) -> list[str]:
    return [n for n in names if n.rstrip("0123456789") in ("alpha", "beta")]


def _angle_difference(a, b, names) -> float:
    return max(float(np.abs(a[n] - b[n]).max()) for n in _angles(names))


@dataclass
class Bound:
    """How far the FMU's angles may be from the reference: SAFETY x (settings_error +
    reference_error). `settings_error`: DOP853 at the FMU's tolerance (`tolerance`) against
    the reference; `reference_error`: the reference's own, its difference from the looser
    reference scaled by their tolerances' ratio."""

    tolerance: float
    settings_error: float
    reference_error: float
    measured: bool = True  # False: settings_error scaled, the FMU's tolerance being below the reference's

    @property
    def value(self) -> float:
        return SAFETY * (self.settings_error + self.reference_error)

    def describe(self) -> str:
        loose, tight = REFERENCE_RTOL
        scaled = "" if self.measured else f" (scaled from {loose:g}'s)"
        return (
            f"the bound: {self.value:.2g} rad = {SAFETY:g} x ({self.settings_error:.2g}, DOP853's error at "
            f"the FMU's rtol {self.tolerance:g}{scaled} + {self.reference_error:.2g}, the reference's at "
            f"rtol {tight:g}: {tight / loose:g} x its difference from rtol {loose:g})"
        )


@dataclass
class Comparison:
    names: list[str]
    max_abs_diff: np.ndarray  # against the reference at REFERENCE_RTOL[1]
    fmu_seconds: float
    result: np.ndarray  # the FMU's run, as fmpy returns it
    bound: Bound

    def worst(self, prefix: str = "") -> float:
        picked = [d for n, d in zip(self.names, self.max_abs_diff) if n.startswith(prefix)]
        return max(picked) if picked else 0.0

    def angle_error(self) -> float:
        return max(self.worst("alpha"), self.worst("beta"))

    def passed(self) -> bool:
        """The angles within the bound (a NaN anywhere fails)."""
        return bool(self.angle_error() <= self.bound.value)

    def report(self) -> str:
        rows = [f"  {'variable':<10} max |FMU - native|"]
        rows += [f"  {n:<10} {d:.3e}" for n, d in zip(self.names, self.max_abs_diff)]
        return "\n".join(rows)


def compare(
    fmu_path,
    scene: Scene,
    *,
    stop_time=10.0,
    output_interval=1.0 / 60.0,
    start_values=None,
    rtol=1e-12,
    atol=1e-12,
) -> Comparison:
    """Run the FMU at the given tolerances and the native DOP853 reference on the same grid,
    at REFERENCE_RTOL and, when looser, at the FMU's tolerances (the bound)."""
    start_values = dict(start_values or {})
    settings = {"solver": 2, "rtol": rtol, "atol": atol}
    begin = time.perf_counter()
    result = run_fmu(fmu_path, stop_time, output_interval, {**settings, **start_values})
    seconds = time.perf_counter() - begin
    params, state = scene.split_start(start_values)

    def reference(rtol, atol):
        return simulate(
            scene, result["time"], parameters=params, state=state, method="DOP853", rtol=rtol, atol=atol
        )

    loose, tight = REFERENCE_RTOL
    native, looser = reference(tight, tight), reference(loose, loose)
    names = scene.state_names() + scene.output_names()
    spread = _angle_difference(looser, native, names)
    tolerance = max(rtol, atol)
    if (rtol, atol) == (loose, loose):
        bound = Bound(tolerance, spread, spread * tight / loose)
    elif tolerance > tight:
        settings_error = _angle_difference(reference(rtol, atol), native, names)
        bound = Bound(tolerance, settings_error, spread * tight / loose)
    else:  # tighter than the reference: DOP853's error scaled down from the looser reference's
        bound = Bound(tolerance, spread * tolerance / loose, spread * tight / loose, measured=False)
    diffs = np.array([np.abs(result[name] - native[name]).max() for name in names])
    return Comparison(names, diffs, seconds, result, bound)
