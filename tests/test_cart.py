"""The coupled demo's cart as a native FMU: cart_model.c behind the same FMI glue as the pendulum,
FMI 2.0 and FMI 3.0 (fmi3_glue.c, the FMI 2.0 cart's behaviour through FMI 3.0's API)."""

import math
import struct
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu
from scipy.linalg import expm

from conical_pendulum.analysis.fmpy_runs import simulate_fmu
from conical_pendulum.builder.compiler import CSRC_FILES
from conical_pendulum.builder.models import cart
from conical_pendulum.builder.models.pendulum import PENDULUM
from conical_pendulum.builder.packaging import native
from conical_pendulum.cli import main
from conical_pendulum.demos.monolithic import cart_parameters
from differences import richardson
from fmu_helpers import INSTANCES, Instance, Instance3

ERROR, DISCARD = 3, 2  # fmi2Error, fmi2Discard (fmi3Error, fmi3Discard the same)


def test_the_cart_fmu_is_valid_and_says_what_depends_on_what(cart_fmu):
    assert validate_fmu(str(cart_fmu)) == []
    md = read_model_description(str(cart_fmu))
    assert md.coSimulation.modelIdentifier == md.modelExchange.modelIdentifier == "Cart"
    experiment = md.defaultExperiment
    assert (experiment.startTime, experiment.stopTime, experiment.stepSize) == ("0.0", "10.0", "0.01")
    dependencies = {u.variable.name: [v.name for v in u.dependencies] for u in md.outputs}
    # a state is an output of its own value; only a answers the inputs at once
    assert dependencies == {"x": ["x"], "v": ["v"], "a": ["F_x", "M_x", "x", "v"]}
    assert {u.variable.name: [v.name for v in u.dependencies] for u in md.derivatives} == {
        "der(x)": ["v"],
        "der(v)": ["F_x", "M_x", "x", "v"],
    }
    # at initialization the parameters are knowns too (and the states, exact at their starts)
    assert {u.variable.name: [v.name for v in u.dependencies] for u in md.initialUnknowns} == {
        name: ["m_cart", "k_cart", "c_cart", "F_x", "M_x", "x", "v"] for name in ("a", "der(x)", "der(v)")
    } | {"der(x)": ["v"]}
    starts = {v.name: v.start for v in md.modelVariables if v.start is not None}
    assert starts == {
        **{name: repr(value) for name, (_, value) in cart.PARAMETERS.items()},
        **{name: repr(value) for name, value in cart.START.items()},
        "F_x": "0.0",
        "M_x": "0.0",
        "F_x_order": "0",
    }


@pytest.mark.parametrize("version", [2, 3])
def test_the_glue_is_the_pendulums_unchanged(built_cart, version):
    """One more model file, not a copy of the glue: the cart ships runtime/csrc's FMI layer
    byte for byte, the files the pendulum's native FMU ships; FMI 3.0 adds only what builder.fmi.fmi3
    generates for any model (fmi3_arrays.h, buildDescription.xml)."""
    path = built_cart(version)
    with zipfile.ZipFile(path) as archive:
        shipped = {name.split("/", 1)[1] for name in archive.namelist() if name.startswith("sources/")}
        for name in (
            *native.LAYER_SOURCES[version],
            "fmi_layer.h",
            "fmu_model.h",
            "rules.c",
            "rules.h",
            "variable_table.c",
            "variable_table.h",
        ):
            assert archive.read(f"sources/{name}") == CSRC_FILES[name].read_bytes(), name
    generated = {"fmi3_arrays.h", "buildDescription.xml"} if version == 3 else set()
    assert shipped == {
        *native.glue_sources(cart.MODEL, version),
        *native.glue_headers(cart.MODEL),
        *generated,
    }
    pendulum, cart_sources = native.glue_sources(PENDULUM, version), native.glue_sources(cart.MODEL, version)
    assert pendulum[-2:] == cart_sources[-2:] == list(native.LAYER_SOURCES[version])
    assert "pendulum_model.c" not in cart_sources and "cart_model.c" not in pendulum


# The pythonfmu cart (cart_slave.py, removed; in git history) on the same run: M_x = 30 kg, F_x =
# 50 sin t + 20 t set before each of six 0.25 s steps; (x, v, a) after each step.
PYTHONFMU = {
    0: [
        (0.9646130540058507, -0.27959571109287873, -1.0700003375309233),
        (0.8668256055665973, -0.49660262496552426, -0.7901660797919459),
        (0.7238306574398281, -0.6395555455359462, -0.4754785444234241),
        (0.5548208444524838, -0.7039739813101674, -0.15432083877309635),
        (0.3792470263150546, -0.6922409522005483, 0.14639472567036618),
        (0.21517709132585783, -0.6129308591716334, 0.4033175727102561),
    ],
    1: [
        (0.9646130540058507, -0.27959571109287873, -1.0700003375309233),
        (0.8681992211755418, -0.480211204773133, -0.6606558704262794),
        (0.7304403675493332, -0.6090736478524377, -0.36009404828966973),
        (0.5697778512382631, -0.6632959352796377, -0.061601230061718804),
        (0.40455906514423884, -0.6464411886889214, 0.2100778806289658),
        (0.2515119400339422, -0.5677453042014645, 0.4342540598007825),
    ],
}


def _run(cart_fmu, order):
    fmu = Instance(cart_fmu, start_values={"M_x": 30.0, "F_x_order": order})
    rows = []
    for _ in range(6):
        fmu.set({"F_x": 50.0 * math.sin(fmu.time) + 20.0 * fmu.time})
        fmu.step(0.25)
        rows.append(fmu.get("x", "v", "a"))
    fmu.close()
    return np.array(rows)


@pytest.mark.parametrize("order", [0, 1])
def test_the_native_cart_is_the_pythonfmu_cart_to_rounding(cart_fmu, order):
    """Held and extrapolated force with an apparent mass: the same scaling and squaring, in C
    (BLAS sums numpy's products in another order: a few units in the last place)."""
    np.testing.assert_allclose(_run(cart_fmu, order), PYTHONFMU[order], rtol=0, atol=4e-15)


@pytest.mark.parametrize("order", [0, 1])
def test_each_step_is_the_exact_solution(cart_fmu, order):
    """Against scipy's expm of the same (x, v, F, F') system, step by step."""
    m, k, c = cart_parameters().values()
    mass = m + 30.0
    system = np.zeros((4, 4))
    system[0, 1], system[1, :3], system[2, 3] = 1.0, (-k / mass, -c / mass, 1.0 / mass), 1.0
    state, last, expected = np.array([1.0, 0.0]), None, []
    for step in range(6):
        t = 0.25 * step
        force = 50.0 * math.sin(t) + 20.0 * t
        slope = (force - last) / 0.25 if order == 1 and last is not None else 0.0
        last = force
        x, v, f, _ = expm(system * 0.25) @ (*state, force, slope)
        state = np.array([x, v])
        expected.append((x, v, (f - k * x - c * v) / mass))
    np.testing.assert_allclose(_run(cart_fmu, order), expected, rtol=0, atol=1e-13)


def test_cart_alone_is_the_exact_damped_oscillator(cart_fmu):
    m, k, c = cart_parameters().values()
    for carried in (0.0, 30.0):  # an apparent mass moves with the cart's own
        fmu = Instance(cart_fmu, start_values={"x": 1.0, "v": 0.0, "M_x": carried})
        mass = m + carried
        rate, damping = math.sqrt(k / mass - (c / (2 * mass)) ** 2), c / (2 * mass)
        for dt in (0.3, 1e-3, 2.0):  # exact whatever the step
            fmu.step(dt)
            t = fmu.time
            x = math.exp(-damping * t) * (math.cos(rate * t) + damping / rate * math.sin(rate * t))
            assert fmu.get("x")[0] == pytest.approx(x, abs=1e-13)
        fmu.set({"F_x": 50.0})  # the acceleration answers the inputs at once
        x, v = fmu.get("x", "v")
        assert fmu.get("a")[0] == pytest.approx((50.0 - k * x - c * v) / mass, rel=1e-14)
        fmu.close()


def test_cart_extrapolates_its_force_linearly_when_asked(cart_fmu):
    """F_x_order = 1: a force that grows linearly is followed exactly once two values are
    known (the first step holds it: no slope yet); held, the cart lags it."""
    from scipy.integrate import solve_ivp

    m, k, c = cart_parameters().values()
    slope, dt, steps = 40.0, 0.25, 8

    def motion(force, start, span):
        return solve_ivp(
            lambda t, y: [y[1], (force(t) - k * y[0] - c * y[1]) / m],
            span,
            start,
            dense_output=True,
            rtol=1e-13,
            atol=1e-13,
        ).sol

    first = motion(lambda t: 0.0, [1.0, 0.0], (0.0, dt))  # the first step: F_x = 0 held
    rest = motion(lambda t: slope * t, first(dt), (dt, steps * dt))
    errors = {}
    for order in (0, 1):
        fmu = Instance(cart_fmu, start_values={"x": 1.0, "v": 0.0, "F_x_order": order})
        for step in range(steps):
            fmu.set({"F_x": slope * step * dt})
            fmu.step(dt)
        errors[order] = abs(fmu.get("x")[0] - rest(steps * dt)[0])
        fmu.close()
    assert errors[1] < 1e-11 and errors[0] > 1e-3, errors


def test_model_exchange_in_cvode_is_the_exact_solution(cart_fmu):
    """F_x_order is Co-Simulation's: in Model Exchange the host integrates x' = v, v' = a."""
    m, k, c = cart_parameters().values()
    result = simulate_fmu(
        str(cart_fmu), fmi_type="ModelExchange", stop_time=3.0, output_interval=0.1, relative_tolerance=1e-10
    )
    rate, damping = math.sqrt(k / m - (c / (2 * m)) ** 2), c / (2 * m)
    t = result["time"]
    x = np.exp(-damping * t) * (np.cos(rate * t) + damping / rate * np.sin(rate * t))
    assert np.abs(result["x"] - x).max() < 1e-7


BAD_VALUES = [
    ("m_cart", -1.0, "m_cart = -1.0: a mass must be positive"),
    ("k_cart", -3.0, "k_cart = -3.0: a stiffness cannot be negative"),
    ("M_x", -2.0, "M_x = -2.0: an apparent mass cannot be negative"),
    ("F_x", float("nan"), "F_x = nan: must be finite"),
    ("F_x_order", 2, "F_x_order = 2: choose 0 (held over the step) or 1 (extrapolated linearly)"),
    ("a", 1.0, "a is a calculated output: it cannot be set"),
]


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("name, value, message", BAD_VALUES)
def test_a_bad_value_is_an_error_with_the_pythonfmu_carts_words(built_cart, version, name, value, message):
    """runtime/rules.py's words, as the pythonfmu cart said them at its next step; here the
    value is refused where it is set (fmi2Error, fmi3Error), and the instance goes on."""
    fmu = INSTANCES[version](built_cart(version), initialize=False)
    with pytest.raises(FMICallException) as failure:
        fmu.set({name: value})
    assert failure.value.status == ERROR
    assert message in fmu.texts(ERROR), fmu.messages
    fmu.initialize()
    fmu.step(0.1)
    assert fmu.get("m_cart", "M_x") == [100.0, 0.0]
    fmu.close()


def test_what_the_glue_refuses_it_refuses_for_the_cart_too(cart_fmu):
    fmu = Instance(cart_fmu)
    with pytest.raises(FMICallException):
        fmu.set({"m_cart": 50.0})  # fixed: before initialization only
    with pytest.raises(FMICallException):
        fmu.fmu.enterInitializationMode()  # once only
    with pytest.raises(FMICallException) as failure:
        fmu.step(-0.1)
    assert failure.value.status == DISCARD
    with pytest.raises(FMICallException):
        fmu.fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.1)  # stepFailed
    texts = [text for _, text in fmu.messages]
    assert any("m_cart cannot be set after initialization (variability fixed)" in text for text in texts), (
        texts
    )
    assert any("fmi2EnterInitializationMode is not allowed in state stepComplete" in text for text in texts)
    assert any(
        "communication step -0.1: must be a non-negative finite number; the state is kept" in text
        for text in texts
    )
    assert any("fmi2DoStep is not allowed in state stepFailed" in text for text in texts)
    fmu.fmu.reset()
    fmu.close(after_fatal=True)  # reset: only freed


def run_on(instance):
    """Five steps of a force set before each (an FMI 2.0 or 3.0 instance): (x, v, a) after them."""
    for step in range(5):
        instance.set({"F_x": 10.0 * (instance.time + step) ** 2})
        instance.step(0.2)
    return instance.get("x", "v", "a")


@pytest.mark.parametrize("version", [2, 3])
def test_fmu_state_get_set_and_serialize_replay_bit_for_bit(built_cart, cart_fmu, version):
    """The replay of a saved, or serialized and restored, FMU state is the first run, and the
    FMI 2.0 cart's run: the FMI 3.0 cart's state holds all of the model's."""
    path, make = built_cart(version), INSTANCES[version]
    fmu = make(path, start_values={"F_x_order": 1, "M_x": 30.0})
    run_on(fmu)  # the extrapolation carries the last point
    saved = fmu.get_state()
    data = fmu.serialize(saved)
    start_time = fmu.time
    first = run_on(fmu)
    reference = Instance(cart_fmu, start_values={"F_x_order": 1, "M_x": 30.0})
    run_on(reference)
    assert run_on(reference) == first
    reference.close()
    fmu.set_state(saved)
    fmu.time = start_time
    assert run_on(fmu) == first
    other = make(path)
    restored = other.deserialize(data)
    other.set_state(restored)
    other.time = start_time
    assert run_on(other) == first
    # bytes with a mass that is no mass: refused, naming it, and nothing taken
    mass = struct.pack("<d", 100.0)
    assert data.count(mass) == 1
    with pytest.raises(FMICallException) as failure:
        other.deserialize(data.replace(mass, struct.pack("<d", -1.0)))
    assert failure.value.status == ERROR
    function = {2: "fmi2DeSerializeFMUstate", 3: "fmi3DeserializeFMUState"}[version]
    assert any(
        f"{function}: the state's m_cart = -1.0: a mass must be positive" in text
        for _, text in other.messages
    ), other.messages[-3:]
    fmu.free_state(saved)
    other.free_state(restored)
    fmu.close()
    other.close()


def test_directional_derivatives_are_exact(cart_fmu):
    """a = (F - k_cart x - c_cart v) / (m_cart + M_x), written out: along the state, the
    inputs and the parameters (FMI 2.0's knowns of the InitialUnknowns, which OMSimulator
    asks for while starting the explicit scheme's loop), after steps."""
    m, k, c = cart_parameters().values()
    fmu = Instance(cart_fmu, start_values={"M_x": 30.0, "F_x": 40.0})
    fmu.step(0.5)
    fmu.set({"F_x": 25.0})
    vr = fmu.vr
    mass, (a, x, v) = m + 30.0, fmu.get("a", "x", "v")
    knowns = ["x", "v", "F_x", "M_x", "m_cart", "k_cart", "c_cart"]
    expected = {
        "a": [-k / mass, -c / mass, 1 / mass, -a / mass, -a / mass, -x / mass, -v / mass],
        "der(x)": [0, 1, 0, 0, 0, 0, 0],
        "x": [1, 0, 0, 0, 0, 0, 0],
    }
    expected["der(v)"] = expected["a"]
    for unknown, row in expected.items():
        for known, entry in zip(knowns, row):
            (value,) = fmu.fmu.getDirectionalDerivative([vr[unknown]], [vr[known]], [1.0])
            assert value == pytest.approx(entry, rel=1e-15, abs=0), (unknown, known)
    for known in ("a", "F_x_order"):  # a calculated output, an Integer parameter
        with pytest.raises(FMICallException):
            fmu.fmu.getDirectionalDerivative([vr["a"]], [vr[known]], [1.0])
        assert (
            f"value reference {vr[known]} ({known}) as a known: only states, inputs and Real parameters are"
            in fmu.texts()
        )
    fmu.close()


def test_partials_along_the_parameters_are_the_differences_of_a(cart_fmu):
    """In initialization mode, where the parameters may be set: each column of a and der(v)
    along m_cart, k_cart, c_cart and M_x equals Richardson differences of fmi2GetReal's a, to
    1e-10 relative (a is rational in them: the differences' error is rounding)."""
    fmu = Instance(cart_fmu, initialize=False, start_values={"M_x": 30.0, "F_x": 40.0, "v": 0.7})
    fmu.fmu.setupExperiment(startTime=0.0)
    fmu.fmu.enterInitializationMode()
    vr = fmu.vr
    for known in ("m_cart", "k_cart", "c_cart", "M_x"):
        (start,) = fmu.get(known)
        along = fmu.fmu.getDirectionalDerivative([vr["a"], vr["der(v)"]], [vr[known]], [1.0])

        def values(p, known=known):
            fmu.set({known: p[0]})
            return np.array(fmu.get("a"))

        (difference,) = richardson(values, np.array([start]), np.array([start])) / start
        values([start])
        assert along[0] == along[1] == pytest.approx(difference, rel=1e-10, abs=0), known
    fmu.fmu.exitInitializationMode()
    fmu.close()


def test_check_on_the_cart_says_it_is_no_pendulum(cart_fmu, capsys):
    """The cart is built here too, but has no scene to check against: one line, no traceback."""
    assert main(["check", str(cart_fmu)]) == 2
    assert (
        capsys.readouterr().err
        == f"conical-pendulum check: {cart_fmu}: Cart is no pendulum: it has no scene\n"
    )


# ---- the FMI 3.0 cart: fmi3_glue.c unchanged, the FMI 2.0 cart's behaviour through FMI 3.0's API ----

START3 = {"M_x": 30.0, "F_x": 40.0}  # an apparent mass and a force


def test_the_fmi3_cart_is_valid_with_the_fmi2_carts_variables_and_no_structural_parameter(
    cart_fmu3, cart_fmu
):
    assert validate_fmu(str(cart_fmu3)) == []
    ours, theirs = (read_model_description(str(path)) for path in (cart_fmu3, cart_fmu))
    assert ours.fmiVersion == "3.0"
    assert ours.coSimulation.modelIdentifier == ours.modelExchange.modelIdentifier == "Cart"
    experiment = ours.defaultExperiment
    assert (experiment.startTime, experiment.stopTime, experiment.stepSize) == ("0.0", "10.0", "0.01")
    types = {"Real": "Float64", "Integer": "Int32"}

    def described(v, type_):
        return v.valueReference, type_, v.causality, v.variability, v.initial, v.start, v.dimensions

    mine = {v.name: described(v, v.type) for v in ours.modelVariables}
    assert mine.pop("time")[:3] == (len(theirs.modelVariables), "Float64", "independent")
    # the same scalars and value references: no array, no UInt64 structural parameter
    assert mine == {v.name: described(v, types[v.type]) for v in theirs.modelVariables}
    for unknowns in ("outputs", "derivatives", "initialUnknowns"):
        assert [
            (u.variable.name, [v.name for v in u.dependencies or []]) for u in getattr(ours, unknowns)
        ] == [(u.variable.name, [v.name for v in u.dependencies or []]) for u in getattr(theirs, unknowns)]
    with zipfile.ZipFile(cart_fmu3) as archive:
        assert "binaries/x86_64-linux/Cart.so" in archive.namelist()
        build = ET.fromstring(archive.read("sources/buildDescription.xml"))
    assert build.find("BuildConfiguration").get("modelIdentifier") == "Cart"
    assert [f.get("name") for f in build.iter("SourceFile")] == native.glue_sources(cart.MODEL, 3)


def _simulate(path, fmi_type, **options):
    return simulate_fmu(str(path), fmi_type=fmi_type, stop_time=3.0, output_interval=0.05, **options)


def test_co_simulation_is_the_fmi2_carts_bit_for_bit_held_and_extrapolated(cart_fmu3, cart_fmu):
    """fmpy's simulate_fmu on both, an apparent mass and a force that varies (fmpy sets the input
    at each communication point), F_x_order set as an Int32."""
    t = np.linspace(0.0, 3.0, 301)
    signal = np.array(
        list(zip(t, 50.0 * np.sin(t) + 20.0 * t, np.full_like(t, 30.0))),
        dtype=[("time", "f8"), ("F_x", "f8"), ("M_x", "f8")],
    )
    runs = {}
    for order in (0, 1):
        ours, theirs = (
            _simulate(path, "CoSimulation", start_values={"M_x": 30.0, "F_x_order": order}, input=signal)
            for path in (cart_fmu3, cart_fmu)
        )
        assert ours.dtype.names == theirs.dtype.names == ("time", "x", "v", "a")
        for name in theirs.dtype.names:
            assert np.array_equal(ours[name], theirs[name]), (order, name)
        runs[order] = ours
    assert not np.array_equal(runs[0]["x"], runs[1]["x"])  # F_x_order was taken


def test_model_exchange_with_cvode_agrees_with_the_fmi2_cart(cart_fmu3, cart_fmu):
    ours, theirs = (
        _simulate(path, "ModelExchange", solver="CVode", relative_tolerance=1e-10, start_values=START3)
        for path in (cart_fmu3, cart_fmu)
    )
    for name in ("x", "v", "a"):  # the same x' from the same C: within CVode's tolerance
        np.testing.assert_allclose(ours[name], theirs[name], rtol=1e-10, atol=1e-12, err_msg=name)
    assert abs(ours["v"]).max() > 0.1  # it moved


def test_what_only_the_pendulum_has_is_refused_for_the_fmi3_cart(cart_fmu3):
    """No arrays and no structural parameter: no UInt64 variable, no configuration mode."""
    fmu = Instance3(cart_fmu3, initialize=False)
    with pytest.raises(FMICallException):
        fmu.fmu.fmi3EnterConfigurationMode(fmu.fmu.component)
    fmu.fmu.enterInitializationMode(startTime=0.0)
    fmu.fmu.exitInitializationMode()
    with pytest.raises(FMICallException):
        fmu.fmu.getUInt64([len(fmu.records) + 1])  # where the pendulum has n_links
    assert "fmi3EnterConfigurationMode: this FMU has no tunable structural parameters" in fmu.texts(ERROR)
    assert "fmi3GetUInt64: value reference 12: this FMU has no UInt64 variables" in fmu.texts(ERROR)
    assert fmu.get("time", "x") == [0.0, 1.0]
    fmu.close()


def test_fmi3_directional_and_adjoint_derivatives_are_the_fmi2_carts(cart_fmu3, cart_fmu):
    fmu2, fmu3 = (
        make(path, start_values=START3) for make, path in ((Instance, cart_fmu), (Instance3, cart_fmu3))
    )
    for fmu in (fmu2, fmu3):
        fmu.step(0.5)
    vr = fmu3.vr
    for unknown in ("a", "der(x)", "der(v)", "x"):
        for known in ("x", "v", "F_x", "M_x"):
            (expected,) = fmu2.fmu.getDirectionalDerivative([vr[unknown]], [vr[known]], [1.0])
            assert fmu3.fmu.getDirectionalDerivative([vr[unknown]], [vr[known]], [1.0]) == [expected]
            assert fmu3.fmu.getAdjointDerivative([vr[unknown]], [vr[known]], [1.0]) == [expected]
    fmu2.close()
    fmu3.close()
