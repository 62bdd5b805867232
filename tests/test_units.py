"""What every model description says of its values (builder.fmi.units, the records' rules): units
with their SI exponents, angles shown in degrees, ranges from the value rules (values beyond
them still refused with the same messages), the solver an enumeration, the states' nominals."""

import math
import shutil
from ctypes import POINTER, c_double

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model
from fmpy.fmi3 import FMU3Model
from fmpy.validation import validate_fmu

from conical_pendulum import Scene
from conical_pendulum.analysis.fmpy_runs import simulate_fmu
from conical_pendulum.builder.fmi.units import UNITS
from conical_pendulum.runtime.rules import RULES, SETTINGS, SOLVERS
from fmu_helpers import INSTANCES

COUPLED = Scene.uniform(3, coupling=True)
ERROR = 3


@pytest.fixture(scope="module")
def fmus(built_fmu, built_cart):
    """Every kind of FMU the project writes, by name."""
    return {
        "pythonfmu FMI 2.0": built_fmu(COUPLED),
        "native FMI 2.0": built_fmu(COUPLED, backend="native"),
        "native FMI 3.0": built_fmu(COUPLED, backend="native", fmi_version=3),
        "cart FMI 2.0": built_cart(2),
        "cart FMI 3.0": built_cart(3),
    }


REALS = ("Real", "Float64")
# The only Real without a unit: an absolute tolerance applies to states of different units.
UNITLESS = {"atol"}


@pytest.mark.parametrize(
    "name", ["pythonfmu FMI 2.0", "native FMI 2.0", "native FMI 3.0", "cart FMI 2.0", "cart FMI 3.0"]
)
def test_every_real_has_a_declared_unit(fmus, name):
    path = fmus[name]
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    declared = {u.name: u for u in md.unitDefinitions}
    reals = [v for v in md.modelVariables if v.type in REALS]
    assert {v.name for v in reals if v.unit is None} <= UNITLESS
    for v in reals:
        if v.unit is None:
            continue
        unit, ours = declared[v.unit], UNITS[v.unit]
        exponents = {k: getattr(unit.baseUnit, k) for k in ("kg", "m", "s", "A", "K", "mol", "cd", "rad")}
        assert {k: e for k, e in exponents.items() if e} == ours.base, v.name
        assert (unit.baseUnit.factor, unit.baseUnit.offset) == (1.0, 0.0)
        assert v.quantity == ours.quantity and v.displayUnit == (ours.display and ours.display.name)
    assert {u.name for u in md.unitDefinitions} == {v.unit for v in reals} - {None}  # none unused


def test_angles_show_in_degrees_the_way_the_standard_converts(fmus):
    """FMI: value_display = factor * value_unit + offset, so deg is 180/pi times rad; fmpy
    converts a start value given in the display unit that way."""
    md = read_model_description(str(fmus["native FMI 2.0"]))
    variables = {v.name: v for v in md.modelVariables}
    assert (variables["alpha0"].displayUnit, variables["omega0"].displayUnit) == ("deg", "deg/s")
    assert variables["der(omega0)"].displayUnit == "deg/s2"
    (deg,) = next(u for u in md.unitDefinitions if u.name == "rad").displayUnits
    assert (deg.name, deg.factor, deg.offset) == ("deg", 180 / math.pi, 0.0)
    for name in ("native FMI 2.0", "pythonfmu FMI 2.0"):
        result = simulate_fmu(str(fmus[name]), stop_time=0.01, start_values={"alpha0": (30.0, "deg")})
        assert result["alpha0"][0] == pytest.approx(math.radians(30.0), rel=1e-15)


def test_ranges_come_from_the_rules(fmus):
    md = read_model_description(str(fmus["native FMI 2.0"]))
    v = {v.name: v for v in md.modelVariables}
    # positive: FMI's min is inclusive, so min=0 (the FMU still refuses 0); non-negative: min=0
    assert (v["l0"].min, v["m0"].min, v["Ixx0"].min, v["atol"].min) == ("0.0", "0.0", "0.0", "0.0")
    assert float(v["rtol"].min) == RULES["relative-tolerance"].low
    assert (v["max_steps"].min, v["max_steps"].max) == ("1", None)
    assert (v["n_rhs"].min, v["n_rhs"].max) == ("0.0", str(float(2**53 - 1)))
    assert all(v[name].min is None and v[name].max is None for name in ("g", "alpha0", "a_pivot_x", "energy"))
    cart = {v.name: v for v in read_model_description(str(fmus["cart FMI 2.0"])).modelVariables}
    assert (cart["m_cart"].min, cart["k_cart"].min, cart["M_x"].min) == ("0.0", "0.0", "0.0")
    assert (cart["F_x_order"].min, cart["F_x_order"].max) == ("0", "1")


@pytest.mark.parametrize(
    "name, version", [("pythonfmu FMI 2.0", 2), ("native FMI 2.0", 2), ("native FMI 3.0", 3)]
)
@pytest.mark.parametrize(
    "variable, value, message",
    [
        ("l0", 0.0, "l0 = 0.0: a length must be positive"),  # at the declared min, still refused
        ("l0", -1.0, "l0 = -1.0: a length must be positive"),
        ("Ixx0", -1e-3, "Ixx0 = -0.001: a moment of inertia cannot be negative"),
        ("rtol", 1e-15, "rtol = 1e-15: a relative tolerance must be at least 2.22e-14"),
    ],
)
def test_values_beyond_a_rule_are_refused_with_its_message(fmus, name, version, variable, value, message):
    instance = INSTANCES[version](fmus[name], initialize=False)
    try:
        with pytest.raises(FMICallException):
            instance.set({variable: value})
        assert any(message in text for status, text in instance.messages if status == ERROR), (
            instance.messages
        )
    finally:  # never initialized (and the pythonfmu FMU answers fmi2Fatal): only freed
        instance.fmu.freeInstance()
        shutil.rmtree(instance.unzipdir, ignore_errors=True)


def test_the_solver_is_an_enumeration_of_the_same_numbers(fmus):
    items = {}
    for name in ("pythonfmu FMI 2.0", "native FMI 2.0", "native FMI 3.0"):
        md = read_model_description(str(fmus[name]))
        (solver,) = [v for v in md.modelVariables if v.name == "solver"]
        default = str(SETTINGS["solver"].default)
        assert (solver.type, solver.declaredType.name, solver.start) == ("Enumeration", "Solver", default)
        items[name] = [(item.name, int(item.value)) for item in solver.declaredType.items]
    assert items["pythonfmu FMI 2.0"] == [(name, k) for k, name in enumerate(SOLVERS)]
    assert items["native FMI 2.0"] == items["native FMI 3.0"] == items["pythonfmu FMI 2.0"]


def test_fmi3_sets_the_enumeration_as_int64_only(fmus):
    """FMI 3.0 gets and sets an enumeration with fmi3Get/SetInt64; Int32 access to it, and
    Int64 access to an Int32, is refused; an item the FMU lacks gets the solver's message."""
    instance = INSTANCES[3](fmus["native FMI 3.0"], initialize=False)
    try:
        fmu, vr = instance.fmu, instance.vr
        fmu.setInt64([vr["solver"]], [2])
        for call in (
            lambda: fmu.setInt64([vr["max_steps"]], [5]),
            lambda: fmu.setInt64([vr["solver"]], [6]),
            lambda: fmu.setInt64([vr["solver"]], [2**40]),
            lambda: fmu.setInt32([vr["solver"]], [1]),
        ):
            with pytest.raises(FMICallException):
                call()
        fmu.enterInitializationMode(startTime=0.0)
        assert list(fmu.getInt64([vr["solver"]])) == [2]  # nothing refused was taken
        with pytest.raises(FMICallException):
            fmu.getInt32([vr["solver"]])
        errors = [text for status, text in instance.messages if status == ERROR]
        assert errors == [
            f"fmi3SetInt64: value reference {vr['max_steps']} is not an Int64 variable",
            "solver = 6: choose 0 to 5 (0 = rk4, 1 = rk45, 2 = dop853, 3 = radau, 4 = auto, 5 = bdf)",
            f"fmi3SetInt64: solver = {2**40}: out of range",
            f"fmi3SetInt32: value reference {vr['solver']} is not an Int32 variable",
            f"fmi3GetInt32: value reference {vr['solver']} is not an Int32 variable",
        ]
    finally:
        instance.close()


@pytest.mark.parametrize("name", ["native FMI 2.0", "native FMI 3.0", "cart FMI 2.0", "cart FMI 3.0"])
def test_every_continuous_state_has_its_nominal(fmus, name):
    md = read_model_description(str(fmus[name]))
    states = [u.variable.derivative for u in md.derivatives]
    assert states and all(s.nominal is not None and float(s.nominal) > 0 for s in states)
    nominal = {s.name: float(s.nominal) for s in states}
    if name.startswith("cart"):
        assert nominal == {"x": 1.0, "v": pytest.approx(math.sqrt(150.0 / 100.0))}
    else:  # a radian; the chain's natural frequency sqrt(g / total length) for the rates
        angles, rates = (("alpha0", "omega0"), ("alpha", "omega"))[name.endswith("3.0")]
        assert nominal[angles] == 1.0 and nominal[rates] == pytest.approx(np.sqrt(9.8 / 30.0))
    # what Model Exchange answers at run time (a host scales its tolerances by it) is declared
    declared = np.repeat([float(s.nominal) for s in states], [math.prod(s.shape or ()) for s in states])
    unzipped = extract(str(fmus[name]))
    kind = FMU2Model if md.fmiVersion == "2.0" else FMU3Model
    fmu = kind(
        guid=md.guid,
        unzipDirectory=unzipped,
        modelIdentifier=md.modelExchange.modelIdentifier,
        instanceName="nominals",
    )
    try:
        fmu.instantiate()
        answered = np.zeros(len(declared))
        fmu.getNominalsOfContinuousStates(answered.ctypes.data_as(POINTER(c_double)), len(answered))
        fmu.freeInstance()
    finally:
        shutil.rmtree(unzipped, ignore_errors=True)
    np.testing.assert_array_equal(answered, declared)
