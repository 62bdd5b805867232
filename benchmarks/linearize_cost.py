"""What a linear model of a long chain costs: A, B, C, D of the 100-link chain's native FMU.

    python benchmarks/linearize_cost.py

In one process, on the native FMI 2.0 and 3.0 FMUs of Scene.uniform(100) (400 states, 1,401
outputs) and of the seed (3 links) for scale, at the hanging equilibrium: analysis.linearize's whole
call (reading the model description with fmpy, instantiating, initializing, the
derivatives, the matrices) by the FMU's directional derivatives grouped by the
ModelStructure's sparsity (the default), with one directional-derivative call per column,
and by extrapolated central differences (4 evaluations of f and g per group); the calls each
made, and fmpy's read_model_description alone (unvalidated, as linearize reads it), the part
of the whole no method changes.
Medians of 5 repeats. Also each method's largest difference from the default's A and C.
Writes benchmarks/results/linearize_cost.csv.
"""

import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
from fmpy import read_model_description

from conical_pendulum import Scene
from conical_pendulum.analysis.linearize import linearize
from conical_pendulum.builder.fmu import build_fmu
from results_csv import write_rows

REPEATS = 5
HANGING = {"alpha*": 0.0, "beta*": 0.0}
METHODS = {  # name: linearize's options
    "directional, grouped": {"method": "directional"},
    "directional, one call per column": {"method": "directional", "grouped": False},
    "differences, grouped": {"method": "differences"},
}


def timed(f):
    times, result = [], None
    for _ in range(REPEATS):
        begin = time.perf_counter()
        result = f()
        times.append(time.perf_counter() - begin)
    return statistics.median(times), result


def main():
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for n, fmi_version in ((3, 2), (3, 3), (100, 2), (100, 3)):
            path = Path(folder) / f"chain{n}_fmi{fmi_version}.fmu"
            begin = time.perf_counter()
            build_fmu(Scene.uniform(n), path, backend="native", fmi_version=fmi_version)
            print(f"built {n} links, FMI {fmi_version}.0, in {time.perf_counter() - begin:.1f} s")
            reading, _ = timed(lambda: read_model_description(str(path), validate=False))
            reference = None
            for name, options in METHODS.items():
                seconds, model = timed(lambda: linearize(path, states=HANGING, **options))
                reference = model if reference is None else reference
                difference = max(np.abs(model.A - reference.A).max(), np.abs(model.C - reference.C).max())
                rows.append(
                    {
                        "links": n,
                        "fmi": f"{fmi_version}.0",
                        "states": len(model.states),
                        "outputs": len(model.outputs),
                        "method": name,
                        "calls": model.calls,
                        "seconds": f"{seconds:.4f}",
                        "of_which_reading_description": f"{reading:.4f}",
                        "largest_difference_from_grouped": f"{difference:.2g}",
                        "largest_error_estimate": "" if model.error is None else f"{model.error.max():.2g}",
                    }
                )
                print(rows[-1])
    print(f"wrote {write_rows('linearize_cost', rows)}")


if __name__ == "__main__":
    main()
