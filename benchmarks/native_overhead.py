"""What each FMU costs a master per step, next to the master's own floor and the physics.

    python benchmarks/native_overhead.py

The seed scenario (10 s) with three FMUs: the native FMU, the pythonfmu FMU, and a
trivial C FMU (benchmarks/trivial_fmu/trivial.c: constant outputs, a doStep that does
nothing; the master's own floor) with as many variables as the master reads from the
native FMU, in two masters:
- ecos' command-line engine (the executable in the ecospy wheel) at 600 steps/s, writing
  its CSV as a user would: ecos reads and writes every Real variable at every step
  (parameters and the derivatives too), so the trivial FMU has as many Real variables
  as the native FMU; the time of a run of ten steps (start-up, loading, CSV header) is
  subtracted, so what remains is the stepping;
- fmpy.simulate_fmu at 60 steps/s, every output recorded: the trivial FMU has as many
  outputs.
Medians of repeats, the FMUs interleaved, in one run. The physics floor is the right-hand
sides per step (the FMU's n_rhs) times one right-hand side timed in a C loop.
Writes benchmarks/results/native_overhead.csv.
"""

import importlib.util
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import fmpy
import numpy as np

from conical_pendulum import Scene
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.builder.fmu import build_fmu
from conical_pendulum.builder.packaging.native import fmi_headers
from results_csv import write_rows

HERE = Path(__file__).parent
REPEATS = 7
STOP = 10.0
BASE = 10  # steps of the ecos run whose time is subtracted as start-up


def build_trivial(outputs: int, folder: Path) -> Path:
    """The trivial C FMU with `outputs` Real outputs."""
    library = folder / "Trivial.so"
    subprocess.run(
        [
            "cc",
            "-O2",
            "-fPIC",
            "-shared",
            f"-DN_OUTPUTS={outputs}",
            f"-I{fmi_headers()}",
            str(HERE / "trivial_fmu" / "trivial.c"),
            "-o",
            str(library),
        ],
        check=True,
    )
    root = ET.Element(
        "fmiModelDescription",
        fmiVersion="2.0",
        modelName="Trivial",
        guid="{trivial}",
        numberOfEventIndicators="0",
    )
    ET.SubElement(
        root, "CoSimulation", modelIdentifier="Trivial", canHandleVariableCommunicationStepSize="true"
    )
    variables = ET.SubElement(root, "ModelVariables")
    for k in range(outputs):
        v = ET.SubElement(
            variables,
            "ScalarVariable",
            name=f"y{k}",
            valueReference=str(k),
            causality="output",
            variability="continuous",
            initial="exact",
        )
        ET.SubElement(v, "Real", start=str(float(k)))
    structure = ET.SubElement(ET.SubElement(root, "ModelStructure"), "Outputs")
    for k in range(outputs):
        ET.SubElement(structure, "Unknown", index=str(k + 1), dependencies="")
    path = folder / "Trivial.fmu"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("modelDescription.xml", ET.tostring(root, xml_declaration=True, encoding="UTF-8"))
        archive.write(library, "binaries/linux64/Trivial.so")
    return path


def ecos_command(folder: Path):
    """ecos' executable and the environment it needs: libtbb, and for pythonfmu, libpython."""
    binaries = Path(importlib.util.find_spec("ecospy").submodule_search_locations[0]) / "binaries"
    ecos = folder / "ecos"
    shutil.copy2(binaries / "ecos", ecos)
    ecos.chmod(0o755)
    libpython = Path(sysconfig.get_config_var("LIBDIR")) / sysconfig.get_config_var("LDLIBRARY")
    plain = {"LD_LIBRARY_PATH": str(Path(sys.prefix) / "lib")}
    python = {**plain, "LD_PRELOAD": str(libpython), "PYTHONPATH": sysconfig.get_paths()["purelib"]}
    return ecos, plain, python


def ecos_seconds(ecos, env, fmu, stop, step, folder) -> float:
    start = time.perf_counter()
    subprocess.run(
        [
            str(ecos),
            "simulate",
            "--path",
            str(fmu),
            "--stopTime",
            repr(stop),
            "--stepSize",
            repr(step),
            "--noParallel",
            "-l",
            "warn",
        ],
        cwd=folder,
        env=env,
        check=True,
        capture_output=True,
    )
    return time.perf_counter() - start


def main():
    scene = Scene.uniform(3)
    core = load_core(scene)
    rhs_seconds = core.seconds_per_call("rhs", scene.initial_state(), scene.parameters(), 200_000)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        native = build_fmu(scene, tmp / "native" / "ConicalPendulum.fmu", backend="native").path
        python = build_fmu(scene, tmp / "python" / "ConicalPendulum.fmu").path
        variables = fmpy.read_model_description(str(native)).modelVariables
        read = {
            "ecos": sum(v.type == "Real" for v in variables),
            "fmpy": sum(v.causality == "output" for v in variables),
        }
        ecos, plain, with_python = ecos_command(tmp)
        rows = []
        for master, steps_per_second in (("ecos", 600), ("fmpy", 60)):
            (tmp / f"trivial_{master}").mkdir()
            trivial = build_trivial(read[master], tmp / f"trivial_{master}")
            fmus = {
                "native": (native, plain),
                "pythonfmu": (python, with_python),
                "trivial C": (trivial, plain),
            }
            step, steps = 1.0 / steps_per_second, round(STOP * steps_per_second)
            times = {name: [] for name in fmus}
            for _ in range(REPEATS):
                for name, (path, env) in fmus.items():
                    if master == "ecos":  # less a run of BASE steps (ecos fails on one)
                        seconds = ecos_seconds(ecos, env, path, STOP, step, tmp) - ecos_seconds(
                            ecos, env, path, BASE * step, step, tmp
                        )
                        times[name].append(seconds / (steps - BASE))
                    else:
                        start = time.perf_counter()
                        fmpy.simulate_fmu(str(path), stop_time=STOP, output_interval=step)
                        times[name].append((time.perf_counter() - start) / steps)
            per_step = {name: float(np.median(values)) for name, values in times.items()}
            run = fmpy.simulate_fmu(str(native), stop_time=STOP, output_interval=step)
            physics = run["n_rhs"][-1] / steps * rhs_seconds
            for name, seconds in per_step.items():
                rows.append(
                    {
                        "master": f"{master}, {steps_per_second} steps/s",
                        "fmu": name,
                        "variables_read": read[master],
                        "us_per_step": round(seconds * 1e6, 2),
                        "ratio_to_trivial": round(seconds / per_step["trivial C"], 2),
                        "physics_floor_us": round(physics * 1e6, 2),
                    }
                )
    write_rows("native_overhead", rows)
    print(f"one right-hand side: {rhs_seconds * 1e6:.2f} us (C loop); medians of {REPEATS}")
    print(f"{'master':<22} {'FMU':<10} {'us/step':>9} {'x trivial':>10} {'physics floor us':>17}")
    for row in rows:
        print(
            f"{row['master']:<22} {row['fmu']:<10} {row['us_per_step']:>9} "
            f"{row['ratio_to_trivial']:>10} {row['physics_floor_us']:>17}"
        )


if __name__ == "__main__":
    main()
