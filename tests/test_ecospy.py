"""The FMU in a co-simulation engine that is not fmpy: ecospy (libecos)."""

import json
import subprocess
import sys

import numpy as np
import pytest

from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.demos.ecospy_run import check_job, cosimulate

RECORD = ("alpha0", "bob2_x", "energy")


@pytest.mark.tools
def test_seed_scenario_in_ecospy_matches_fmpy(seed_fmu):
    # demos/ecospy_run.py runs in its own process: ecospy needs libtbb loaded first, and
    # pythonfmu 0.7's exit-time destructor can abort an interpreter that still has the FMU
    # library mapped, so it leaves with os._exit once its results are printed.
    runs = cosimulate(
        {
            "models": {"p": str(seed_fmu)},
            "parameters": {"p::l0": 5.0, "p::alpha0": 0.3},
            "steps": [1.0 / 60.0],
            "stop_time": 10.0,
            "record": [f"p::{n}" for n in RECORD],
        },
        timeout=300,
    )
    assert [run["step"] for run in runs] == [1.0 / 60.0]
    ecos = {name.removeprefix("p::"): values for name, values in runs[0]["values"].items()}
    ours = run_fmu(seed_fmu, stop_time=10.0, output_interval=1 / 60, start_values={"l0": 5.0, "alpha0": 0.3})
    assert len(ecos["time"]) == len(ours["time"]) == 601
    # ecos adds dt to its clock, fmpy multiplies: the communication points differ by ~1e-13 s
    np.testing.assert_allclose(ecos["time"], ours["time"], rtol=0, atol=1e-12)
    for name in RECORD:
        scale = np.abs(ours[name]).max()
        assert np.abs(np.array(ecos[name]) - ours[name]).max() <= 1e-11 * scale, name
    assert ecos["alpha0"][0] == 0.3


@pytest.mark.parametrize(
    "job, message",
    [
        ({"models": {}, "steps": [0.1], "stop_time": 1, "record": []}, "models must name at least one FMU"),
        ({"models": {"p": "P.fmu"}, "steps": [0.1], "record": []}, "missing stop_time"),
        (
            {"models": {"p": "P.fmu"}, "steps": [0], "stop_time": 1, "record": []},
            "steps must be a list of positive",
        ),
        (
            {"models": {"p": "P.fmu"}, "steps": [0.1], "stop_time": 1, "record": [], "warmup": True},
            "unknown key(s) warmup",
        ),
        (
            {
                "models": {"p": "P.fmu"},
                "steps": [0.1],
                "stop_time": 1,
                "record": ["p::x"],
                "limits": {"p::y": 1.0},
            },
            "limits must map recorded variables to positive numbers, got {'p::y': 1.0}",
        ),
    ],
)
def test_bad_jobs_are_refused(job, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        check_job(job)
    run = subprocess.run(
        [sys.executable, "-m", "conical_pendulum.demos.ecospy_run", json.dumps(job)],
        check=False,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 2
    assert message in run.stderr and "Traceback" not in run.stderr
