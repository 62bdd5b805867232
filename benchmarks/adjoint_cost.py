"""What the three F_pivot rows of the Jacobian cost by adjoint against directional derivatives.

    python benchmarks/adjoint_cost.py

A chain hanging from a moving support (inputs a_pivot, outputs F_pivot) of 20 and 100 links
(recursive formulation), the model contract driven from C (benchmarks/adjoint_host.c,
compiled with the native FMU's model sources, no FMI layer), at one fixed state; the knowns
are every state and input (2n + 3 for n links: all F_pivot depends on). Per operation:
- rhs: one right-hand side (model_set_states and model_get_derivatives), the unit;
- outputs: every output once (model_set_states and model_get_real of F_pivot_x), in real
  arithmetic: what a reverse sweep would start from (reverse mode's cost is a small multiple
  of it per row; not measured, there is none);
- adjoint: the 3 rows by model_adjoint_derivative, one call per row (seed 1 on that row);
- directional: the 3 rows by model_directional_derivative, one call per known, all 3 rows;
- directional_per_row: 3 x (2n + 3) calls, one row and one known each.
The adjoint is by complex step: one complex evaluation per known and per call, so a row costs
what its 2n + 3 directional derivatives cost; true reverse mode would cost a few right-hand
sides per row. Medians of repeats, the operations interleaved, in one run.
Writes benchmarks/results/adjoint_cost.csv.
"""

import subprocess
import tempfile
import zipfile
from pathlib import Path

from fmpy import read_model_description

from conical_pendulum import Scene
from conical_pendulum.builder.fmu import build_fmu
from conical_pendulum.builder.packaging.native import LAYER_SOURCES
from results_csv import write_rows

HERE = Path(__file__).parent
LINKS = (20, 100)
REPEATS = 5
GLUES = {name for layer in LAYER_SOURCES.values() for name in layer}  # both FMI layers and their body


def main():
    rows = []
    with tempfile.TemporaryDirectory(prefix="adjoint_cost_") as tmp:
        tmp = Path(tmp)
        for n in LINKS:
            scene = Scene.uniform(n, coupling=True)
            path = build_fmu(scene, tmp / f"chain{n}.fmu", backend="native").path
            folder = tmp / f"chain{n}"
            with zipfile.ZipFile(path) as archive:
                archive.extractall(folder)
            sources = folder / "sources"
            host = folder / "adjoint_host"
            model = [str(p) for p in sorted(sources.glob("*.c")) if p.name not in GLUES]
            subprocess.run(
                ["cc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", f"-I{sources}"]
                + [str(HERE / "adjoint_host.c"), *model, "-o", str(host), "-lm"],
                check=True,
            )
            vr = {v.name: v.valueReference for v in read_model_description(str(path)).modelVariables}
            states = [vr[name] for name in scene.state_names()]
            inputs = [vr[name] for name in scene.input_names()]
            forces = [vr[name] for name in ("F_pivot_x", "F_pivot_y", "F_pivot_z")]
            run = subprocess.run(
                [str(host), *(",".join(map(str, v)) for v in (states, inputs, forces)), "1", str(REPEATS)],
                capture_output=True,
                text=True,
                check=True,
            )
            us = {name: float(value) for name, value in (line.split() for line in run.stdout.splitlines())}
            unit = us["rhs"] - us["set"]
            us["rhs"], us["outputs"] = unit, us["outputs"] - us["set"]
            knowns = len(states) + len(inputs)
            for name, calls in (
                ("rhs", 1),
                ("outputs", 1),
                ("adjoint", 3),
                ("directional", knowns),
                ("directional_per_row", 3 * knowns),
            ):
                cost = us[name]
                rows.append(
                    {
                        "links": n,
                        "knowns": knowns,
                        "operation": name,
                        "calls": calls,
                        "us": round(cost, 1),
                        "ratio_to_rhs": round(cost / unit, 1),
                    }
                )
                print(f"{n:4d} links {name:20s} {calls:5d} calls {cost:12.1f} us {cost / unit:10.1f} x rhs")
    print(write_rows("adjoint_cost", rows))


if __name__ == "__main__":
    main()
