"""Scene -> compiled core: derive, generate C, compile with Cython (abi3), cache by hash.

The cache key covers the scene's structure and the generator's own sources, so a
rebuild of the same scene only loads the cached extension.
"""

from __future__ import annotations

import hashlib
import importlib.machinery
import importlib.util
import json
import os
import shutil
import sys
import sysconfig
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import UserError
from ..scene import Scene

HERE = Path(__file__).parent
CSRC = HERE.parent / "runtime" / "csrc"
CORE_CSRC = CSRC / "core"  # the model's numerics: the compiled core's C, and the native FMU's
# Every C file of runtime/csrc by name, whichever role's folder holds it (core/, fmi/: the FMI
# layers, models/: the models behind fmu_model.h); names are unique, so an FMU's sources/
# folder holds them side by side.
CSRC_FILES = {path.name: path for path in sorted(CSRC.glob("*/*.[ch]"))}
GENERATOR_SOURCES = [
    *(HERE / name for name in ("kane.py", "model.py", "codegen.py", "compiler.py")),
    HERE.parent / "runtime" / "rules.py",  # the statistics' slots (model.h)
    *sorted(CORE_CSRC.glob("*.[chp]*")),
]
LIMITED_API = "0x030B0000"  # CPython 3.11: one compiled file serves 3.11 and newer


def cache_root() -> Path:
    root = os.environ.get("CONICAL_PENDULUM_CACHE")
    if root:
        return Path(root)
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "conical_pendulum"


def generator_version() -> str:
    digest = hashlib.sha256()
    for path in GENERATOR_SOURCES:
        digest.update(path.name.encode() + path.read_bytes())
    return digest.hexdigest()


@dataclass
class CoreBuild:
    """Where a scene's compiled core is, and what building it cost."""

    scene: Scene
    directory: Path
    module_name: str
    cached: bool
    seconds: dict = field(default_factory=dict)

    @property
    def library(self) -> Path:
        return next(self.directory.glob(f"{self.module_name}.*.so"))

    def load(self):
        return load_module(self.module_name, self.library)


def load_module(name: str, path: Path):
    """Import an extension module from a file (no sys.path change)."""
    if name in sys.modules:
        return sys.modules[name]
    loader = importlib.machinery.ExtensionFileLoader(name, str(path))
    spec = importlib.util.spec_from_file_location(name, path, loader=loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    sys.modules[name] = module
    return module


def build_core(scene: Scene, cache: Path | None = None) -> CoreBuild:
    key = scene.key(generator_version())
    name = f"cp_core_{key[:16]}"
    directory = (cache or cache_root()) / name
    if (directory / "build.json").exists():
        return CoreBuild(scene, directory, name, cached=True)
    directory.parent.mkdir(parents=True, exist_ok=True)
    seconds = {}
    with tempfile.TemporaryDirectory(dir=directory.parent, prefix=f".{name}.") as tmp:
        work = Path(tmp)
        from .codegen import generate, generate_recursive  # sympy: build time only
        from .model import derive

        start = time.perf_counter()
        if scene.resolved_formulation() == "recursive":  # nothing to derive: loops over links
            seconds["derive"] = 0.0
            files = generate_recursive(scene)
        else:
            equations = derive(scene)
            seconds["derive"] = time.perf_counter() - start
            start = time.perf_counter()
            files = generate(equations)
        seconds["codegen"] = time.perf_counter() - start
        for filename, text in files.items():
            (work / filename).write_text(text)

        start = time.perf_counter()
        for source in CORE_CSRC.glob("*.[ch]"):
            shutil.copy2(source, work / source.name)
        shutil.copy2(CORE_CSRC / "core.pyx", work / f"{name}.pyx")
        _compile(name, work)
        seconds["compile"] = time.perf_counter() - start
        (work / "build.json").write_text(json.dumps({"scene": scene.to_dict(), "seconds": seconds}, indent=1))
        try:
            work.rename(directory)
        except OSError:
            if not (directory / "build.json").exists():  # not a concurrent build of the same key
                raise
    return CoreBuild(scene, directory, name, cached=False, seconds=seconds)


def _compile(name: str, work: Path) -> None:
    from Cython.Build import cythonize
    from setuptools import Distribution, Extension

    compiler = (os.environ.get("CC") or sysconfig.get_config_var("CC") or "cc").split()[0]
    if shutil.which(compiler) is None:
        raise UserError(
            f"the compiled core needs the C compiler {compiler}, which is not on "
            "PATH (Debian: apt-get install gcc; or set CC)"
        )

    sources = [f"{name}.pyx", "model.c", "dynamics.c", "solvers.c", "diagnosis.c", "cosim.c", "chain.c"]
    extension = Extension(
        name,
        [str(work / s) for s in sources],
        include_dirs=[str(work)],
        define_macros=[("Py_LIMITED_API", LIMITED_API), ("CYTHON_LIMITED_API", "1")],
        py_limited_api=True,
        extra_compile_args=["-O2", "-g0"],
        extra_link_args=["-s"],
    )
    cwd = os.getcwd()
    os.chdir(work)
    try:
        modules = cythonize([extension], quiet=True, language_level=3)
        dist = Distribution({"ext_modules": modules, "script_name": "build", "verbose": 0})
        command = dist.get_command_obj("build_ext")
        command.build_lib = str(work)
        command.build_temp = str(work / "obj")
        command.ensure_finalized()
        command.run()
    finally:
        os.chdir(cwd)
    shutil.rmtree(work / "obj", ignore_errors=True)
    (work / f"{name}.c").unlink(missing_ok=True)  # Cython's output: large, regenerated from the .pyx


def load_core(scene: Scene, cache: Path | None = None):
    """The compiled core of a scene, built on first use."""
    return build_core(scene, cache).load()
