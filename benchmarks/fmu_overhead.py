"""What the FMU costs through fmpy, next to the interface's floor.

    python benchmarks/fmu_overhead.py

Builds the seed FMU and a trivial pythonfmu FMU with the same number of outputs
(constant outputs, pythonfmu's default one-getter-per-variable glue, a do_step that
does nothing), then times fmpy.simulate_fmu on both: the seed scenario, 10 s with an
output every 1/60 s (600 communication steps), median of repeats, in one run. Also
reports the FMU's size, build time cold (fresh core cache) and cached, and the time
to instantiate. Writes benchmarks/results/fmu_overhead.csv (the figures
docs/performance.md quotes).
"""

import tempfile
import time
from pathlib import Path

import fmpy
import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from conical_pendulum import Scene
from conical_pendulum.builder.fmu import build_fmu
from results_csv import write_rows


def build_trivial(outputs: int, directory: Path) -> Path:
    from pythonfmu import FmuBuilder

    script = Path(__file__).parent / "trivial_fmu" / "trivial_slave.py"
    return FmuBuilder.build_FMU(script, dest=directory, newargs={"count": outputs})


def median_seconds(*calls, repeats=15):
    """Median seconds of each call, the calls interleaved so that load hits them alike."""
    for f in calls:
        f()  # warm: extraction caches, imports
    runs = [[] for _ in calls]
    for _ in range(repeats):
        for f, times in zip(calls, runs):
            start = time.perf_counter()
            f()
            times.append(time.perf_counter() - start)
    return [float(np.median(times)) for times in runs]


def instantiate_seconds(path: Path, repeats=20) -> float:
    md = read_model_description(str(path))
    unzipdir = extract(str(path))
    runs = []
    for k in range(repeats):
        fmu = FMU2Slave(
            guid=md.guid,
            unzipDirectory=unzipdir,
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=f"i{k}",
        )
        start = time.perf_counter()
        fmu.instantiate()
        runs.append(time.perf_counter() - start)
        fmu.freeInstance()
    return float(np.median(runs))


def main():
    scene = Scene.uniform(3)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        start = time.perf_counter()
        cold = build_fmu(scene, tmp / "cold" / "ConicalPendulum.fmu", cache=tmp / "cache")
        cold_s = time.perf_counter() - start
        start = time.perf_counter()
        fmu = build_fmu(scene, tmp / "ConicalPendulum.fmu", cache=tmp / "cache").path
        cached_s = time.perf_counter() - start
        outputs = len([v for v in read_model_description(str(fmu)).modelVariables if v.causality == "output"])
        trivial = build_trivial(outputs, tmp)
        size_kib = fmu.stat().st_size / 1024
        print(
            f"FMU size {size_kib:.0f} KiB; build cold {cold_s:.1f} s "
            f"(core compile {cold.core.seconds['compile']:.1f} s), cached {cached_s:.2f} s"
        )
        instantiate, instantiate_trivial = instantiate_seconds(fmu), instantiate_seconds(trivial)
        print(
            f"instantiate: ConicalPendulum {instantiate * 1e3:.2f} ms, "
            f"trivial {instantiate_trivial * 1e3:.2f} ms"
        )
        steps = 600
        run = {"stop_time": 10.0, "output_interval": 10.0 / steps}
        ours, floor = median_seconds(
            lambda: fmpy.simulate_fmu(str(fmu), **run), lambda: fmpy.simulate_fmu(str(trivial), **run)
        )
        print(f"fmpy.simulate_fmu, {steps} steps, {outputs} outputs, default settings:")
        print(f"  ConicalPendulum {ours * 1e3:7.1f} ms ({ours / steps * 1e6:5.1f} us/step)")
        print(f"  trivial FMU     {floor * 1e3:7.1f} ms ({floor / steps * 1e6:5.1f} us/step)")
        print(f"  ratio {ours / floor:.2f} (target: at most 1.0)")
    write_rows(
        "fmu_overhead",
        [
            {"figure": "FMU size", "value": round(size_kib), "unit": "KiB"},
            {"figure": "build, cold (fresh core cache)", "value": round(cold_s, 1), "unit": "s"},
            {"figure": "build, core cached", "value": round(cached_s, 2), "unit": "s"},
            {"figure": "instantiate", "value": round(instantiate * 1e3, 2), "unit": "ms"},
            {
                "figure": "instantiate, trivial pythonfmu FMU",
                "value": round(instantiate_trivial * 1e3, 2),
                "unit": "ms",
            },
            {"figure": f"fmpy.simulate_fmu, {steps} steps", "value": round(ours * 1e3, 1), "unit": "ms"},
            {
                "figure": f"fmpy.simulate_fmu, {steps} steps, trivial pythonfmu FMU",
                "value": round(floor * 1e3, 1),
                "unit": "ms",
            },
            {"figure": "simulate_fmu, ratio to the trivial FMU", "value": round(ours / floor, 2), "unit": ""},
        ],
    )


if __name__ == "__main__":
    main()
