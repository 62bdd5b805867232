"""pythonfmu's export library, built here from its own sources with two fixes.

The pythonfmu FMU's binary (binaries/linux64/<model>.so) is pythonfmu 0.7.0's export
library: FMI 2.0 in C++ around the Python slave. Its wheel ships it prebuilt, with two
defects that corrupt a host's heap (docs/pythonfmu.md): the interpreter's state was
released twice by a process that exits with the library loaded (fmpy keeps it loaded
after any failed call), and an instance's objects twice after fmi2Fatal. The sources,
runtime/pythonfmu_export/ (pythonfmu's src/pythonfmu at 0.7.0, fixed where marked
"conical-pendulum"), are compiled once per source digest and cached beside the cores.

It exports the FMI functions only (and the finalizer pythonfmu's C++ names), so no C++
symbol of one FMU's copy binds another's and each copy unloads when its host frees it.
"""

from __future__ import annotations

import hashlib
import os
import shlex
import shutil
import subprocess
import sysconfig
import tempfile
from pathlib import Path

from ...errors import UserError
from ..core.cache import LIMITED_API, cache_root
from .native import fmi_headers

SOURCES = Path(__file__).parents[2] / "runtime" / "pythonfmu_export"
EXPORTS = "{ global: fmi2*; finalizePythonInterpreter; local: *; };\n"


def compiler() -> list[str]:
    """The C++ compiler: $CXX, or the one Python was built with, or c++."""
    return shlex.split(os.environ.get("CXX") or sysconfig.get_config_var("CXX") or "c++")


def command(library: Path, exports: Path) -> list[str]:
    return [
        *compiler(),
        "-std=c++17",
        "-O2",
        "-fPIC",
        "-shared",
        "-fvisibility=hidden",
        "-fno-gnu-unique",
        f"-DPy_LIMITED_API={LIMITED_API}",
        f"-I{SOURCES}",
        f"-I{sysconfig.get_paths()['include']}",
        f"-I{fmi_headers()}",
        *(str(path) for path in sorted((SOURCES / "pythonfmu").glob("*.cpp"))),
        f"-Wl,--version-script={exports}",
        "-o",
        str(library),
        "-s",
    ]


def export_library(cache: Path | None = None) -> Path:
    """The compiled export library, built on first use and cached by what it is made of
    (the sources, the compiler's command, Python's and fmpy's headers)."""
    digest = hashlib.sha256(" ".join(command(Path("out"), Path("map"))).encode() + EXPORTS.encode())
    for path in sorted(SOURCES.rglob("*")):
        if path.is_file():
            digest.update(path.name.encode() + path.read_bytes())
    directory = (cache or cache_root()) / f"pythonfmu_export_{digest.hexdigest()[:16]}"
    library = directory / "libpythonfmu-export.so"
    if library.exists():
        return library
    if shutil.which(compiler()[0]) is None:
        raise UserError(
            f"the pythonfmu FMU's export library needs the C++ compiler {compiler()[0]}, which is "
            "not on PATH (Debian: apt-get install g++; or set CXX), or build the native FMU (--native)"
        )
    directory.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=directory.parent, prefix=f".{directory.name}.") as tmp:
        work = Path(tmp)
        (work / "exports.map").write_text(EXPORTS)
        built = command(work / library.name, work / "exports.map")
        run = subprocess.run(built, check=False, capture_output=True, text=True)
        if run.returncode:
            raise RuntimeError(
                f"compiling pythonfmu's export library failed:\n{shlex.join(built)}\n{run.stderr}"
            )
        try:
            work.rename(directory)
        except OSError:
            if not library.exists():  # not a concurrent build of the same digest
                raise
    return library
