"""The FMU as fmpy users meet it: conformant, equal to the native integrator, robust."""

import gc
import math
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from conical_pendulum import Link, Scene
from conical_pendulum.analysis.compare import compare
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.builder.fmu import build_fmu
from fmu_helpers import BAD_VALUES, Instance


def model_description(path):
    with zipfile.ZipFile(path) as archive:
        return ET.fromstring(archive.read("modelDescription.xml"))


def test_fmpy_validates_it(seed_fmu):
    assert validate_fmu(str(seed_fmu)) == []


def test_variables_are_the_contract(seed_fmu):
    root = model_description(seed_fmu)
    variables = {v.get("name"): v for v in root.iter("ScalarVariable")}
    scene = Scene.uniform(3)
    for name, start in zip(scene.parameter_names(), scene.parameter_defaults()):
        v = variables[name]
        assert (v.get("causality"), v.get("variability")) == ("parameter", "fixed")
        assert float(v.find("Real").get("start")) == start
    assert float(variables["Ixx0"].find("Real").get("start")) == pytest.approx(10 * (3 * 0.25 + 100) / 12)
    assert float(variables["Iyy0"].find("Real").get("start")) == pytest.approx(10 * 0.25)
    for name in scene.state_names():
        v = variables[name]
        assert (v.get("causality"), v.get("initial")) == ("output", "exact")
        expected = math.radians(10) if name[0] in "ab" else 0.0
        assert float(v.find("Real").get("start")) == expected
    for name in ["bob0_x", "bob2_z", "link1_qw", "link2_y", "energy"]:
        assert (variables[name].get("causality"), variables[name].get("initial")) == ("output", "calculated")
    for name in ["solver", "rtol", "atol", "max_step", "max_steps"]:
        assert variables[name].get("causality") == "parameter"
    cs = root.find("CoSimulation")
    for flag in ["canHandleVariableCommunicationStepSize", "canGetAndSetFMUstate", "canSerializeFMUstate"]:
        assert cs.get(flag) == "true"
    index = {v.get("name"): str(i) for i, v in enumerate(root.iter("ScalarVariable"), start=1)}
    initial = {u.get("index") for u in root.find("ModelStructure/InitialUnknowns")}
    assert index["energy"] in initial and index["bob1_y"] in initial and index["alpha0"] not in initial


def test_only_this_platform_is_shipped(seed_fmu):
    with zipfile.ZipFile(seed_fmu) as archive:
        binaries = {n.split("/")[1] for n in archive.namelist() if n.startswith("binaries/")}
    assert binaries == {"linux64"}


def test_seed_scenario_matches_native(seed_fmu):
    comparison = compare(seed_fmu, Scene.uniform(3))
    assert comparison.angle_error() < 1e-8
    assert comparison.worst("bob") < 1e-7
    assert comparison.worst("energy") < 1e-6


@pytest.mark.parametrize("n", [1, 2, 4])
def test_other_chains_match_native(chain_fmu, n):
    start = {"alpha0": 0.5, f"beta{n - 1}": -0.3, f"delta{n - 1}": 0.2}
    comparison = compare(chain_fmu(n), Scene.uniform(n), stop_time=5.0, start_values=start)
    assert comparison.angle_error() < 1e-8


def test_parameters_and_start_values_reach_the_model(seed_fmu):
    start = {
        "l0": 4.0,
        "m1": 1.5,
        "M2": 3.0,
        "Iyy2": 0.1,
        "g": 3.7,
        "alpha1": -0.7,
        "beta2": 1.2,
        "omega0": 0.4,
    }
    comparison = compare(seed_fmu, Scene.uniform(3), start_values=start)
    assert comparison.angle_error() < 1e-8
    result = run_fmu(seed_fmu, stop_time=0.0, start_values=start)
    assert result["alpha1"][0] == -0.7
    assert result["bob0_y"][0] == pytest.approx(-4.0 * math.cos(math.radians(10)) ** 2)


def test_setup_experiment_tolerance_replaces_rtol(seed_fmu):
    loose = run_fmu(
        seed_fmu, stop_time=4.0, output_interval=2.0, relative_tolerance=1e-3, output=["rtol", "n_rhs"]
    )
    tight = run_fmu(
        seed_fmu, stop_time=4.0, output_interval=2.0, relative_tolerance=1e-11, output=["rtol", "n_rhs"]
    )
    assert loose["rtol"][-1] == 1e-3 and tight["rtol"][-1] == 1e-11
    assert loose["n_rhs"][-1] < tight["n_rhs"][-1]


def test_state_restores_bit_identically(seed_fmu):
    fmu = Instance(seed_fmu)
    names = Scene.uniform(3).state_names() + ["energy", "bob2_x"]
    for _ in range(7):
        fmu.step(0.1)
    saved, t_saved = fmu.fmu.getFMUstate(), fmu.time

    def steps_from_saved(instance, state=None):
        if state is not None:
            instance.fmu.setFMUstate(state)
            instance.time = t_saved
        for dt in [0.05, 0.3, 0.013]:
            instance.step(dt)
        return instance.get(*names), instance.get("n_rhs", "n_steps", "n_rejected")

    first = steps_from_saved(fmu)  # straight on from the saved point
    serialized = fmu.fmu.serializeFMUstate(saved)
    assert steps_from_saved(fmu, saved) == first
    # through bytes, into a fresh instance
    other = Instance(seed_fmu, name="other")
    restored = other.fmu.deSerializeFMUstate(serialized)
    assert steps_from_saved(other, restored) == first
    fmu.fmu.freeFMUstate(saved)
    other.fmu.freeFMUstate(restored)
    fmu.close()
    other.close()


@pytest.mark.parametrize(
    "name, value, message",
    BAD_VALUES
    + [
        (
            "solver",
            7,
            "solver = 7: choose 0 to 5 (0 = rk4, 1 = rk45, 2 = dop853, 3 = radau, 4 = auto, 5 = bdf)",
        ),
    ],
)
def test_bad_input_is_refused_and_named(seed_fmu, name, value, message):
    fmu = Instance(seed_fmu, initialize=False)
    with pytest.raises(FMICallException) as failure:
        fmu.set({name: value})
    assert failure.value.status == 4  # pythonfmu 0.7 maps every exception to fmi2Fatal
    assert any(status == 3 and text.startswith(message) for status, text in fmu.messages)
    fmu.close(after_fatal=True)
    gc.collect()  # pythonfmu releases a failed instance twice: the slave makes up for it
    # the host and other instances carry on
    assert run_fmu(seed_fmu, stop_time=0.5)["alpha0"][-1] == run_fmu(seed_fmu, stop_time=0.5)["alpha0"][-1]


def test_a_refused_run_leaves_no_folder_behind(seed_fmu, temporary_folder):
    """fmpy's simulate_fmu leaves the FMU it extracted whenever the FMU refuses (it removes it
    only after a run that completes); the package's runs extract into a folder they remove."""
    before = set(os.listdir(temporary_folder))
    with pytest.raises(FMICallException):
        run_fmu(seed_fmu, stop_time=0.1, start_values={"l0": -1.0})
    assert set(os.listdir(temporary_folder)) == before
    with pytest.raises(FMICallException):
        fmpy.simulate_fmu(str(seed_fmu), stop_time=0.1, start_values={"l0": -1.0})
    left = set(os.listdir(temporary_folder)) - before
    assert len(left) == 1  # what leaves_no_temporary_files would report
    shutil.rmtree(temporary_folder / left.pop())


@pytest.mark.parametrize(
    "name, initialize, message",
    [
        ("l1", True, "l1 cannot be set after initialization"),
        ("alpha0", True, "alpha0 cannot be set after initialization"),
        ("rtol", True, "rtol cannot be set after initialization"),
        ("energy", False, "energy is a calculated output: it cannot be set"),
    ],
)
def test_variables_are_set_only_when_the_standard_allows(seed_fmu, name, initialize, message):
    fmu = Instance(seed_fmu, initialize=initialize)
    if initialize:
        fmu.step(0.1)
    with pytest.raises(FMICallException):
        fmu.set({name: 1.0})
    assert any(text.startswith(message) for _, text in fmu.messages)
    fmu.close(after_fatal=True)


def _bad_tolerance(fmu):
    fmu.fmu.setupExperiment(tolerance=0.0, startTime=0.0)


# (what, the instance initialized, its start values, what is done to it)
SAID_ALIKE = [
    ("a bad value", False, {}, lambda fmu: fmu.set({"l0": -1.0})),
    ("a fixed value after initialization", True, {}, lambda fmu: fmu.set({"rtol": 1e-6})),
    ("a calculated output", False, {}, lambda fmu: fmu.set({"energy": 1.0})),
    ("a bad setting", False, {}, lambda fmu: fmu.set({"max_steps": 0})),
    ("a bad tolerance", False, {}, _bad_tolerance),
    ("a step that cannot complete", True, {"max_steps": 2, "rtol": 1e-13}, lambda fmu: fmu.step(1.0)),
]


@pytest.mark.parametrize("what, initialize, start, action", SAID_ALIKE, ids=[c[0] for c in SAID_ALIKE])
def test_both_fmus_say_the_same_words(seed_fmu, native_seed_fmu, what, initialize, start, action):
    """The slave's refusals and diagnoses are the native FMU's C (pendulum_model.c behind
    fmu_model.h): the same text, word for word, from either FMU."""
    said = []
    for path in (seed_fmu, native_seed_fmu):
        fmu = Instance(path, start_values=start, initialize=initialize)
        fmu.messages.clear()
        with pytest.raises(FMICallException):
            action(fmu)
        said.append([text for status, text in fmu.messages if status in (2, 3)])
        fmu.close(after_fatal=True)
    gc.collect()  # pythonfmu releases a failed instance twice: the slave makes up for it
    assert said[0] and said[0] == said[1], said


def test_step_that_cannot_complete_is_discarded_and_state_kept(seed_fmu):
    fmu = Instance(seed_fmu, start_values={"max_steps": 2, "rtol": 1e-13, "atol": 1e-13})
    before = fmu.get("alpha0", "beta2", "omega1", "energy")
    with pytest.raises(FMICallException) as failure:
        fmu.step(1.0)
    assert failure.value.status == 2  # fmi2Discard
    assert fmu.get("alpha0", "beta2", "omega1", "energy") == before
    assert any(
        status == 2 and "too many steps" in text and "max_steps = 2" in text for status, text in fmu.messages
    )
    fmu.time = 0.0
    fmu.step(1e-3)  # a shorter step still works from the kept state
    assert all(math.isfinite(v) for v in fmu.get("alpha0", "energy"))
    fmu.close()


def test_singular_mass_matrix_is_discarded_with_a_diagnosis(built_fmu):
    """A massless link with only a bob, lying along its parent's x axis."""
    path = built_fmu(Scene(links=(Link(), Link(has_mass=False))))
    fmu = Instance(path, start_values={"alpha1": math.pi / 2, "beta1": 0.0})
    with pytest.raises(FMICallException) as failure:
        fmu.step(0.01)
    assert failure.value.status == 2
    text = " ".join(t for _, t in fmu.messages)
    assert "singular mass matrix" in text and "link 1" in text
    assert fmu.get("alpha1") == [math.pi / 2]
    fmu.close()


def test_same_fmu_simulated_repeatedly_in_one_process(seed_fmu):
    runs = [run_fmu(seed_fmu, stop_time=1.0) for _ in range(4)]
    for run in runs[1:]:
        np.testing.assert_array_equal(run["bob2_x"], runs[0]["bob2_x"])


def test_two_builds_side_by_side(seed_fmu, chain_fmu):
    """Instances of two builds, and of one build with other parameters, stepped in turn."""
    setups = [(seed_fmu, {}, "alpha2"), (chain_fmu(2), {"l0": 2.0}, "alpha1"), (chain_fmu(2), {}, "alpha1")]

    def run(chosen):
        instances = [
            (Instance(path, name=f"i{k}", start_values=start), name)
            for k, (path, start, name) in enumerate(chosen)
        ]
        for _ in range(60):
            for fmu, _ in instances:
                fmu.step(1 / 60)
        values = [fmu.get(name) for fmu, name in instances]
        for fmu, _ in instances:
            fmu.close()
        return values

    alone = [run([setup])[0] for setup in setups]
    together = run(setups)
    assert together == alone
    assert alone[1] != alone[2]


def test_rebuilt_fmu_at_the_same_path_runs_its_new_model(fmu_dir):
    path = fmu_dir / "Rebuilt.fmu"
    build_fmu(Scene.uniform(3), path)
    first = run_fmu(path, stop_time=0.5)
    build_fmu(Scene.uniform(2), path)
    second = run_fmu(path, stop_time=0.5)
    assert "alpha2" in first.dtype.names and "alpha2" not in second.dtype.names
    np.testing.assert_array_equal(second["alpha1"], run_fmu(path, stop_time=0.5)["alpha1"])


def test_failed_build_leaves_no_fmu(fmu_dir):
    path = fmu_dir / "Never.fmu"
    with pytest.raises(ValueError, match="unknown setting"):
        build_fmu(Scene.uniform(1), path, settings={"rtoll": 1e-3})
    assert not path.exists()


BUILD_AFTER_A_RUN = """
import sys, fmpy
from conical_pendulum import Scene
from conical_pendulum.builder.fmu import build_fmu
seed, out = sys.argv[1:]
first = fmpy.simulate_fmu(seed, stop_time=0.2, output_interval=0.1)  # its pythonfmu, in-process
loaded = sys.modules["pythonfmu"].__file__
build_fmu(Scene.uniform(1), out)
assert sys.modules["pythonfmu"].__file__ == loaded  # put back for the FMU that imported it
again = fmpy.simulate_fmu(seed, stop_time=0.2, output_interval=0.1)
assert (first["alpha0"] == again["alpha0"]).all()
print(fmpy.simulate_fmu(out, stop_time=0.2, output_interval=0.1)["alpha0"][-1])
"""


def test_a_process_that_ran_a_pythonfmu_fmu_builds_another(seed_fmu, fmu_dir):
    """Running a pythonfmu FMU in-process imports the copy of pythonfmu in its resources, which
    has no binaries to pack and another Fmi2Slave: a build after it still packs the export
    library (it failed, 'pythonfmu packed no binary'), and the first FMU runs on."""
    out = fmu_dir / "AfterARun.fmu"
    run = subprocess.run(
        [sys.executable, "-c", BUILD_AFTER_A_RUN, str(seed_fmu), str(out)],
        check=False,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    assert float(run.stdout.split()[-1]) != 0.0 and validate_fmu(str(out)) == []
    with zipfile.ZipFile(out) as archive:
        assert [n for n in archive.namelist() if n.startswith("binaries/")] == [
            "binaries/linux64/ConicalPendulum.so"
        ]


def test_fmutool_check_passes(seed_fmu):
    """fmu-manipulation-toolbox: the FMI 2.0 schema and the semantic rules of section 2.2."""
    fmutool = shutil.which("fmutool", path=os.path.dirname(sys.executable)) or shutil.which("fmutool")
    assert fmutool, "fmutool comes with the test extra: pip install -e .[test]"
    run = subprocess.run(
        [fmutool, "-input", str(seed_fmu), "-check"], check=False, capture_output=True, text=True
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert "compliant with FMI-2.0" in run.stdout and "No semantic error" in run.stdout


def test_radau_matches_native(seed_fmu):
    """solver = 3: the core's Radau IIA, inside the FMU, against the native reference."""
    start = {"solver": 3, "rtol": 1e-10, "atol": 1e-10, "alpha1": 0.6}
    result = run_fmu(seed_fmu, stop_time=2.0, output_interval=0.1, start_values=start)
    from conical_pendulum.analysis.simulate import simulate

    native = simulate(Scene.uniform(3), result["time"], state={"alpha1": 0.6}, rtol=1e-12, atol=1e-12)
    for name in Scene.uniform(3).state_names():
        assert np.abs(result[name] - native[name]).max() < 1e-7, name
    assert result["n_rhs"][-1] > 0 and result["n_steps"][-1] > 0
    assert result["n_jacobians"][-1] > 0 and result["n_factorizations"][-1] >= 2 * result["n_jacobians"][-1]


@pytest.mark.parametrize("name, setter, value", [("l0", "setInteger", 3), ("solver", "setReal", 1.0)])
def test_wrong_types_are_refused_and_named(seed_fmu, name, setter, value):
    fmu = Instance(seed_fmu, initialize=False)
    with pytest.raises(FMICallException):
        getattr(fmu.fmu, setter)([fmu.vr[name]], [value])
    kind = "an Integer" if setter == "setInteger" else "a Real"
    assert any(
        f"value reference {fmu.vr[name]} is not {kind} variable" in text
        for status, text in fmu.messages
        if status == 3
    )
    fmu.close(after_fatal=True)
    gc.collect()
