"""What the FMI 3.0 native FMU costs per step through fmpy, next to the FMI 2.0 native FMU.

    python benchmarks/fmi3_overhead.py

The seed scenario (3 links, 10 s at 60 steps/s, default settings: RK45 at 1e-8), both FMUs
built from the same scene, in one run, interleaved, medians of REPEATS:
- "fmpy low-level": fmpy's FMU2Slave / FMU3Slave, one doStep and one read of the 12 states per
  step (FMI 2.0: 12 scalars by value reference; FMI 3.0: the 4 arrays alpha, beta, omega,
  delta in one fmi3GetFloat64 of 12 values);
- "fmpy.simulate_fmu": only `energy` recorded (a scalar in both), then every output
  (FMI 3.0: the per-link outputs as arrays, which fmpy's recorder reshapes row by row).
Both FMUs run the same C step (bit for bit, tests/test_fmi3.py); what differs is the glue and
fmpy's side of each API. Writes benchmarks/results/fmi3_overhead.csv.
"""

import shutil
import tempfile
import time
from pathlib import Path

import fmpy
import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

from conical_pendulum import Scene
from conical_pendulum.builder.fmu import build_fmu
from results_csv import write_rows

REPEATS = 7
STOP, STEP = 10.0, 1.0 / 60.0
STEPS = round(STOP / STEP)


def low_level(path: Path, version: int, scene: Scene) -> float:
    """Seconds per step: doStep and one read of the states."""
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    folder = extract(str(path))
    cls = FMU2Slave if version == 2 else FMU3Slave
    fmu = cls(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier)
    fmu.instantiate()
    if version == 2:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        states = [vr[name] for name in scene.state_names()]

        def read():
            return fmu.getReal(states)
    else:
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        arrays = [vr[name] for name in ("alpha", "beta", "omega", "delta")]
        n = len(scene.state_names())

        def read():
            return fmu.getFloat64(arrays, nValues=n)

    t = 0.0
    start = time.perf_counter()
    for _ in range(STEPS):
        fmu.doStep(t, STEP)
        t += STEP
        read()
    seconds = (time.perf_counter() - start) / STEPS
    fmu.terminate()
    fmu.freeInstance()
    shutil.rmtree(folder, ignore_errors=True)
    return seconds


def simulated(path: Path, output=None) -> float:
    start = time.perf_counter()
    fmpy.simulate_fmu(str(path), stop_time=STOP, output_interval=STEP, output=output)
    return (time.perf_counter() - start) / STEPS


def main():
    scene = Scene.uniform(3)
    with tempfile.TemporaryDirectory() as tmp:
        fmus = {
            version: build_fmu(
                scene,
                Path(tmp) / f"fmi{version}" / "ConicalPendulum.fmu",
                backend="native",
                fmi_version=version,
            ).path
            for version in (2, 3)
        }
        rows = []
        for master, measure in (
            ("fmpy low-level: doStep + the 12 states", lambda path, version: low_level(path, version, scene)),
            ("fmpy.simulate_fmu, energy only", lambda path, version: simulated(path, ["energy"])),
            ("fmpy.simulate_fmu, every output", lambda path, version: simulated(path)),
        ):
            times = {version: [] for version in fmus}
            for _ in range(REPEATS):
                for version, path in fmus.items():
                    times[version].append(measure(path, version))
            per_step = {version: float(np.median(values)) for version, values in times.items()}
            for version, seconds in per_step.items():
                rows.append(
                    {
                        "master": master,
                        "fmu": f"native FMI {version}.0",
                        "us_per_step": round(seconds * 1e6, 2),
                        "ratio_to_fmi2": round(seconds / per_step[2], 3),
                    }
                )
    write_rows("fmi3_overhead", rows)
    print(f"seed scenario, {STEPS} steps of 1/60 s; medians of {REPEATS}")
    for row in rows:
        print(f"{row['master']:<40} {row['fmu']:<16} {row['us_per_step']:>8} us {row['ratio_to_fmi2']:>7}")


if __name__ == "__main__":
    main()
