"""The native FMI 3.0 FMU in OpenModelica's OMSimulator (Co-Simulation; this version has no
FMI 3.0 Model Exchange): it reads no arrays, so the FMU built with scalars (build_fmu(...,
arrays=False), `build --native --fmi 3 --scalars`) is the one it runs. The SSP package in
OMSimulator: tests/test_ssp.py."""

import subprocess

import numpy as np
import pytest

from conftest import SEED
from conical_pendulum.analysis.fmpy_runs import simulate_fmu
from required_tools import require_omsimulator

STOP, STEP = "10", "0.01"
COMPARED = ["alpha0", "beta2", "omega1", "bob2_x", "energy"]


@pytest.fixture(scope="module")
def omsimulator():
    return require_omsimulator()


def simulate(omsimulator, fmu, folder):
    """OMSimulator's Co-Simulation run of an FMU: what it printed and its CSV's rows (the last
    of the two it writes at each communication point), or None without a result."""
    run = subprocess.run(
        [str(omsimulator), str(fmu), "--mode=cs", f"--stopTime={STOP}", f"--stepSize={STEP}"]
        + [f"--tempDir={folder}", "--resultFile=result.csv"],
        cwd=folder,
        capture_output=True,
        text=True,
        check=False,
        timeout=600,
    )
    assert run.returncode == 0  # whether or not the run failed: its messages say
    result = folder / "result.csv"
    if not result.exists():
        return run.stdout + run.stderr, None
    table = np.genfromtxt(result, delimiter=",", names=True, deletechars="", ndmin=1)
    if table.size == 0:
        return run.stdout + run.stderr, table
    last = np.append(table["time"][1:] != table["time"][:-1], True)
    return run.stdout + run.stderr, table[last]


def test_omsimulator_reads_each_fmi3_array_as_one_value(omsimulator, built_fmu, tmp_path):
    """The limit, with the arrays: it declares no Dimension support (its sources never read
    one), asks for one value per value reference, and the FMU refuses every such call; it
    records nothing and exits 0."""
    printed, rows = simulate(omsimulator, built_fmu(SEED, backend="native", fmi_version=3), tmp_path)
    assert "fmi3GetFloat64: nValues = 1, but the 1 value references have 3 values" in printed
    assert rows is not None and len(rows) == 0  # the CSV's header only


def test_the_fmi3_fmu_with_scalars_runs_in_omsimulator(omsimulator, built_fmu, native_seed_fmu, tmp_path):
    """With scalars it runs clean and equals the FMI 2.0 native FMU in fmpy (which the FMI 3.0
    FMU equals bit for bit) to the 12 significant digits of OMSimulator's CSV."""
    printed, rows = simulate(
        omsimulator, built_fmu(SEED, backend="native", fmi_version=3, arrays=False), tmp_path
    )
    assert "error:" not in printed and "warning:" not in printed, printed
    # OMSimulator enters initialization with no stop time defined, so the solver's last step may
    # pass 10 s (and points inside it are answered by its dense output): fmpy is asked the same
    reference = simulate_fmu(
        str(native_seed_fmu),
        stop_time=float(STOP),
        output_interval=float(STEP),
        output=COMPARED,
        set_stop_time=False,
    )
    np.testing.assert_allclose(rows["time"], reference["time"], rtol=0, atol=1e-12)
    for name in COMPARED:
        scale = np.abs(reference[name]).max()
        np.testing.assert_allclose(rows[name], reference[name], rtol=0, atol=1e-11 * scale, err_msg=name)
