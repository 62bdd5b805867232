"""What the native FMU's output derivatives cost against one right-hand side.

    python benchmarks/output_derivatives_cost.py

For the pendulum on a moving support (3 links, expanded equations; 7 links, recursive), the
native FMI 2.0 FMU's binary driven from C (benchmarks/output_derivatives_host.c, compiled
here; Co-Simulation, after initialization), timing per call
- set: fmi2SetReal of a_pivot_x alone, alternating between two values (it precedes every call
  below, so nothing is cached);
- rhs: fmi2GetReal of the state derivatives, one right-hand side: the unit of the table;
- outputs: fmi2GetReal of every continuous output (states, positions, energy, forces, M_app);
- first: fmi2GetRealOutputDerivatives, order 1 of every continuous output;
- first_and_second: orders 1 and 2 of every continuous output in one call (what a
  second-order master asks once per step);
- dd_outputs: fmi2GetDirectionalDerivative of the outputs along a_pivot_x, for comparison.
Medians of repeats, the operations interleaved, in one run; the set time is subtracted.
Writes benchmarks/results/output_derivatives_cost.csv.
"""

import subprocess
import tempfile
import zipfile
from pathlib import Path

from fmpy import read_model_description

from conical_pendulum import Scene
from conical_pendulum.builder.fmu import build_fmu
from conical_pendulum.builder.packaging.native import fmi_headers
from results_csv import write_rows

HERE = Path(__file__).parent
SCENES = {
    "3 links, moving support": Scene.uniform(3, coupling=True),
    "7 links, moving support (recursive)": Scene.uniform(7, coupling=True),
}
REPEATS = 5
OPERATIONS = ("rhs", "outputs", "first", "first_and_second", "dd_outputs")


def main():
    rows = []
    with tempfile.TemporaryDirectory(prefix="output_derivatives_cost_") as tmp:
        tmp = Path(tmp)
        host = tmp / "output_derivatives_host"
        flags = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", f"-I{fmi_headers()}"]
        source = str(HERE / "output_derivatives_host.c")
        subprocess.run(["cc", *flags, source, "-o", str(host), "-ldl"], check=True)
        for k, (label, scene) in enumerate(SCENES.items()):
            path = build_fmu(scene, tmp / f"scene{k}.fmu", backend="native").path
            md = read_model_description(str(path))
            folder = tmp / f"scene{k}"
            zipfile.ZipFile(path).extractall(folder)
            outputs = [
                v.valueReference
                for v in md.modelVariables
                if v.causality == "output" and v.variability == "continuous"
            ]
            derivatives = [u.variable.valueReference for u in md.derivatives]
            vr = {v.name: v.valueReference for v in md.modelVariables}
            run = subprocess.run(
                [
                    str(host),
                    str(folder / "binaries" / "linux64" / "ConicalPendulum.so"),
                    md.guid,
                    str(vr["a_pivot_x"]),
                    ",".join(map(str, derivatives)),
                    ",".join(map(str, outputs)),
                    "2000",
                    str(REPEATS),
                ],
                capture_output=True,
                text=True,
                check=True,
            )
            us = {name: float(value) for name, value in (line.split() for line in run.stdout.splitlines())}
            unit = us["rhs"] - us["set"]
            for name in OPERATIONS:
                cost = us[name] - us["set"]
                rows.append(
                    {
                        "scene": label,
                        "states": len(scene.state_names()),
                        "outputs": len(outputs),
                        "operation": name,
                        "us_per_call": round(cost, 3),
                        "ratio_to_rhs": round(cost / unit, 2),
                    }
                )
                print(f"{label:36s} {name:18s} {cost:10.3f} us {cost / unit:8.2f} x rhs")
    print(write_rows("output_derivatives_cost", rows))


if __name__ == "__main__":
    main()
