import subprocess
from pathlib import Path

import pytest

from conical_pendulum import Scene
from conical_pendulum.builder.fmu import build_fmu
from conical_pendulum.builder.native import fmi_headers


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("fmus")


@pytest.fixture(scope="session")
def seed_fmu(fmu_dir):
    """The seed scene's FMU, as `python build_fmu.py` builds it."""
    return build_fmu(Scene.uniform(3), fmu_dir / "ConicalPendulum.fmu").path


@pytest.fixture(scope="session")
def native_seed_fmu(fmu_dir):
    """The seed scene's native FMU (FMI glue in C), as `python build_fmu.py --native` builds it."""
    return build_fmu(Scene.uniform(3), fmu_dir / "ConicalPendulumNative.fmu", backend="native").path


@pytest.fixture(scope="session")
def chain_fmu(fmu_dir):
    """FMUs of other uniform chains, by number of links."""
    built = {}

    def get(n):
        if n not in built:
            built[n] = build_fmu(Scene.uniform(n), fmu_dir / f"Chain{n}.fmu").path
        return built[n]

    return get


@pytest.fixture(scope="session")
def coupled_fmu(fmu_dir):
    """The seed chain hanging from a moving support: a_pivot inputs, F_pivot outputs."""
    return build_fmu(Scene.uniform(3, coupling=True), fmu_dir / "Coupled.fmu").path


@pytest.fixture(scope="session")
def c_host(tmp_path_factory):
    """tests/hosts/fmi_host.c compiled: a host that is a plain C program."""
    program = tmp_path_factory.mktemp("c_host") / "fmi_host"
    source = Path(__file__).parent / "hosts" / "fmi_host.c"
    subprocess.run(
        [
            "cc",
            "-std=c99",
            "-O1",
            "-Wall",
            "-Werror",
            f"-I{fmi_headers()}",
            str(source),
            "-o",
            str(program),
            "-ldl",
        ],
        check=True,
    )
    return program
