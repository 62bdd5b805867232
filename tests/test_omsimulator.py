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
from test_elastic_ropes import BOUNCING, G

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


# A load dropped with 0.5 m of slack onto an elastic rope (tests/test_elastic_ropes.py's BOUNCING)
DROP_SCRIPT = """
oms_setTempDirectory("./tmp")
oms_newModel("model")
oms_addSystem("model.root", oms_system_sc)
oms_addSubModel("model.root.drop", "{fmu}")
oms_setResultFile("model", "drop.csv")
oms_setStopTime("model", 0.4)
oms_setVariableStepSize("model.root", 1e-6, 1e-12, 1e-3)
oms_setTolerance("model.root", 1e-8)
oms_instantiate("model")
oms_setReal("model.root.drop.r0", 9.5)
oms_setReal("model.root.drop.alpha0", 0)
oms_setReal("model.root.drop.beta0", 0)
oms_initialize("model")
oms_simulate("model")
oms_terminate("model")
oms_delete("model")
"""


def test_omsimulator_locates_an_elastic_ropes_snap_from_its_event_indicator(omsimulator, built_fmu, tmp_path):
    """Its Model Exchange (the FMI 2.0 FMU, its CVode at 1e-8) finds the snap where the taut
    margin crosses 0: an event row at the closed form's sqrt(2 h / g) to its tolerance, the
    snap counted and the rope taut after it (until the load bounces off at 0.425 s)."""
    fmu = built_fmu(BOUNCING, backend="native", fmi_version=2)
    (tmp_path / "drop.lua").write_text(DROP_SCRIPT.format(fmu=fmu))
    run = subprocess.run(
        [str(omsimulator), "drop.lua"], cwd=tmp_path, capture_output=True, text=True, check=False, timeout=600
    )
    assert "error:" not in run.stdout + run.stderr, run.stdout + run.stderr
    rows = np.genfromtxt(tmp_path / "drop.csv", delimiter=",", names=True, deletechars="")

    def column(name):  # the CSV names it model.root.drop.<name>
        return rows[next(key for key in rows.dtype.names if key.endswith("." + name))]

    event = rows["time"][np.flatnonzero(column("taut_margin0") == 0.0)[0]]  # the state on the root
    assert abs(event - np.sqrt(2 * 0.5 / G)) < 1e-6
    assert column("snaps0")[-1] == 1 and column("taut0")[-1] == 1
