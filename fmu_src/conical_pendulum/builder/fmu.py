"""Scene -> ConicalPendulum.fmu: the compiled core, the runtime's slave and the scene's data.

The slave is one ordinary module for every scene (runtime/slave.py); what is particular
to a scene (its variables, start values, descriptions, the core's file) goes into
resources/model.json. pythonfmu writes the archive; model_description.complete then
mends its modelDescription, and the FMU moves into place only when everything succeeded.
"""

from __future__ import annotations

import ast
import contextlib
import hashlib
import importlib
import importlib.metadata
import json
import os
import shutil
import sys
import tempfile
import time
import zipfile
from dataclasses import dataclass, replace
from pathlib import Path

from ..runtime.files import MODEL_FILE, MODEL_NAME
from ..runtime.rules import SETTINGS, check_setting
from ..scene import Scene
from .compiler import CoreBuild, build_core
from .fmi.variables import Variable, records, variables
from .models import pendulum
from .models.pendulum import DEFAULT_SETTINGS
from .packaging.pythonfmu_description import complete, model_description_text
from .packaging.pythonfmu_export import export_library

RUNTIME = Path(__file__).parents[1] / "runtime"


@dataclass
class FmuBuild:
    path: Path
    core: CoreBuild
    module_name: str  # the FMU's entry module (pythonfmu's slavemodule.txt)
    seconds: float


def model_data(
    scene: Scene, core: CoreBuild, settings: dict, backend: str = "pythonfmu", arrays: bool = True
) -> dict:
    """What the slave reads from MODEL_FILE: the FMU's variables in value-reference order
    (builder.fmi.variables, as dicts), the core's file, the settings' start values, and the
    scene itself (see fmu_scene). arrays=False: no variable in an FMI 3.0 array, each
    element a scalar of its own (alpha0, alpha1, ...), as in FMI 2.0."""
    found = variables(scene, settings, backend)
    if not arrays:
        found = [replace(v, array=None, index=None) for v in found]
    return {
        "model": MODEL_NAME,
        "description": model_description_text(scene),
        "core": {"module": core.module_name, "file": core.library.name},
        "variables": [v.to_dict() for v in found],
        "settings": settings,
        "scene": scene.to_dict(),
    }


BACKENDS = ("pythonfmu", "native")


def build_fmu(
    scene: Scene,
    output: Path | str = Path("dist") / f"{MODEL_NAME}.fmu",
    settings: dict | None = None,
    cache: Path | None = None,
    backend: str = "pythonfmu",
    platforms: tuple[str, ...] = ("linux64",),
    fmi_version: int = 2,
    arrays: bool = True,
) -> FmuBuild:
    """The scene's FMU at `output`: the pythonfmu slave (the default), or with
    backend="native" the same C with FMI glue in C (builder.packaging.native), with a binary for each
    of `platforms` ("linux64", and cross-compiled "win64" and, FMI 3.0 only, "aarch64-linux";
    the pythonfmu FMU is linux64 only).
    fmi_version=3 (native only): an FMI 3.0 FMU (builder.fmi.fmi3) instead of FMI 2.0; with
    arrays=False its per-link quantities are scalars with FMI 2.0's names, for tools that read
    no FMI 3.0 arrays (OMSimulator reads each array as its first element)."""
    if fmi_version not in (2, 3):
        raise ValueError(f"fmi_version: {fmi_version!r} is not 2 or 3")
    if not arrays and fmi_version != 3:
        raise ValueError("arrays: only an FMI 3.0 FMU has arrays; arrays=False needs fmi_version=3")
    if fmi_version == 3 and backend != "native":
        raise ValueError("fmi_version: the pythonfmu FMU is FMI 2.0 only; FMI 3.0 needs backend='native'")
    if backend != "native" and tuple(platforms) != ("linux64",):
        raise ValueError(
            f"platforms: the pythonfmu FMU runs on linux64 only, not {platforms}; "
            "a native FMU (backend='native') can carry win64 too"
        )
    if backend not in BACKENDS:
        raise ValueError(f"backend: {backend!r} is not one of {BACKENDS}")
    start = time.perf_counter()
    output, settings = checked_output(output), checked_settings(settings)
    # the pythonfmu slave's model is the core's, with these settings' start values; the
    # native FMU compiles its own from the core's generated C
    core = build_core(scene, cache, settings if backend == "pythonfmu" else None)
    data = model_data(scene, core, settings, backend, arrays)
    if backend == "native":
        pendulum.write_native_fmu(scene, core.directory, data, output, platforms, fmi_version)
        return FmuBuild(output, core, MODEL_NAME, time.perf_counter() - start)
    with tempfile.TemporaryDirectory(prefix="conical_pendulum_model_") as tmp:
        model_file = Path(tmp) / MODEL_FILE
        model_file.write_text(json.dumps(data, indent=1))
        module_name = package(
            "slave",
            [model_file, core.library],
            output,
            records(data),
            canGetAndSetFMUstate=True,
            canSerializeFMUstate=True,
        )
    return FmuBuild(output, core, module_name, time.perf_counter() - start)


def checked_output(output: Path | str) -> Path:
    output = Path(output)
    if output.suffix != ".fmu":
        raise ValueError(f"output: {str(output)!r} must end in .fmu")
    if output.is_dir():
        raise ValueError(f"output: {str(output)!r} is a directory")
    folder = next(parent for parent in output.absolute().parents if parent.exists())
    if not folder.is_dir():  # the FMU's folder would be made inside a file
        raise ValueError(f"output: {str(output)!r}: {str(folder)!r} is not a directory")
    return output


def checked_settings(settings: dict | None) -> dict:
    """Every solver setting: the defaults, some replaced; unknown names and bad values refused."""
    unknown = set(settings or {}) - set(SETTINGS)
    if unknown:
        raise ValueError(f"unknown setting(s) {sorted(unknown)}; known: {sorted(SETTINGS)}")
    return {
        name: check_setting(name, value) for name, value in {**DEFAULT_SETTINGS, **(settings or {})}.items()
    }


def runtime_digest() -> str:
    """A hash of the runtime's Python sources: the package name they ship under."""
    digest = hashlib.sha256()
    for path in sorted(RUNTIME.glob("*.py")):
        digest.update(path.name.encode() + path.read_bytes())
    return digest.hexdigest()[:16]


def runtime_modules(slave_module: str) -> list[str]:
    """The runtime's modules an FMU of runtime/<slave_module>.py ships: the package's
    __init__, the slave and what they import from the runtime, transitively (their
    relative imports, read from the sources)."""
    needed, wanted = set(), ["__init__", slave_module]
    while wanted:
        name = wanted.pop()
        if name in needed:
            continue
        needed.add(name)
        for node in ast.walk(ast.parse((RUNTIME / f"{name}.py").read_text(), f"{name}.py")):
            if isinstance(node, ast.ImportFrom) and node.level == 1:
                wanted += [node.module] if node.module else [alias.name for alias in node.names]
    return sorted(needed)


def package(
    slave_module: str,
    data_files: list[Path],
    output: Path,
    described: list[Variable],
    **capabilities,
) -> str:
    """Build the FMU of runtime/<slave_module>.py (its SLAVE class) at `output`.

    The FMU's resources hold the runtime's modules the slave runs with (runtime_modules)
    as the package cp_runtime_<digest>, the entry module pythonfmu loads (runtime/entry.py
    as <slave_module>_<digest>.py) and `data_files`; its model description is completed
    from `described`, the variables as builder.fmi.variables describes them
    (model_description.complete). Returns the entry module's name.
    """
    digest = runtime_digest()
    runtime_name, entry_name = f"cp_runtime_{digest}", f"{slave_module}_{digest}"
    output.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="conical_pendulum_fmu_") as tmp:
        src = Path(tmp) / "src"
        runtime = src / runtime_name
        runtime.mkdir(parents=True)
        for name in runtime_modules(slave_module):
            shutil.copy2(RUNTIME / f"{name}.py", runtime / f"{name}.py")
        script = src / f"{entry_name}.py"
        shutil.copy2(RUNTIME / "entry.py", script)
        staged = Path(tmp) / f"{slave_module}.fmu"
        saved_path = list(sys.path)
        try:  # pythonfmu leaves its import of the slave behind: _installed_pythonfmu drops it
            with _installed_pythonfmu(entry_name, runtime_name) as pythonfmu:
                pythonfmu.FmuBuilder.build_FMU(
                    script,
                    dest=staged,
                    project_files=[runtime, *data_files],
                    canHandleVariableCommunicationStepSize=True,
                    **capabilities,
                )
                complete(staged, described, export_library())
        finally:
            sys.path[:] = saved_path
        os.replace(staged, output)
    return entry_name


@contextlib.contextmanager
def _installed_pythonfmu(*packages: str):
    """The installed pythonfmu, imported (build time only), with the modules of `packages`
    (the FMU's entry and runtime) set aside while it builds, and put back after for the FMUs
    still using them. A pythonfmu FMU that ran in this process (fmpy loads one in-process)
    has imported those from its resources, and its own copy of pythonfmu, whose builder finds
    no binaries to pack and whose Fmi2Slave is not the installed one's; that copy is set
    aside too."""
    installed = Path(importlib.metadata.distribution("pythonfmu").locate_file("pythonfmu")).resolve()
    loaded = sys.modules.get("pythonfmu")
    shadowed = loaded is not None and Path(loaded.__path__[0]).resolve() != installed
    tops = (*packages, "pythonfmu") if shadowed else packages

    def ours(name):
        return name.split(".")[0] in tops

    aside = {name: sys.modules.pop(name) for name in list(sys.modules) if ours(name)}
    if shadowed:
        sys.path.insert(0, str(installed.parent))
    try:
        yield importlib.import_module("pythonfmu")
    finally:
        if shadowed:
            sys.path.remove(str(installed.parent))
        for name in [name for name in sys.modules if ours(name)]:
            del sys.modules[name]
        sys.modules.update(aside)


def fmu_scene(path: Path | str) -> Scene:
    """The scene an FMU of this package was built from (its resources' MODEL_FILE)."""
    try:
        with zipfile.ZipFile(path) as archive:
            data = json.loads(archive.read(f"resources/{MODEL_FILE}"))
    except OSError as exc:  # no such file, a folder, no permission: that first, not what it is not
        raise ValueError(f"{path}: {exc.strerror or exc}") from None
    except (KeyError, zipfile.BadZipFile, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: not an FMU built by conical_pendulum ({exc})") from None
    if "scene" not in data:  # the coupled demo's cart: built here, but no pendulum
        raise ValueError(f"{path}: {data.get('model', 'this FMU')} is no pendulum: it has no scene")
    return Scene.from_dict(data["scene"])
