"""Scene -> compiled core: derive, generate C, compile with Cython (abi3), cache by hash.

The core holds the scene's numerics and, behind the model contract (fmu_model.h), the
pendulum's model with its variable table (pendulum_model.c and the fmu_config.h of
builder.models.pendulum.core_config), which the pythonfmu slave runs on. The cache key covers the
scene's structure, what the variable table is made of (builder.models.pendulum.core_config_key: the
solver settings, its starts, and the variable groups) and the generator's own sources, so a
rebuild of the same scene only loads the cached extension.
"""

from __future__ import annotations

import hashlib
import importlib.machinery
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import UserError
from ..scene import Scene
from .core.cache import LIMITED_API, cache_root
from .fmi.contract import CSRC, CSRC_FILES
from .models.pendulum import CORE_SOURCES, DEFAULT_SETTINGS, MODEL_SOURCES, core_config, core_config_key

HERE = Path(__file__).parent  # builder/
CORE_CSRC = CSRC / "core"  # the model's numerics: the compiled core's C, and the native FMU's
MODEL_FILES = ("fmu_model.h", "variable_table.h", "variable_table.c", "pendulum_model.c")  # not in core/
# The model compiled again in complex arithmetic, which pendulum_model.c links to.
# directional.c (first derivatives by complex step) gives the implicit solver's exact
# Jacobians, which the pythonfmu slave's Radau and `auto` call on stiff scenes: it compiles
# at -O2 with the rest, as the native FMU compiles it. At -O0 (before issue 55) a Jacobian
# took 2.6 to 3.4 times as long (20 and 50 links); -O2 adds some 4 s to the seed's cold
# build and 0.5 s to a recursive chain's (benchmarks/stiff_long_chains.py's docs section:
# docs/performance.md#build-time-of-the-optimized-derivatives).
DERIVATIVE_SOURCES = ("directional.c",)
# second_directional.c (the outputs' second derivatives, fmi2GetRealOutputDerivatives of
# order 2) is linked but never called by the slave, whose FMU declares no output
# derivatives: -O0, which compiles it in a tenth of the time (0.5 s against 7 s for the
# seed; the native FMU, which calls it, compiles its own at -O2).
UNOPTIMIZED_SOURCES = ("second_directional.c",)
GENERATOR_SOURCES = [
    *(HERE / "core" / name for name in ("kane.py", "equations.py", "codegen.py", "cache.py")),
    HERE / "compiler.py",
    # the variable table's fmu_config.h (builder.models.pendulum.core_config)
    HERE / "models" / "pendulum.py",
    *(HERE / "fmi" / name for name in ("fmu_config.py", "variables.py")),
    HERE / "c_literals.py",
    *sorted((HERE / "templates").glob("*.in")),
    *sorted((HERE.parent / "scene").glob("*.py")),  # the variables' names
    HERE.parent / "runtime" / "rules.py",  # the statistics' slots (model.h), the value rules
    *sorted(CORE_CSRC.glob("*.[chp]*")),
    *(CSRC_FILES[name] for name in MODEL_FILES),
]


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


def build_core(scene: Scene, cache: Path | None = None, settings: dict | None = None) -> CoreBuild:
    """The scene's compiled core, built or found in the cache; settings: the solver settings'
    start values of the model it holds (builder.fmu.checked_settings; None: the defaults)."""
    settings = DEFAULT_SETTINGS if settings is None else settings
    key = scene.key(generator_version() + core_config_key(scene, settings))
    name = f"cp_core_{key[:16]}"
    directory = (cache or cache_root()) / name
    if (directory / "build.json").exists():
        return CoreBuild(scene, directory, name, cached=True)
    directory.parent.mkdir(parents=True, exist_ok=True)
    seconds = {}
    with tempfile.TemporaryDirectory(dir=directory.parent, prefix=f".{name}.") as tmp:
        work = Path(tmp)
        from .core.codegen import generate, generate_recursive  # sympy: build time only
        from .core.equations import derive

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
        files["fmu_config.h"] = core_config(scene, settings)
        for filename, text in files.items():
            (work / filename).write_text(text)

        start = time.perf_counter()
        for source in [*CORE_CSRC.glob("*.[ch]"), *(CSRC_FILES[name] for name in MODEL_FILES)]:
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

    unoptimized = [work / Path(source).with_suffix(".o") for source in UNOPTIMIZED_SOURCES]
    for source, target in zip(UNOPTIMIZED_SOURCES, unoptimized):
        command = [compiler, "-O0", "-g0", "-fPIC", "-I", str(work), "-c", str(work / source)]
        subprocess.run([*command, "-o", str(target)], check=True)
    sources = [f"{name}.pyx", *CORE_SOURCES, *MODEL_SOURCES, *DERIVATIVE_SOURCES]
    extension = Extension(
        name,
        [str(work / s) for s in sources],
        include_dirs=[str(work)],
        define_macros=[("Py_LIMITED_API", LIMITED_API), ("CYTHON_LIMITED_API", "1")],
        py_limited_api=True,
        extra_compile_args=["-O2", "-g0"],
        extra_objects=[str(path) for path in unoptimized],
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
