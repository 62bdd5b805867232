"""fmpy runs the FMU; the native reference runs the same scene; compare every output."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..scene import Scene
from .fmpy_runs import run_fmu
from .simulate import simulate


@dataclass
class Comparison:
    names: list[str]
    max_abs_diff: np.ndarray
    fmu_seconds: float
    result: np.ndarray  # the FMU's run, as fmpy returns it

    def worst(self, prefix: str = "") -> float:
        picked = [d for n, d in zip(self.names, self.max_abs_diff) if n.startswith(prefix)]
        return max(picked) if picked else 0.0

    def angle_error(self) -> float:
        return max(self.worst("alpha"), self.worst("beta"))

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
    """Run the FMU at the given tolerances and the native DOP853 reference on the same grid."""
    start_values = dict(start_values or {})
    settings = {"solver": 2, "rtol": rtol, "atol": atol}
    begin = time.perf_counter()
    result = run_fmu(fmu_path, stop_time, output_interval, {**settings, **start_values})
    seconds = time.perf_counter() - begin
    params = {k: v for k, v in start_values.items() if k in scene.core_parameter_names()}
    state = {k: v for k, v in start_values.items() if k in scene.state_names()}
    native = simulate(
        scene,
        result["time"],
        parameters=params,
        state=state,
        method="DOP853",
        rtol=min(rtol, 1e-12),
        atol=min(atol, 1e-12),
    )
    names = scene.state_names() + scene.output_names()
    diffs = np.array([np.abs(result[name] - native[name]).max() for name in names])
    return Comparison(names, diffs, seconds, result)
