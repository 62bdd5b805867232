"""Session fixtures: every FMU the tests run, built once and kept across runs.

built_fmu(scene, backend=..., fmi_version=..., settings=..., platforms=...) and
built_cart(fmi_version) are the one place the tests ask the builder for an FMU. An FMU is
cached under a hash of everything it is built from (the test's key: scene, settings,
backend, platforms, FMI version; and the build's inputs: every file of the installed
package, the Python packages and compilers the build uses), in the project's cache root
(builder.compiler.cache_root(), beside the compiled cores), and built under a file lock by
whichever pytest process asks first; `pytest --fresh-fmus` builds them anew in the run's
own temporary folder instead. Tests of the builder itself (what it refuses, rebuilding in
place, the command line) call it directly.
"""

import fcntl
import functools
import hashlib
import json
import multiprocessing.process
import os
import platform
import shlex
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from collections import Counter
from importlib.metadata import version
from pathlib import Path

import pytest

import conical_pendulum
from conical_pendulum import Link, Scene
from conical_pendulum.builder.core.cache import cache_root
from conical_pendulum.builder.fmu import build_fmu
from conical_pendulum.builder.models.cart import build_cart
from conical_pendulum.builder.packaging.native import COMPILERS

SEED = Scene.uniform(3)
COUPLED = Scene.uniform(3, coupling=True)
# a rope (its length a state, its winch's speed an input) with a forced hook and a link below,
# on a moving support: the tension and W_hoist need the accelerations
HOISTED_LINKS = (
    Link(has_mass=False, rope=True, rope_min=1.0, rope_max=30.0, bob_force=True),
    Link(length=3.0),
)
RUN_RECORD = "fmu-cache"  # under the run's base temporary folder, the workers' shared parent
KEPT = "test-fmus"  # under the cache root: the FMUs kept across runs
KEPT_DAYS = 14  # an FMU no run has used for this long is deleted at the start of a run
# what goes into an FMU besides the package's own files: the Python packages the build runs
BUILD_PACKAGES = ("pythonfmu", "fmpy", "cython", "numpy", "sympy", "setuptools")


def pytest_addoption(parser):
    parser.addoption(
        "--fresh-fmus",
        action="store_true",
        help="build every FMU the tests run anew, in this run's temporary folder (not the kept cache)",
    )


def run_folder(config) -> Path:
    """The run's base temporary folder: under xdist each worker's is a subfolder of it."""
    base = config._tmp_path_factory.getbasetemp()
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


@functools.cache
def package_digest() -> str:
    """Every file of the installed package: generator, runtime, C, templates, export sources."""
    root = Path(conical_pendulum.__file__).parent
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts:
            digest.update(str(path.relative_to(root)).encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


@functools.cache
def compiler_version(command: str) -> str:
    """What `command --version` prints (the compiler's identity in a cache key), or "absent"."""
    words = shlex.split(command)
    if not words or shutil.which(words[0]) is None:
        return "absent"
    try:
        run = subprocess.run([*words, "--version"], check=False, capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return "absent"
    return run.stdout.strip()


def build_inputs(backend: str, platforms) -> dict:
    """What an FMU is built from besides the test's key: the package's files, the Python and
    packages that build it, and each compiler it runs (the core's, the native binaries' for
    `platforms`, pythonfmu's export library's C++ compiler)."""
    compilers = [os.environ.get("CC") or sysconfig.get_config_var("CC") or "cc"]  # the core
    compilers += [" ".join(COMPILERS[p][0][:1]) for p in platforms if p in COMPILERS]
    if backend == "pythonfmu":
        compilers.append(os.environ.get("CXX") or sysconfig.get_config_var("CXX") or "c++")
    return {
        "package": package_digest(),
        "python": sys.version,
        "machine": platform.machine(),
        "packages": {name: version(name) for name in BUILD_PACKAGES},
        "compilers": {command: compiler_version(command) for command in compilers},
    }


def cached(folders: dict, key: dict, name: str, build):
    """The file `name` that build(path) made for `key` (with its build_inputs), made once in
    all processes that share the cache (flock); the run records which it built and reused."""
    digest = hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:16]
    entry = folders["store"] / digest
    entry.mkdir(parents=True, exist_ok=True)
    path = entry / name
    with open(entry / "lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        made = not path.exists()
        if made:  # the builder moves an FMU into place only when it is complete
            build(path)
            (entry / "key.json").write_text(json.dumps(key, indent=1, sort_keys=True))
        (entry / "used").touch()
    folders["record"].mkdir(parents=True, exist_ok=True)
    record = folders["record"] / digest
    if made or not record.exists():  # a later use does not hide that this run built it
        record.write_text(json.dumps({"kind": key["kind"], "built": made}))
    return path


def store(config) -> Path:
    """Where the FMUs are kept: the cache root's, or with --fresh-fmus the run's own folder."""
    if config.getoption("--fresh-fmus"):
        return run_folder(config) / RUN_RECORD
    return cache_root() / KEPT


@pytest.fixture(scope="session")
def fmu_folders(pytestconfig):
    """Where this run keeps its FMUs, and where it records which it used (fixed at its start,
    before any test changes the cache root's environment variable)."""
    return {"store": store(pytestconfig), "record": run_folder(pytestconfig) / RUN_RECORD / "used"}


def prune_kept(now: float) -> None:
    """Delete the kept FMUs no run has used for KEPT_DAYS (each source edit makes new keys)."""
    for entry in (cache_root() / KEPT).glob("*"):
        used = entry / "used"
        if used.exists() and now - used.stat().st_mtime < KEPT_DAYS * 86400:
            continue
        with open(entry / "lock", "w") as lock:
            try:
                fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                continue  # another run is building or reading it
            shutil.rmtree(entry, ignore_errors=True)


def pytest_sessionstart(session):
    if not os.environ.get("PYTEST_XDIST_WORKER") and not session.config.getoption("--fresh-fmus"):
        prune_kept(time.time())


@pytest.fixture(scope="session", autouse=True)
def temporary_folder(tmp_path_factory):
    """This process's TMPDIR (its programs' too), inside pytest's own folder: what a test's
    tools leave in it is seen by leaves_no_temporary_files, whichever test made it."""
    folder = tmp_path_factory.mktemp("tmpdir")
    before = os.environ.get("TMPDIR")
    os.environ["TMPDIR"] = tempfile.tempdir = str(folder)
    # the process's own multiprocessing folder (a local sweep cluster's fork server keeps its
    # socket there), made now, inside pytest's folder, and given to multiprocessing as its own
    # (its config's tempdir): get_temp_dir() would register its removal at exit, which fails
    # once pytest has removed its folder of a passing run, and an xdist worker skips it
    sockets = tmp_path_factory.mktemp("multiprocessing")
    multiprocessing.process.current_process()._config["tempdir"] = str(sockets)
    yield folder
    multiprocessing.process.current_process()._config["tempdir"] = None
    tempfile.tempdir = None
    if before is None:
        del os.environ["TMPDIR"]
    else:
        os.environ["TMPDIR"] = before


@pytest.fixture(scope="module", autouse=True)
def leaves_no_temporary_files(temporary_folder):
    """Nothing a test file (its FMU runs, fmpy's extractions, the programs it starts, its
    fixtures once closed) leaves in TMPDIR: fmpy leaves its extracted FMU there whenever a run
    raises, unless the run takes a folder it removes (analysis.fmpy_runs.simulate_fmu). Checked
    after the file's last test, as its module fixtures may keep an instance across tests; the
    leftovers are removed, and named."""
    before = set(os.listdir(temporary_folder))
    yield
    left = sorted(set(os.listdir(temporary_folder)) - before)
    for name in left:
        path = temporary_folder / name
        shutil.rmtree(path) if path.is_dir() and not path.is_symlink() else path.unlink()
    assert left == [], f"the test file left {len(left)} entries in TMPDIR: {left[:5]}"


@pytest.fixture(scope="session")
def built_fmu(fmu_folders):
    """A scene's FMU, built once and kept: the pythonfmu FMU by default, or backend="native"
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
            "fmi_version": fmi_version,
            "backend": backend,
            "arrays": arrays,
            "built_from": build_inputs(backend, platforms),
        }
        return cached(
            fmu_folders,
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
def built_cart(fmu_folders):
    """The coupled demo's cart FMU (builder.models.cart), FMI 2.0 or 3.0, built once and kept."""
    return lambda fmi_version=2: cached(
        fmu_folders,
        {"kind": f"cart FMI {fmi_version}.0", "built_from": build_inputs("native", ("linux64",))},
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
    """One line: the FMUs the run's tests used, by kind, and how many of them it built."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        return
    records = [json.loads(p.read_text()) for p in (run_folder(config) / RUN_RECORD / "used").glob("*")]
    if records:
        kinds = Counter(record["kind"] for record in records)
        built = sum(record["built"] for record in records)
        where = store(config)
        terminalreporter.write_line(
            f"FMUs the tests ran: {len(records)} ({', '.join(f'{n} {k}' for k, n in sorted(kinds.items()))}); "
            f"built by this run: {built}, kept from an earlier run: {len(records) - built}; in {where}"
        )
