"""What leaving things out of a scene saves: RHS cost, output cost and FMU time.

    python benchmarks/scene_cost.py

Variants of the seed scene (3 links): everything; no calculated outputs (state only);
massless links (bobs only); no bobs (links only). RHS and output costs are timed in a C
loop; the FMU time is fmpy.simulate_fmu of 10 s at 60 outputs per second (median of
repeats, interleaved), each FMU with its own default settings. Prints the table
docs/model.md shows and writes benchmarks/results/scene_cost.csv.
"""

import tempfile
import time
from pathlib import Path

import fmpy
import numpy as np

from conical_pendulum import Scene
from conical_pendulum.builder.compiler import build_core
from conical_pendulum.builder.fmu import build_fmu
from results_csv import write_rows

VARIANTS = {
    "seed (links + bobs, all outputs)": Scene.uniform(3),
    "state only (no calculated outputs)": Scene.uniform(3, outputs=()),
    "bobs only (massless links)": Scene.uniform(3, massless_links=True),
    "links only (no bobs)": Scene.uniform(3, bobs=False),
}


def main():
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        fmus = {}
        for label, scene in VARIANTS.items():
            build = build_core(scene)
            core = build.load()
            x = np.array(scene.initial_state()) + np.linspace(0.1, 0.3, core.NSTATE)
            p = np.array(scene.parameters())
            rhs = np.median([core.seconds_per_call("rhs", x, p, 200000) for _ in range(5)])
            out = np.median([core.seconds_per_call("outputs", x, p, 200000) for _ in range(5)])
            lines = len((build.directory / "model.c").read_text().splitlines())
            fmus[label] = build_fmu(scene, Path(tmp) / f"{len(fmus)}.fmu").path
            rows.append([label, rhs, out, core.NOUTPUT, len(scene.parameter_names()), lines])
        times = {label: [] for label in fmus}
        for path in fmus.values():  # warm
            fmpy.simulate_fmu(str(path), stop_time=10.0, output_interval=1 / 60)
        for _ in range(9):
            for label, path in fmus.items():
                start = time.perf_counter()
                fmpy.simulate_fmu(str(path), stop_time=10.0, output_interval=1 / 60)
                times[label].append(time.perf_counter() - start)
    print(
        f"{'scene':<36} {'RHS us':>7} {'outputs us':>10} {'outputs':>8} {'params':>7} "
        f"{'C lines':>8} {'fmpy ms':>8}"
    )
    table = []
    for label, rhs, out, n_out, n_par, lines in rows:
        print(
            f"{label:<36} {rhs * 1e6:7.3f} {out * 1e6:10.3f} {n_out:8d} {n_par:7d} {lines:8d} "
            f"{np.median(times[label]) * 1e3:8.1f}"
        )
        table.append(
            {
                "scene": label,
                "rhs_us": round(rhs * 1e6, 3),
                "outputs_us": round(out * 1e6, 3),
                "outputs": n_out,
                "parameters": n_par,
                "c_lines": lines,
                "simulate_fmu_ms": round(float(np.median(times[label])) * 1e3, 1),
            }
        )
    write_rows("scene_cost", table)


if __name__ == "__main__":
    main()
