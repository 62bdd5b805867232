"""The pythonfmu FMU never takes its host down at exit, whatever it refused.

pythonfmu 0.7.0's prebuilt export library released its interpreter state twice in a
process that exits with the library still loaded (fmpy keeps it loaded after a failed
call; a C host's dlclose could not unload it), and an instance's objects twice after
fmi2Fatal: hosts died at exit with a corrupted heap. The FMU now carries that library
built from pythonfmu's sources with both fixed (builder/packaging/pythonfmu_export.py,
docs/pythonfmu.md). These tests run hosts as they failed: many processes refusing values
of every kind, a few of them under valgrind, and a C host with libpython preloaded.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import sysconfig
import zipfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from fmpy import read_model_description

from refusing_host import REFUSALS
from required_tools import require_tool

HOST = Path(__file__).with_name("refusing_host.py")
PROCESSES = 40
INVALID = re.compile(r"^==\d+== (Invalid (read|write|free)|Mismatched free)", re.M)


def refusing(fmu: Path, kinds: list[str], folder: Path, prefix: tuple[str, ...] = (), env=None, timeout=300):
    """The host run on fmu; what fmpy extracts for each refused run stays in folder (its TMPDIR:
    fmpy removes its extraction only after a run that completes)."""
    return subprocess.run(
        [*prefix, sys.executable, str(HOST), str(fmu), *kinds],
        check=False,
        capture_output=True,
        text=True,
        env={**(env or os.environ), "TMPDIR": str(folder)},
        timeout=timeout,
    )


def how_it_ended(run: subprocess.CompletedProcess) -> str:
    if run.returncode < 0:
        return f"killed by {signal.Signals(-run.returncode).name}: {run.stderr[-800:]}"
    return f"exit status {run.returncode}: {run.stderr[-800:]}"


def test_forty_processes_refusing_every_kind_exit_normally(seed_fmu, tmp_path):
    """Each process has the FMU refuse each kind of value twice (in an order of its own)
    and then returns from its script: every one prints its last line and exits 0."""
    kinds = list(REFUSALS) * 2

    def one(k: int):
        return refusing(seed_fmu, kinds[k % len(kinds) :] + kinds[: k % len(kinds)], tmp_path)

    with ThreadPoolExecutor(4) as pool:
        runs = list(pool.map(one, range(PROCESSES)))
    failed = [how_it_ended(run) for run in runs if run.returncode != 0]
    assert failed == [], f"{len(failed)} of {PROCESSES} processes: {failed[0]}"
    assert {run.stdout for run in runs} == {f"refused {len(kinds)}\n"}


def invalid_accesses(valgrind_log: str) -> list[str]:
    """valgrind's invalid reads, writes and frees, each with its stack; but ld.so's own
    (is_dst: strncmp reading whole words past an rpath string while it loads a library)."""
    blocks = re.split(r"^==\d+== *$", valgrind_log, flags=re.M)  # an error, then a blank line
    return [block.strip() for block in blocks if INVALID.search(block) and "is_dst" not in block]


@pytest.mark.tools
@pytest.mark.slow
@pytest.mark.parametrize("kinds", [["nan", "state", "negative_length"], ["bad_setting", "inf", "nan"]])
def test_under_valgrind_no_invalid_access_at_exit(seed_fmu, kinds, tmp_path):
    """Before the fix: one invalid read in pythonfmu's finalizePythonInterpreter at exit
    for every copy of the library fmpy had loaded, of a block the exit handlers had freed."""
    require_tool("valgrind", None, "Debian's valgrind (.ci/run installs it)")
    run = refusing(
        seed_fmu,
        kinds,
        tmp_path,
        prefix=("valgrind", "--quiet"),
        env={**os.environ, "PYTHONMALLOC": "malloc"},
        timeout=1800,
    )
    assert run.returncode == 0, how_it_ended(run)
    assert run.stdout == f"refused {len(kinds)}\n"
    assert invalid_accesses(run.stderr) == []


@pytest.mark.parametrize("start", [{}, {"l0": "-1"}, {"g": "nan"}], ids=["runs", "negative_length", "nan"])
def test_a_c_host_with_libpython_preloaded_exits_normally(seed_fmu, c_host, tmp_path, start):
    """A host that is no Python process (the FMU Compliance Checker's case): libpython
    preloaded, the FMU's slave finding numpy on PYTHONPATH. The prebuilt library aborted
    every such process at exit, a good run included (SIGABRT in 40 of 40)."""
    libdir, library = sysconfig.get_config_var("LIBDIR"), sysconfig.get_config_var("LDLIBRARY")
    libpython = Path(libdir) / library
    if not libpython.exists() or not library.endswith(".so"):
        pytest.skip(f"this Python has no shared libpython ({libpython})")
    md = read_model_description(str(seed_fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    with zipfile.ZipFile(seed_fmu) as archive:
        archive.extractall(tmp_path)
    site_packages = [p for p in sys.path if p.endswith("site-packages")]
    env = {
        "LD_PRELOAD": str(libpython),
        "PYTHONPATH": os.pathsep.join(site_packages),
        "FMI_RESOURCE_LOCATION": (tmp_path / "resources").as_uri(),
    }
    for _ in range(5):
        run = subprocess.run(
            [
                str(c_host(2)),
                str(tmp_path / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"),
                md.guid,
                "0.1",
                "0.05",
                "1",
                "0",
                *(["--", *(f"{vr[name]}={value}" for name, value in start.items())] if start else []),
            ],
            check=False,
            capture_output=True,
            text=True,
            env=env,
            timeout=300,
        )
        assert run.returncode == (1 if start else 0), how_it_ended(run)
        if start:
            assert "failed: SetReal" in run.stderr
        else:
            assert run.stdout.splitlines()[-1].startswith("0.1")
