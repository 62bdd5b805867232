"""Scene -> ConicalPendulum.fmu: compiled core plus a rendered pythonfmu slave.

pythonfmu writes the archive; this module then completes its modelDescription
(InitialUnknowns for the calculated outputs, which pythonfmu leaves out) and moves
the FMU into place only when everything succeeded.
"""
from __future__ import annotations

import hashlib
import os
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path

from .compiler import CoreBuild, build_core
from ..scene import PIVOT_OUTPUTS, Scene

HERE = Path(__file__).parent
TEMPLATE = HERE.parent / "runtime" / "slave.py"
MODEL_NAME = "ConicalPendulum"
DEFAULT_SETTINGS = {"rtol": 1e-8, "atol": 1e-8, "max_step": 0.0, "solver": 1, "max_steps": 100_000}


@dataclass
class FmuBuild:
    path: Path
    core: CoreBuild
    module_name: str
    seconds: float


# The module pythonfmu loads. pythonfmu 0.7 compiles and executes it again at every
# instantiation to find the slave class (findClass), with the module's dict as globals and
# a fresh dict as locals; it never releases the classes it finds in those locals, and it
# releases the module's dict once without having taken a reference. So it stays tiny
# (compiled per instance), defines the class only at import, and later only names it and
# gives the dict its reference back.
ENTRY = '''"""{model}: FMI 2.0 co-simulation FMU entry point (the slave is {implementation})."""
if "{model}" in globals():
    {model} = globals()["{model}"]
    __import__("ctypes").pythonapi.Py_IncRef(__import__("ctypes").py_object(globals()))
else:
    from {implementation} import {model}
'''


def start_values(scene: Scene) -> dict[str, dict[str, float]]:
    """The scene's start values by name: parameters, inputs (at rest) and state."""
    return {"PARAMETER_START": dict(zip(scene.parameter_names(), scene.parameter_defaults())),
            "INPUT_START": dict.fromkeys(scene.input_names(), 0.0),
            "STATE_START": dict(zip(scene.state_names(), scene.state_defaults()))}


def render_slave(scene: Scene, core: CoreBuild, settings: dict) -> tuple[str, str]:
    """(module name, source) of the slave: the template with this scene's values."""
    values = {
        "CORE_MODULE": core.module_name,
        "CORE_FILE": core.library.name,
        **start_values(scene),
        "DESCRIPTION": _description(scene),
        "SETTINGS_START": settings,
    }
    template = TEMPLATE.read_text()
    start = template.index("# --- rendered by conical_pendulum.fmu ---\n")
    end = template.index("# --- end of rendered values ---\n")
    block = "".join(f"{name} = {value!r}\n" for name, value in values.items())
    source = template[:start] + "# --- rendered by conical_pendulum.fmu ---\n" + block + template[end:]
    digest = hashlib.sha256(source.encode()).hexdigest()[:16]
    return f"cp_slave_{digest}", source


def build_fmu(scene: Scene, output: Path | str = Path("dist") / f"{MODEL_NAME}.fmu",
              settings: dict | None = None, cache: Path | None = None) -> FmuBuild:
    start = time.perf_counter()
    output = Path(output)
    if output.suffix != ".fmu":
        raise ValueError(f"output: {str(output)!r} must end in .fmu")
    unknown = set(settings or {}) - set(DEFAULT_SETTINGS)
    if unknown:
        raise ValueError(f"unknown setting(s) {sorted(unknown)}; known: {sorted(DEFAULT_SETTINGS)}")
    core = build_core(scene, cache)
    settings = {**DEFAULT_SETTINGS, **(settings or {})}
    slave_name, source = render_slave(scene, core, settings)
    starts = {name: value for group in start_values(scene).values() for name, value in group.items()}
    module_name = slave_name.replace("cp_slave_", "conical_pendulum_")
    package(MODEL_NAME, module_name, slave_name, source, [core.library], output, {**starts, **settings},
            describe, feedthrough=PIVOT_OUTPUTS if scene.coupling else (),
            canGetAndSetFMUstate=True, canSerializeFMUstate=True)
    return FmuBuild(output, core, module_name, time.perf_counter() - start)


def package(model: str, module_name: str, slave_name: str, source: str, project_files: list[Path],
            output: Path, starts: dict, describe=None, feedthrough=(), **capabilities) -> None:
    """Build the FMU of a pythonfmu slave (class `model` in module `slave_name`) at `output`.

    The module pythonfmu loads is the small ENTRY, named `module_name` (the FMU's model
    identifier); the FMU moves into place only when everything succeeded. `describe`
    gives variable descriptions by name, if the slave's own are not kept; `feedthrough`
    names the outputs that depend at once on the inputs.
    """
    from pythonfmu import FmuBuilder  # build time only

    output.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="conical_pendulum_fmu_") as tmp:
        tmp = Path(tmp)
        script = tmp / "src" / f"{module_name}.py"
        script.parent.mkdir()
        script.write_text(ENTRY.format(model=model, implementation=slave_name))
        slave = script.parent / f"{slave_name}.py"
        slave.write_text(source)
        staged = tmp / f"{model}.fmu"
        saved_path, saved_modules = list(sys.path), set(sys.modules)
        try:
            FmuBuilder.build_FMU(script, dest=staged, project_files=[slave, *project_files],
                                 canHandleVariableCommunicationStepSize=True, **capabilities)
        finally:  # pythonfmu leaves its import of the slave behind
            sys.path[:] = saved_path
            for name in set(sys.modules) - saved_modules:
                if name in (module_name, slave_name):
                    del sys.modules[name]
        _finish(staged, starts, describe, set(feedthrough))
        os.replace(staged, output)


def _finish(fmu: Path, starts: dict, describe, feedthrough: set[str]) -> None:
    """Complete ModelStructure as FMI 2.0 requires; exact start values; this platform only;
    text compressed, binaries stored (fmpy extracts the FMU at every simulate_fmu).

    Outputs declare their direct feedthrough (the `feedthrough` outputs depend on every
    input, the others on none), so a master knows where an algebraic loop can be.

    pythonfmu lists no InitialUnknowns, writes Real starts with 16 digits (a double
    needs 17 to round-trip), and packs binaries for every platform it has, while the
    compiled core runs only on the platform that built it.
    """
    from pythonfmu.osutil import get_platform

    platform = f"binaries/{get_platform()}/"
    with zipfile.ZipFile(fmu) as archive:
        entries = {info.filename: archive.read(info) for info in archive.infolist()
                   if not info.filename.startswith("binaries/") or info.filename.startswith(platform)}
    root = ET.fromstring(entries["modelDescription.xml"])
    variables = root.find("ModelVariables").findall("ScalarVariable")
    structure = root.find("ModelStructure")
    for child in list(structure):
        structure.remove(child)
    outputs = ET.SubElement(structure, "Outputs")
    initial = ET.SubElement(structure, "InitialUnknowns")
    inputs = " ".join(str(index) for index, var in enumerate(variables, start=1)
                      if var.get("causality") == "input")
    for index, var in enumerate(variables, start=1):
        real = var.find("Real")
        if describe:
            var.set("description", describe(var.get("name")))
        if real is not None and real.get("start") is not None:
            real.set("start", repr(float(starts[var.get("name")])))
        if var.get("causality") == "output":
            direct = var.get("name") in feedthrough
            ET.SubElement(outputs, "Unknown", index=str(index), dependencies=inputs if direct else "",
                          **({"dependenciesKind": " ".join(["dependent"] * len(inputs.split()))}
                             if direct and inputs else {}))
            if var.get("initial") in ("calculated", "approx"):
                ET.SubElement(initial, "Unknown", index=str(index))
    if not len(initial):
        structure.remove(initial)
    ET.indent(root)
    entries["modelDescription.xml"] = ET.tostring(root, encoding="UTF-8", xml_declaration=True)
    with zipfile.ZipFile(fmu, "w") as archive:
        for name, data in entries.items():  # binaries stored: every run extracts them
            stored = name.endswith((".so", ".dll", ".dylib"))
            archive.writestr(name, data, zipfile.ZIP_STORED if stored else zipfile.ZIP_DEFLATED)


def _description(scene: Scene) -> str:
    links = ", ".join(
        ("cylinder" if link.has_mass else "massless") + ("+bob" if link.has_bob else "")
        for link in scene.links)
    kinematics = ("" if scene.kinematics == "consistent"
                  else "; PUBLISHED pydy-example kinematics (does not conserve energy)")
    coupling = ("; hangs from a moving support: inputs a_pivot_x/y/z (held constant over each "
                "communication step), outputs F_pivot_x/y/z" if scene.coupling else "")
    return f"{scene.n}-link conical pendulum ({links}){kinematics}{coupling}"


_INDEXED = {
    "l": "length of link {i} [m]", "m": "mass of bob {i} [kg]", "M": "mass of link {i} [kg]",
    "Ixx": "central inertia of link {i} about its x axis [kg m2]",
    "Iyy": "central inertia of link {i} about its own (y) axis [kg m2]",
    "Izz": "central inertia of link {i} about its z axis [kg m2]",
    "alpha": "angle of joint {i} about the parent's z axis [rad]",
    "beta": "angle of joint {i} about the parent's x axis [rad]",
    "omega": "alpha{i}' [rad/s]", "delta": "beta{i}' [rad/s]",
}
_NAMED = {
    "g": "gravitational acceleration along -Y [m/s2]",
    "energy": "total mechanical energy relative to the pivot (kinetic + potential, zero at Y = 0) [J]",
    "rtol": "relative tolerance of the adaptive solvers (replaced by setupExperiment's tolerance when given)",
    "atol": "absolute tolerance of the adaptive solvers",
    "max_step": "largest internal step [s]; RK4 splits each communication step into steps of at most this (0: no limit)",
    "solver": "0 = RK4 (fixed step), 1 = RK45 (Dormand-Prince 5(4)), 2 = DOP853, 3 = Radau (scipy, stiff)",
    "max_steps": "most internal steps per do_step: a step needing more is discarded",
    "n_rhs": "right-hand side evaluations so far",
    "n_steps": "accepted internal steps so far",
    "n_rejected": "rejected internal steps so far",
}


def describe(name: str) -> str:
    """The description of an FMU variable, from its name."""
    if name in _NAMED:
        return _NAMED[name]
    if name.startswith("a_pivot_"):
        return (f"acceleration of the pivot (the support), inertial {name[-1]} (Y up) [m/s2]; "
                "held constant over each communication step")
    if name.startswith("F_pivot_"):
        return (f"force the pendulum exerts on its support, inertial {name[-1]} (Y up) [N]; "
                "depends at once on the a_pivot inputs")
    if name.startswith("bob"):
        return f"bob {name[3:].split('_')[0]} position relative to the pivot, inertial {name[-1]} (Y up) [m]"
    if name.startswith("link"):
        index, part = name[4:].split("_")
        if part.startswith("q"):
            return f"link {index} orientation quaternion, {part[1]} component"
        return f"link {index} mass-centre position relative to the pivot, inertial {part} [m]"
    kind = name.rstrip("0123456789")
    return _INDEXED[kind].format(i=name[len(kind):])
