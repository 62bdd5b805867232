"""The FMU built here runs under fmpy in other CPython minor versions (abi3 core)."""

import glob
import json
import os
import subprocess
import sys

import pytest

from conical_pendulum.analysis.fmpy_runs import run_fmu

OTHER_PYTHONS = {
    v: sorted(glob.glob(os.path.expanduser(f"~/.pyenv/versions/{v}.*/bin/python"))) for v in ("3.12", "3.13")
}
SCRIPT = """
import json, sys, fmpy
r = fmpy.simulate_fmu(sys.argv[1], stop_time=2.0, output_interval=0.1, start_values={"l1": 7.0})
print(json.dumps({name: float(r[name][-1]) for name in r.dtype.names}))
"""


@pytest.mark.slow
@pytest.mark.parametrize("version", sorted(OTHER_PYTHONS))
def test_runs_under_another_python(version, seed_fmu, tmp_path):
    if not OTHER_PYTHONS[version]:
        pytest.skip(f"no Python {version} under ~/.pyenv on this machine")
    if sys.version_info[:2] == tuple(map(int, version.split("."))):
        pytest.skip("that is the Python running the tests")
    venv = tmp_path / "venv"
    subprocess.run([OTHER_PYTHONS[version][-1], "-m", "venv", str(venv)], check=True)
    python = str(venv / "bin" / "python")
    subprocess.run([python, "-m", "pip", "install", "-q", "fmpy", "numpy"], check=True)
    out = subprocess.run(
        [python, "-c", SCRIPT, str(seed_fmu)], check=True, capture_output=True, text=True
    ).stdout
    theirs = json.loads(out.strip().splitlines()[-1])
    ours = run_fmu(seed_fmu, stop_time=2.0, output_interval=0.1, start_values={"l1": 7.0})
    assert set(theirs) == set(ours.dtype.names)
    for name, value in theirs.items():
        assert value == ours[name][-1], name  # same compiled core: the same numbers
