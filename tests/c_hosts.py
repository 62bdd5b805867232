"""The C hosts of tests/hosts by FMI version (fmi_host.c for FMI 2.0, fmi3_host.c for 3.0):
compiled for Linux or, cross-compiled, for Windows, and one command line for both, so that a
test body runs a native FMU of either version in a host that is not Python."""

import subprocess
from pathlib import Path

import numpy as np
from fmpy import read_model_description

from conical_pendulum.builder.packaging.native import fmi_headers

HOSTS = Path(__file__).parent / "hosts"
SOURCES = {2: HOSTS / "fmi_host.c", 3: HOSTS / "fmi3_host.c"}
# binaries/<folder> of a platform, as each standard names it
FOLDERS = {
    2: {"linux64": "linux64", "win64": "win64"},
    3: {"linux64": "x86_64-linux", "win64": "x86_64-windows", "aarch64-linux": "aarch64-linux"},
}
# the columns of a row the host prints for host_arguments, after time, by the FMI 2.0 names
OUTPUTS = {2: ["alpha0", "beta2", "bob2_x", "energy"], 3: ["alpha0", "alpha1", "alpha2", "energy"]}


def compile_host(fmi_version, compiler, output, *extra):
    subprocess.run(
        [
            compiler,
            "-std=c99",
            "-O1",
            "-Wall",
            "-Wextra",
            "-Werror",
            f"-I{fmi_headers()}",
            str(SOURCES[fmi_version]),
            "-o",
            str(output),
            *extra,
        ],
        check=True,
    )
    return output


def binary(fmi_version, folder, platform="linux64"):
    """The pendulum's library in an FMU extracted to `folder`."""
    suffix = ".dll" if platform == "win64" else ".so"
    return Path(folder) / "binaries" / FOLDERS[fmi_version][platform] / f"ConicalPendulum{suffix}"


def host_arguments(fmi_version, path, stop="10", cycles="1"):
    """The host's arguments after the library: steps of 1/60 s to `stop`, l0 = 8 m, and out
    the OUTPUTS (FMI 3.0: the array alpha, then energy)."""
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    head = [md.guid, stop, repr(1 / 60), cycles]
    if fmi_version == 3:  # l set whole: l0 = 8, the others their start
        lengths = ["8", *next(v.start for v in md.modelVariables if v.name == "l").split()[1:]]
        return [*head, f"{vr['alpha']}:3,{vr['energy']}", f"{vr['l']}={':'.join(lengths)}"]
    return [*head, ",".join(str(vr[name]) for name in OUTPUTS[2]), "--", f"{vr['l0']}=8"]


def rows_of(run):
    return np.array([[float(x) for x in line.split(",")] for line in run.stdout.split()])
