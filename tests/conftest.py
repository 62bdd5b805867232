"""Session fixtures: every FMU the tests run, built once per run of the suite.

built_fmu(scene, backend=..., fmi_version=..., settings=..., platforms=...) and
built_cart(fmi_version) are the one place the tests ask the builder for an FMU; an FMU is
cached under a hash of what it is built from, in a folder all of pytest-xdist's workers of
one run share, and built once under a file lock, whichever worker asks first. Tests of the
builder itself (what it refuses, rebuilding in place, the command line) call it directly.
"""

import fcntl
import hashlib
import json
import os
from collections import Counter

import pytest

from conical_pendulum import Scene
from conical_pendulum.builder.cart import build_cart
from conical_pendulum.builder.fmu import build_fmu

SEED = Scene.uniform(3)
COUPLED = Scene.uniform(3, coupling=True)
CACHE = "fmu-cache"  # under the run's base temporary folder, the workers' shared parent


def cache_folder(tmp_path_factory):
    """The run's base temporary folder: under xdist each worker's is a subfolder of it."""
    base = tmp_path_factory.getbasetemp()
    return (base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / CACHE


def cached(folder, key: dict, name: str, build):
    """The file `name` that build(path) made for `key`, made once in all workers (flock)."""
    digest = hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:16]
    entry = folder / digest
    entry.mkdir(parents=True, exist_ok=True)
    path = entry / name
    with open(entry / "lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not path.exists():  # the builder moves an FMU into place only when it is complete
            build(path)
            (entry / "kind").write_text(key["kind"])
    return path


@pytest.fixture(scope="session")
def fmu_cache(tmp_path_factory):
    return cache_folder(tmp_path_factory)


@pytest.fixture(scope="session")
def built_fmu(fmu_cache):
    """A scene's FMU, built once per run: the pythonfmu FMU by default, or backend="native"
    (fmi_version 2 or 3, platforms "linux64", "win64" and "aarch64"; FMI 3.0 with arrays or,
    arrays=False, scalars), with solver settings changed."""

    def get(
        scene=SEED, backend="pythonfmu", fmi_version=2, settings=None, platforms=("linux64",), arrays=True
    ):
        key = {
            "kind": f"{backend} FMI {fmi_version}.0"
            + "".join(f" +{p}" for p in platforms if p != "linux64")
            + " scalars" * (not arrays),
            "scene": scene.to_dict(),
            "settings": settings or {},
            "platforms": list(platforms),
            **({} if arrays else {"arrays": False}),
        }
        return cached(
            fmu_cache,
            key,
            "ConicalPendulum.fmu",
            lambda path: build_fmu(
                scene,
                path,
                settings,
                backend=backend,
                platforms=platforms,
                fmi_version=fmi_version,
                arrays=arrays,
            ),
        )

    return get


@pytest.fixture(scope="session")
def built_cart(fmu_cache):
    """The coupled demo's cart FMU (builder.cart), FMI 2.0 or 3.0, built once per run."""
    return lambda fmi_version=2: cached(
        fmu_cache,
        {"kind": f"cart FMI {fmi_version}.0"},
        "Cart.fmu",
        lambda path: build_cart(path, fmi_version=fmi_version),
    )


@pytest.fixture(scope="session")
def c_host(tmp_path_factory):
    """tests/hosts' C host for an FMI version (2 or 3), compiled for Linux on first use."""
    from c_hosts import compile_host

    folder, made = tmp_path_factory.mktemp("c_hosts"), {}

    def get(fmi_version):
        if fmi_version not in made:
            made[fmi_version] = compile_host(fmi_version, "cc", folder / f"fmi{fmi_version}_host", "-ldl")
        return made[fmi_version]

    return get


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    """A folder for FMUs a test builds for what it checks of the builder."""
    return tmp_path_factory.mktemp("fmus")


@pytest.fixture(scope="session")
def seed_fmu(built_fmu):
    """The seed scene's FMU, as `python build_fmu.py` builds it."""
    return built_fmu(SEED)


@pytest.fixture(scope="session")
def native_seed_fmu(built_fmu):
    """The seed scene's native FMU (FMI glue in C), as `python build_fmu.py --native` builds it."""
    return built_fmu(SEED, backend="native")


@pytest.fixture(scope="session")
def chain_fmu(built_fmu):
    """FMUs of other uniform chains, by number of links."""
    return lambda n: built_fmu(Scene.uniform(n))


@pytest.fixture(scope="session")
def coupled_fmu(built_fmu):
    """The seed chain hanging from a moving support: a_pivot inputs, F_pivot outputs."""
    return built_fmu(COUPLED)


@pytest.fixture(scope="session")
def cart_fmu(built_cart):
    return built_cart(2)


@pytest.fixture(scope="session")
def cart_fmu3(built_cart):
    return built_cart(3)


def pytest_terminal_summary(terminalreporter, config):
    """One line: the FMUs the run built for its tests, by kind (each once)."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        return
    folder = config._tmp_path_factory.getbasetemp() / CACHE
    kinds = Counter(kind.read_text() for kind in folder.glob("*/kind"))
    if kinds:
        built = ", ".join(f"{count} {kind}" for kind, count in sorted(kinds.items()))
        terminalreporter.write_line(f"FMUs built for the tests, once each: {sum(kinds.values())} ({built})")
