"""A native FMU packed: any model behind fmu_model.h (a NativeModel) with the FMI glue in C,
compiled for each platform, no Python at run time.

One FMU with both interfaces: Co-Simulation (the model's own step) and Model Exchange (the
host integrates the derivatives). The binary links only libc and libm; the C sources ship in
`sources/`, so a host can compile it for its platform. The FMI version is a value: its
Standard (builder.fmi.fmi2.FMI2, builder.fmi.fmi3.FMI3) writes the model description and whatever
else that version's FMU holds, and this module compiles and packs what it says. The models:
the pendulum's (builder.models.pendulum), the coupled demo's cart (builder.models.cart).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import uuid
import zipfile
from pathlib import Path

from ...errors import UserError
from ...runtime.files import MODEL_FILE
from ..fmi.contract import CSRC_FILES, Description, NativeModel
from ..fmi.fmi2 import FMI2
from ..fmi.fmi3 import FMI3
from ..fmi.fmu_config import config_header
from ..fmi.variables import records

# The C files of the FMI layers, which serve every model behind fmu_model.h.
LAYER_SOURCES = {2: ("fmi_layer.c", "fmi2_glue.c"), 3: ("fmi_layer.c", "fmi3_glue.c")}
LAYER_HEADERS = ("fmu_model.h", "fmi_layer.h", "fmu_config.h")
STANDARDS = {standard.version: standard for standard in (FMI2, FMI3)}


def glue_sources(model: NativeModel, fmi_version: int = 2) -> list[str]:
    """The C sources of a model's native FMU of an FMI version: the model's, then its FMI
    layer's."""
    if fmi_version not in model.fmi_versions:
        raise ValueError(f"fmi_version: {fmi_version!r} is not one of {model.fmi_versions} ({model.name})")
    return [*model.sources, *LAYER_SOURCES[fmi_version]]


def glue_headers(model: NativeModel) -> list[str]:
    """The C headers a native FMU ships: the model's, then its FMI layer's."""
    return [*model.headers, *LAYER_HEADERS]


def fmi_headers() -> Path:
    """The FMI 2.0 and 3.0 headers, from the installed fmpy (its c-code folder)."""
    import fmpy

    return Path(fmpy.__file__).parent / "c-code"


# How each platform's binary is compiled from the FMU's sources: Linux x86-64 natively,
# Windows and Linux on 64-bit ARM cross-compiled with Debian's compilers (CROSS_PACKAGES).
_LINUX = (".so", ["-lm", "-Wl,-z,defs"])
COMPILERS = {
    "linux64": (["cc", "-fPIC", "-fvisibility=hidden"], *_LINUX),
    "win64": (["x86_64-w64-mingw32-gcc"], ".dll", ["-static-libgcc"]),
    "aarch64-linux": (["aarch64-linux-gnu-gcc", "-fPIC", "-fvisibility=hidden"], *_LINUX),
}
CROSS_PACKAGES = {"win64": "gcc-mingw-w64-x86-64", "aarch64-linux": "gcc-aarch64-linux-gnu"}


def compile_binary(
    model: NativeModel, sources: Path, folder: Path, platform: str = "linux64", fmi_version: int = 2
) -> Path:
    """The platform's shared library of a model's FMU from the FMU's own sources, exporting
    only the FMI functions: on Linux it needs libc and libm only, on Windows kernel32 and
    msvcrt."""
    if platform not in COMPILERS:
        raise ValueError(f"platform: {platform!r} is not one of {sorted(COMPILERS)}")
    compiler, suffix, libraries = COMPILERS[platform]
    library = folder / f"{model.name}{suffix}"
    command = [
        *compiler,
        "-std=c99",
        "-O2",
        "-shared",
        "-Wall",
        "-Wextra",
        "-Werror",
        f"-I{sources}",
        f"-I{fmi_headers()}",
        *(str(sources / name) for name in glue_sources(model, fmi_version)),
        "-o",
        str(library),
        *libraries,
        "-s",
    ]
    if shutil.which(compiler[0]) is None:
        raise UserError(
            f"the {platform} binary needs the compiler {compiler[0]}"
            + (f" (Debian: apt-get install {CROSS_PACKAGES[platform]})" if platform in CROSS_PACKAGES else "")
        )
    run = subprocess.run(command, check=False, capture_output=True, text=True)
    if run.returncode:
        raise RuntimeError(f"compiling the native FMU failed:\n{' '.join(command)}\n{run.stderr}")
    return library


# What writes a native FMU, besides its standard's module: a change here is a new GUID.
WRITERS = (
    Path(__file__),
    *(Path(__file__).parents[1] / name for name in ("fmi/fmu_config.py", "c_literals.py", "fmi/contract.py")),
    *sorted((Path(__file__).parents[1] / "templates").glob("*.in")),
)


def guid_of(model: NativeModel, data: dict, fmi_version: int = 2) -> str:
    """A GUID that changes with anything the model description or binary says: the
    variables and start values, for the pendulum the core's build (the scene's cache fields
    and generator) and the settings, every C file it ships from runtime/csrc, and the code
    that writes it (WRITERS, its standard's module and its model's)."""
    files = glue_sources(model, fmi_version) + glue_headers(model)
    shipped = [CSRC_FILES[name] for name in files if name in CSRC_FILES]
    modules = (STANDARDS[fmi_version].model_description.__module__, model.config.__module__)
    writers = [*WRITERS, *(Path(sys.modules[name].__file__) for name in modules)]
    glue = b"".join(path.read_bytes() for path in shipped + writers)
    text = json.dumps(data, sort_keys=True) + glue.hex()
    return "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, text)) + "}"


def write_model_fmu(
    model: NativeModel,
    data: dict,
    output: Path,
    platforms: tuple[str, ...] = ("linux64",),
    fmi_version: int = 2,
    generated: dict[str, Path] | None = None,
) -> None:
    """The native FMU of a model behind fmu_model.h at `output` (moved into place only when
    complete): its sources (from runtime/csrc, or `generated` by name), fmu_config.h and what
    its FMI version's Standard writes (the model description; FMI 3.0: fmi3_arrays.h and
    buildDescription.xml) from data's variables, a binary per platform, and model.json in its
    resources."""
    standard = STANDARDS[fmi_version]
    for platform in platforms:
        if platform not in standard.platform_folders:
            raise ValueError(
                f"platforms: FMI {fmi_version}.0 names no binaries folder for {platform!r} "
                f"(it has {', '.join(standard.platform_folders)}): docs/native.md#platforms"
            )
    shipped = glue_sources(model, fmi_version)
    described = Description(model, data, records(data), guid_of(model, data, fmi_version), shipped)
    output.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="conical_pendulum_native_") as tmp:
        sources = Path(tmp) / "sources"
        sources.mkdir()
        for name in shipped + glue_headers(model):
            if name != "fmu_config.h":
                shutil.copy2((generated or {}).get(name) or CSRC_FILES[name], sources / name)
        headers = {"fmu_config.h": config_header(model, data, described.records, described.guid)}
        for name, text in {**headers, **standard.headers(described)}.items():
            (sources / name).write_text(text)
        for name, content in standard.files(described).items():
            (sources / name).write_bytes(content)
        libraries = {}
        for platform in dict.fromkeys(platforms):
            (Path(tmp) / platform).mkdir()
            libraries[platform] = compile_binary(model, sources, Path(tmp) / platform, platform, fmi_version)
        staged = Path(tmp) / "staged.fmu"
        with zipfile.ZipFile(staged, "w", zipfile.ZIP_DEFLATED) as archive:
            archive.writestr("modelDescription.xml", standard.model_description(described))
            for platform, library in libraries.items():  # stored: hosts extract them at every run
                folder = standard.platform_folders[platform]
                archive.write(library, f"binaries/{folder}/{library.name}", compress_type=zipfile.ZIP_STORED)
            for path in sorted(sources.iterdir()):
                archive.write(path, f"sources/{path.name}")
            archive.writestr(f"resources/{MODEL_FILE}", json.dumps(data, indent=1))
        os.replace(staged, output)
