"""The FMU in a co-simulation engine that is not fmpy: ecospy (libecos)."""
import json
import subprocess
import sys

import numpy as np

from conical_pendulum.analysis.fmpy_runs import run_fmu

# Runs in its own process: ecospy needs libtbb loaded first, and pythonfmu 0.7's exit-time
# destructor can abort an interpreter that still has the FMU library mapped, so the
# script leaves with os._exit once its results are printed.
SCRIPT = r"""
import ctypes, json, os, sys
ctypes.CDLL(os.path.join(sys.prefix, "lib", "libtbb.so.12"), mode=ctypes.RTLD_GLOBAL)
from ecospy import EcosLib, EcosSimulation, EcosSimulationStructure

EcosLib.set_log_level("warn")
dt, steps = 1.0 / 60.0, 600
out = {"time": [], "alpha0": [], "bob2_x": [], "energy": []}
with EcosSimulationStructure() as structure:
    structure.add_model("p", os.path.abspath(sys.argv[1]))
    structure.add_parameter_set("start", {"p::l0": 5.0, "p::alpha0": 0.3})
    with EcosSimulation(structure=structure, step_size=dt) as sim:
        sim.init(parameter_set="start")
        for k in range(steps + 1):
            if k:
                sim.step()
            out["time"].append(sim.get_time())
            for name in ("alpha0", "bob2_x", "energy"):
                out[name].append(sim.get_real("p::" + name))
        sim.terminate()
print(json.dumps(out))
sys.stdout.flush()
os._exit(0)
"""


def test_seed_scenario_in_ecospy_matches_fmpy(seed_fmu):
    run = subprocess.run([sys.executable, "-c", SCRIPT, str(seed_fmu)], capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    ecos = json.loads(run.stdout.strip().splitlines()[-1])
    ours = run_fmu(seed_fmu, stop_time=10.0, output_interval=1 / 60,
                   start_values={"l0": 5.0, "alpha0": 0.3})
    assert len(ecos["time"]) == len(ours["time"]) == 601
    # ecos adds dt to its clock, fmpy multiplies: the communication points differ by ~1e-13 s
    np.testing.assert_allclose(ecos["time"], ours["time"], rtol=0, atol=1e-12)
    for name in ("alpha0", "bob2_x", "energy"):
        scale = np.abs(ours[name]).max()
        assert np.abs(np.array(ecos[name]) - ours[name]).max() <= 1e-11 * scale, name
    assert ecos["alpha0"][0] == 0.3
