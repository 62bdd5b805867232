"""One source for each rule: the scene, the native reference, the compiled core and the slave agree.

The slave is an ordinary module: these tests instantiate it in this process on the
resources of a built FMU, as pythonfmu would, and call its FMI methods directly.
"""

import json
import math
import zipfile
from pathlib import Path

import numpy as np
import pytest

from conical_pendulum import Link, Scene, SceneError
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.analysis.simulate import simulate
from conical_pendulum.builder.compiler import load_core
from conical_pendulum.runtime.files import MODEL_FILE
from conical_pendulum.runtime.rules import SETTINGS, SOLVERS, STATISTICS, BadValue
from conical_pendulum.runtime.slave import ConicalPendulum, Refused

SCENE = Scene.uniform(3, coupling=True)
VALUES = [-1.0, 0.0, 1e-3, 5.0, math.nan, math.inf]
LINK_FIELD = {"l": "length", "M": "mass", "m": "bob_mass"}


@pytest.fixture(scope="module")
def resources(coupled_fmu, tmp_path_factory):
    folder = tmp_path_factory.mktemp("coupled")
    with zipfile.ZipFile(coupled_fmu) as archive:
        archive.extractall(folder)
    return str(folder / "resources")


def refusal(call):
    """The message a call refuses with, or None when it takes the value."""
    try:
        call()
    except (BadValue, Refused) as exc:
        return str(exc)
    return None


def scene_refuses(name, value):
    """Whether a scene with this value (as a link field or gravity) is refused."""
    kind = name.rstrip("0123456789")
    try:
        if kind == "g":
            Scene(gravity=value)
        elif kind in LINK_FIELD:
            Scene(links=(Link(**{LINK_FIELD[kind]: value}),))
        else:  # Ixx, Iyy, Izz
            moments = [1.0, 1.0, 1.0]
            moments[["Ixx", "Iyy", "Izz"].index(kind)] = value
            Scene(links=(Link(moments=tuple(moments)),))
    except SceneError:
        return True
    return False


def test_native_reference_slave_and_scene_refuse_the_same_values(resources):
    slave = ConicalPendulum(instance_name="rules", resources=resources)
    vr = {v.name: v.value_reference for v in slave.vars.values()}
    checked = 0
    for name in SCENE.core_parameter_names() + SCENE.state_names():
        is_parameter = name in SCENE.core_parameter_names()
        for value in VALUES:
            given = {name: value}
            native = refusal(
                lambda: simulate(
                    SCENE,
                    [0.0],
                    method="core",
                    parameters=given if is_parameter else None,
                    state=None if is_parameter else given,
                )
            )
            fmu = refusal(lambda: slave.set_real([vr[name]], [value]))
            assert native == fmu, (name, value)
            if name in SCENE.parameter_names():
                assert scene_refuses(name, value) == (native is not None), (name, value)
            checked += native is not None
    assert checked >= 2 * len(SCENE.core_parameter_names() + SCENE.state_names())  # nan, inf at least


@pytest.mark.parametrize(
    "name, bad, good",
    [
        ("rtol", 0.0, 1e-6),
        ("atol", -1.0, 1e-9),
        ("max_step", -0.1, 0.0),
        ("solver", len(SOLVERS), 0),
        ("max_steps", 0, 1),
    ],
)
def test_the_slave_refuses_settings_by_their_rules(resources, name, bad, good):
    slave = ConicalPendulum(instance_name="settings", resources=resources)
    variable = next(v for v in slave.vars.values() if v.name == name)
    set_value = slave.set_integer if SETTINGS[name].integer else slave.set_real
    with pytest.raises(Refused, match=f"^{name} = {bad!r}: "):
        set_value([variable.value_reference], [bad])
    set_value([variable.value_reference], [good])
    getter = slave.get_integer if SETTINGS[name].integer else slave.get_real
    assert getter([variable.value_reference]) == [good]


def test_the_core_the_slave_and_the_scene_name_the_same_things(resources):
    core = load_core(SCENE)
    model = json.loads((Path(resources) / MODEL_FILE).read_text(encoding="utf-8"))

    def group(*names):
        return tuple(v["name"] for v in model["variables"] if v["group"] in names)

    assert core.PARAMETER_NAMES == tuple(SCENE.core_parameter_names()) == group("parameters", "inputs")
    assert core.STATE_NAMES == tuple(SCENE.state_names()) == group("states")
    assert core.OUTPUT_NAMES == tuple(SCENE.output_names()) == group("outputs")
    assert {name: k for k, name in enumerate(group("statistics"))} == core.STATISTICS_SLOTS
    for method, code in core.METHODS.items():  # the C solvers' codes are the `solver` values
        assert SOLVERS[code] == method
    assert model["settings"] == {name: setting.default for name, setting in SETTINGS.items()}
    slave = ConicalPendulum(instance_name="names", resources=resources)
    assert [v.name for v in slave.vars.values()] == (
        SCENE.core_parameter_names()
        + SCENE.state_names()
        + SCENE.output_names()
        + list(STATISTICS)
        + [n for n, s in SETTINGS.items() if not s.integer]
        + [n for n, s in SETTINGS.items() if s.integer]
    )


def test_the_slave_steps_in_process_as_it_does_in_fmpy(coupled_fmu, resources):
    slave = ConicalPendulum(instance_name="direct", resources=resources)
    vr = {v.name: v.value_reference for v in slave.vars.values()}
    slave.set_real([vr["l0"], vr["alpha0"]], [7.0, 0.4])
    slave.setup_experiment(0.0, 0.5)  # fmpy sets the stop time, where the solver's last step ends
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    time = 0.0
    for k in range(1, 31):  # the communication points as fmpy.simulate_fmu computes them
        assert slave.do_step(time, k * (1 / 60) - time)
        time = k * (1 / 60)
    names = ["alpha0", "beta2", "energy", "F_pivot_y"]
    direct = slave.get_real([vr[name] for name in names])
    run = run_fmu(coupled_fmu, stop_time=0.5, start_values={"l0": 7.0, "alpha0": 0.4})
    np.testing.assert_array_equal(direct, [run[name][-1] for name in names])
