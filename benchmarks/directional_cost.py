"""What the native FMU's directional derivatives cost against one right-hand side.

    python benchmarks/directional_cost.py

For the seed scene (3 links, expanded equations), the same with a moving support (inputs
a_pivot, outputs F_pivot and M_pivot) and a chain of 20 links (recursive formulation):
the native FMU's binary driven from C (benchmarks/directional_host.c, compiled here;
Model Exchange, one fixed state), timing per call
- set: fmi2SetContinuousStates alone (it precedes every call below, so nothing is cached);
- rhs: one fmi2GetDerivatives, one right-hand side: the unit of the table;
- outputs: fmi2GetReal of every calculated output;
- dd_derivatives / dd_outputs / dd_derivatives_and_outputs: one fmi2GetDirectionalDerivative
  along one direction of all states and inputs, for the state derivatives, the outputs, both;
- jacobian_states: d(derivatives)/d(states), one call per state (CP_NSTATE directions).
Medians of repeats, the operations interleaved, in one run; the set time is subtracted.
Writes benchmarks/results/directional_cost.csv.
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
    "seed, 3 links": Scene.uniform(3),
    "3 links, moving support": Scene.uniform(3, coupling=True),
    "20 links (recursive)": Scene.uniform(20),
}
REPEATS = 9


def main():
    rows = []
    with tempfile.TemporaryDirectory(prefix="directional_cost_") as tmp:
        tmp = Path(tmp)
        host = tmp / "directional_host"
        subprocess.run(
            [
                "cc",
                "-std=c99",
                "-O2",
                "-Wall",
                "-Wextra",
                "-Werror",
                f"-I{fmi_headers()}",
                str(HERE / "directional_host.c"),
                "-o",
                str(host),
                "-ldl",
                "-lm",
            ],
            check=True,
        )
        for k, (label, scene) in enumerate(SCENES.items()):
            path = build_fmu(scene, tmp / f"scene{k}.fmu", backend="native").path
            md = read_model_description(str(path))
            folder = tmp / f"scene{k}"
            zipfile.ZipFile(path).extractall(folder)
            vr = {v.name: v.valueReference for v in md.modelVariables}

            def listed(names):
                return ",".join(str(vr[n]) for n in names) or "-"

            outputs = list(scene.output_names())
            derivatives = [u.variable.name for u in md.derivatives]
            n_state = len(scene.state_names())
            calls = max(200, 200_000 // (n_state * n_state))
            run = subprocess.run(
                [
                    str(host),
                    str(folder / "binaries" / "linux64" / "ConicalPendulum.so"),
                    md.guid,
                    listed(scene.state_names()),
                    listed(scene.input_names()),
                    listed(derivatives),
                    listed(outputs),
                    str(calls),
                    str(REPEATS),
                ],
                capture_output=True,
                text=True,
                check=True,
            )
            us = {name: float(value) for name, value in (line.split() for line in run.stdout.splitlines())}
            unit = us["rhs"] - us["set"]
            for name in (
                "rhs",
                "outputs",
                "dd_derivatives",
                "dd_outputs",
                "dd_derivatives_and_outputs",
                "jacobian_states",
            ):
                cost = us[name] - us["set"]
                rows.append(
                    {
                        "scene": label,
                        "states": n_state,
                        "inputs": len(scene.input_names()),
                        "outputs": len(outputs),
                        "operation": name,
                        "us_per_call": round(cost, 3),
                        "ratio_to_rhs": round(cost / unit, 2),
                    }
                )
                print(f"{label:26s} {name:28s} {cost:10.3f} us {cost / unit:8.2f} x rhs")
    print(write_rows("directional_cost", rows))


if __name__ == "__main__":
    main()
