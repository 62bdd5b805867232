"""The coupled demo as an SSP 1.0 package (demos/ssp.py) and its runs in the tools that read
SSP (demos/ssp_tools.py): ecospy, ecos' command line, libcosim, FMPy's simulate_ssp, OMSimulator."""

import math
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.ssp.ssd import read_ssd, read_ssv
from lxml import etree

from conical_pendulum.builder.fmi.units import BASE_UNITS
from conical_pendulum.demos import coupled, ecospy_run, libcosim_run, ssp, ssp_tools
from conical_pendulum.demos.monolithic import cart_parameters
from fmu_helpers import Instance
from required_tools import require_omsimulator, require_tool

STEP, STOP_TIME, CART_MASS = 0.01, 0.1, 5.0  # 10 steps: the fewest ecos' command line takes


@pytest.fixture(scope="module")
def fmus(built_fmu, cart_fmu):
    return built_fmu(coupled.SCENE, backend="native"), cart_fmu


@pytest.fixture(scope="module")
def package(fmus, tmp_path_factory):
    """A light cart (5 kg, not the FMU's 100 kg start), so a run shows its parameters applied."""
    path = tmp_path_factory.mktemp("ssp") / "PendulumOnCart.ssp"
    return ssp.write_package(path, *fmus, cart_mass=CART_MASS, step=STEP, stop_time=STOP_TIME)


@pytest.fixture(scope="module")
def ecospy_runs(package, tmp_path_factory):
    require_tool("ecospy", lambda: ssp_tools.missing("ecospy") is None, 'pip install -e ".[cosim]"')
    work = tmp_path_factory.mktemp("ecospy")
    return {scheme: ssp_tools.run("ecospy", package, scheme, work) for scheme in ssp.VARIANTS}


def test_the_package_is_valid_ssp_with_units_parameters_and_the_step(package, fmus):
    assert ssp.validate(package) == []
    # the connectors' units are the FMUs' own: each variable's unit, each unit's BaseUnit
    mds = dict(zip(ssp.FMUS, (read_model_description(str(path)) for path in fmus)))
    declared = {u.name: u.baseUnit for md in mds.values() for u in md.unitDefinitions}
    units = {(i, v.name): v.unit for i, md in mds.items() for v in md.modelVariables}
    with zipfile.ZipFile(package) as archive:
        assert sorted(archive.namelist()) == sorted(
            ["SystemStructure.ssd", "ApparentMass.ssd", *ssp.FMUS.values()]
            + [ssp.parameter_file(scheme) for scheme in ssp.VARIANTS]
        )
        for scheme, name in ssp.VARIANTS.items():
            root = etree.fromstring(archive.read(name))
            connections = [
                [
                    f"{c.get('startElement')}::{c.get('startConnector')}",
                    f"{c.get('endElement')}::{c.get('endConnector')}",
                ]
                for c in root.iterfind(".//ssd:Connection", ssp.NS)
            ]
            assert connections == coupled.SCHEMES[scheme][0]
            (x,) = root.xpath(
                ".//ssd:Component[@name='cart']/ssd:Connectors/ssd:Connector[@name='x']", namespaces=ssp.NS
            )
            assert x.get("kind") == "output" and x.find("ssc:Real", ssp.NS).get("unit") == "m"
            (newton,) = root.xpath("ssd:Units/ssc:Unit[@name='N']/ssc:BaseUnit", namespaces=ssp.NS)
            assert dict(newton.attrib) == {"kg": "1", "m": "1", "s": "-2"}
            for connector in root.iterfind(".//ssd:Connector", ssp.NS):
                instance = connector.getparent().getparent().get("name")
                unit = connector.find("ssc:Real", ssp.NS).get("unit")
                assert unit == units[instance, connector.get("name")] and unit is not None
            for unit in root.iterfind("ssd:Units/ssc:Unit", ssp.NS):
                base = declared[unit.get("name")]
                wanted = {k: str(getattr(base, k)) for k in BASE_UNITS if getattr(base, k)}
                assert dict(unit.find("ssc:BaseUnit", ssp.NS).attrib) == wanted
            (binding,) = root.xpath(".//ssd:ParameterBinding/@source", namespaces=ssp.NS)
            assert binding == ssp.parameter_file(scheme)
    assert ssp.experiment(package) == (STEP, STOP_TIME)
    assert read_ssd(str(package)).system.name == ssp.SYSTEM  # FMPy reads (and validates) it too
    for scheme in ssp.VARIANTS:
        values = {
            p.name: p.value for p in read_ssv(str(package), resource=ssp.parameter_file(scheme)).parameters
        }
        expected = {**cart_parameters(m_cart=CART_MASS), **coupled.SCHEMES[scheme][1]}
        assert {name: float(value) for name, value in values.items()} == expected


def test_no_input_is_left_unconnected(package):
    """FMPy's simulate_ssp wires an unconnected input to the previous input's source."""
    with zipfile.ZipFile(package) as archive:
        for name in ssp.VARIANTS.values():
            root = etree.fromstring(archive.read(name))
            inputs = {
                f"{c.getparent().getparent().get('name')}::{c.get('name')}"
                for c in root.iterfind(".//ssd:Connector[@kind='input']", ssp.NS)
            }
            ends = {
                f"{c.get('endElement')}::{c.get('endConnector')}"
                for c in root.iterfind(".//ssd:Connection", ssp.NS)
            }
            assert inputs == ends


def test_a_package_against_the_schema_is_named_line_by_line(package, tmp_path):
    broken = tmp_path / "broken.ssp"
    with zipfile.ZipFile(package) as source, zipfile.ZipFile(broken, "w") as target:
        for item in source.infolist():
            data = source.read(item)
            if item.filename == "SystemStructure.ssd":
                data = data.replace(b' version="1.0"', b"", 1)
            if item.filename != ssp.FMUS["cart"]:
                target.writestr(item, data)
    problems = ssp.validate(broken)
    assert any(p.startswith("SystemStructure.ssd:") and "'version' is required" in p for p in problems), (
        problems
    )
    assert f"SystemStructure.ssd: names {ssp.FMUS['cart']}, which the package lacks" in problems


@pytest.mark.tools
def test_ecospy_runs_the_package_as_todays_demo(fmus, ecospy_runs):
    """ecos from the package is the demo's own master wiring the same FMUs in Python: the same numbers."""
    for scheme, run in ecospy_runs.items():
        assert run.refused is None and run.warnings == []
        demo = coupled.cosimulate(*fmus, [STEP], STOP_TIME, cart_parameters(m_cart=CART_MASS), scheme)[STEP]
        assert len(run.values["time"]) == round(STOP_TIME / STEP) + 1
        for name, values in run.values.items():
            np.testing.assert_array_equal(values, demo[name], err_msg=f"{scheme}: {name}")


@pytest.mark.tools
def test_ecos_command_line_runs_it_with_a_clean_environment(package, ecospy_runs, tmp_path):
    """Only LD_LIBRARY_PATH, to a folder with ecos' libtbb: no Python. Its CSV has six decimals."""
    require_tool("ecos", lambda: ssp_tools.missing("ecos") is None, 'pip install -e ".[cosim]"')
    for scheme, library in ecospy_runs.items():
        run = ssp_tools.run("ecos", package, scheme, tmp_path)
        assert run.refused is None, run.refused
        times = run.values["time"]
        np.testing.assert_allclose(times, library.values["time"][: len(times)], rtol=0, atol=1e-12)
        assert len(times) >= round(STOP_TIME / STEP)  # its last row may be the step before the end
        for name, values in run.values.items():
            np.testing.assert_allclose(
                values, library.values[name][: len(times)], rtol=0, atol=5.1e-7, err_msg=f"{scheme}: {name}"
            )


@pytest.mark.tools
def test_ecos_command_line_refuses_fewer_than_ten_steps(fmus, tmp_path):
    short = ssp.write_package(tmp_path / "short.ssp", *fmus, step=0.01, stop_time=0.05)
    run = ssp_tools.run("ecos", short, "explicit", tmp_path / "work")
    assert run.values == {} and "fewer than 10 steps" in run.refused and "SIGFPE" in run.refused


@pytest.mark.tools
def test_libcosim_takes_the_step_from_the_annotation_and_follows_ecos(package, ecospy_runs, tmp_path):
    """The same Jacobi step as ecos: without an algebraic loop (apparent-mass) the same numbers."""
    require_tool("libcosim", lambda: ssp_tools.missing("libcosim") is None, 'pip install -e ".[cosim]"')
    runs = {scheme: ssp_tools.run("libcosim", package, scheme, tmp_path) for scheme in ssp.VARIANTS}
    for run in runs.values():
        assert run.refused is None and run.warnings == [], (run.refused, run.warnings)
        np.testing.assert_allclose(run.values["time"], STEP * np.arange(1, 11), rtol=0, atol=1e-12)
    ecos = ecospy_runs["apparent-mass"].values
    for name in ["x", "v", *coupled.SCENE.state_names()]:
        np.testing.assert_allclose(runs["apparent-mass"].values[name], ecos[name][1:], rtol=0, atol=1e-14)


@pytest.mark.tools
def test_the_explicit_loop_is_initialised_by_two_jacobi_sweeps_in_ecos_and_three_in_libcosim(
    fmus, package, tmp_path
):
    """cart.a and p.F_pivot_x answer each other at once (explicit scheme): both masters
    iterate that loop while initialising, from the inputs' starts (0), and step 1 holds the
    force they stopped at: ecos two sweeps, libcosim three; the consistent force is neither."""
    require_tool("libcosim", lambda: ssp_tools.missing("libcosim") is None, 'pip install -e ".[cosim]"')
    pendulum = Instance(fmus[0])
    free, apparent = pendulum.get("F_free_x", "M_pivot_xx")
    pendulum.close()
    m, k, _ = cart_parameters(m_cart=CART_MASS).values()
    a, force, sweeps = 0.0, 0.0, []
    for _ in range(3):  # Jacobi: each side answers the other's last value
        a, force = (force - k * 1.0) / m, free - apparent * a  # the cart starts at x = 1, v = 0
        sweeps.append(force)
    folder = ssp.variant(package, "explicit", tmp_path / "explicit")
    job = {"ssp": str(folder), "parameter_set": "explicit", "steps": [STEP], "stop_time": STEP}
    (ecos,) = ecospy_run.cosimulate({**job, "record": ["cart::F_x"]})
    libcosim = libcosim_run.simulate({"ssp": str(package), "stop_time": STEP, "record": ["cart::F_x"]})
    assert ecos["values"]["cart::F_x"][0] == pytest.approx(sweeps[1], abs=1e-12)  # set for step 1
    assert libcosim["values"]["cart::F_x"][0] == pytest.approx(sweeps[2], abs=1e-12)  # held in step 1
    consistent = free - apparent * (free - k) / (m + apparent)
    assert abs(sweeps[1] - consistent) > 1.0 and abs(sweeps[2] - consistent) > 0.1


@pytest.mark.tools
def test_fmpy_runs_it_with_its_own_master(package, ecospy_runs, tmp_path):
    """simulate_ssp starts every connector at 0: its first step has F_x = M_x = 0 at the cart,
    which then moves as alone with its parameters applied (5 kg); then the same Jacobi step."""
    for scheme in ssp.VARIANTS:
        run = ssp_tools.run("fmpy", package, scheme, tmp_path)
        assert run.refused is None
        np.testing.assert_allclose(run.values["time"], STEP * np.arange(1, 11), rtol=0, atol=1e-12)
        m, k, c = cart_parameters(m_cart=CART_MASS).values()
        damping = c / (2 * m)
        rate = math.sqrt(k / m - damping**2)
        alone = math.exp(-damping * STEP) * (math.cos(rate * STEP) + damping / rate * math.sin(rate * STEP))
        assert run.values["x"][0] == pytest.approx(alone, abs=1e-13)
        assert run.values["x"][0] != pytest.approx(ecospy_runs[scheme].values["x"][1], abs=1e-6)


@pytest.fixture(scope="module")
def omsimulator_runs(package, tmp_path_factory):
    """OMSimulator ($OMSIMULATOR or PATH), each variant of the package as written."""
    require_omsimulator()
    work = tmp_path_factory.mktemp("omsimulator")
    return {scheme: ssp_tools.run("omsimulator", package, scheme, work) for scheme in ssp.VARIANTS}


@pytest.mark.tools
def test_omsimulator_reads_its_master_and_step_from_the_package(package, omsimulator_runs):
    """Its model is named after the SSD (an identifier), its step is its own annotation's;
    both variants run to the stop time."""
    for scheme, name in ssp.VARIANTS.items():
        with zipfile.ZipFile(package) as archive:
            root = etree.fromstring(archive.read(name))
        assert root.get("name") == ssp.model_name(scheme) and ssp.model_name(scheme).isidentifier()
        (master,) = root.xpath(
            "ssd:System/ssd:Annotations/ssc:Annotation[@type='org.openmodelica']"
            "/oms:Annotations/oms:SimulationInformation/oms:FixedStepMaster",
            namespaces=ssp.NS,
        )
        assert master.get("description") == "oms-ma" and float(master.get("stepSize")) == STEP
        run = omsimulator_runs[scheme]
        assert run.refused is None and run.ended is None, run.refused
        np.testing.assert_allclose(run.values["time"], STEP * np.arange(11), rtol=0, atol=1e-12)


@pytest.mark.tools
def test_omsimulator_prints_no_error(omsimulator_runs):
    """It exits 0 even when a run fails, so the runner reads its `error:` lines: none wanted.
    While initializing it asks for the InitialUnknowns' derivatives with their parameters (l0,
    m_cart, ...) among the knowns, seed 0, and the FMUs answer them."""
    for run in omsimulator_runs.values():
        assert run.warnings == [], run.warnings


@pytest.mark.tools
@pytest.mark.parametrize("cart_mass", [2.0, 0.5])
def test_omsimulator_starts_the_light_carts_in_the_explicit_scheme(fmus, cart_mass, tmp_path):
    """With the 2 and 0.5 kg carts KINSOL converges at the start only on the exact derivatives
    with respect to parameters (it stopped with flag -7 while the FMUs refused them): the run
    reaches the stop time, with no error printed."""
    require_omsimulator()
    path = tmp_path / "PendulumOnCart.ssp"
    package = ssp.write_package(path, *fmus, cart_mass=cart_mass, step=STEP, stop_time=STOP_TIME)
    run = ssp_tools.run("omsimulator", package, "explicit", tmp_path)
    assert run.refused is None and run.ended is None, run.refused
    assert run.warnings == [], run.warnings
    np.testing.assert_allclose(run.values["time"], STEP * np.arange(11), rtol=0, atol=1e-12)


@pytest.mark.tools
def test_omsimulator_solves_the_explicit_loop_at_every_step(fmus, omsimulator_runs, ecospy_runs):
    """cart.a and p.F_pivot_x answer each other at once: OMSimulator solves that loop (KINSOL,
    the FMUs' directional derivatives) at the start and after every step, so each recorded
    point has the force the pendulum gives at the cart's acceleration there, to the loop's
    tolerance (1e-4 on the residual), and starts from the consistent force, which neither
    ecos' two Jacobi sweeps nor libcosim's three reach (the test above)."""
    values = omsimulator_runs["explicit"].values
    pendulum = Instance(fmus[0])
    free, apparent = pendulum.get("F_free_x", "M_pivot_xx")
    pendulum.close()
    m, k, _ = cart_parameters(m_cart=CART_MASS).values()
    consistent = free - apparent * (free - k) / (m + apparent)
    assert values["F_pivot_x"][0] == pytest.approx(consistent, abs=1e-3)
    assert values["a"][0] == pytest.approx((consistent - k) / m, abs=1e-3)
    ecos = ecospy_runs["explicit"].values
    assert abs(ecos["F_pivot_x"][0] - consistent) > 1.0  # ecos starts elsewhere
    # the cart's acceleration is the one the pendulum's force gives, m a = F - k x - c v, at
    # every point: the loop's residual (the cart's input F_x against F_pivot_x) within KINSOL's
    # function-norm tolerance, which is the master's relativeTolerance (1e-4)
    c = cart_parameters(m_cart=CART_MASS)["c_cart"]
    np.testing.assert_allclose(
        m * values["a"], values["F_pivot_x"] - k * values["x"] - c * values["v"], rtol=0, atol=1e-4
    )


@pytest.mark.tools
def test_omsimulator_input_extrapolation_makes_the_apparent_mass_scheme_second_order(fmus, tmp_path):
    """With --inputExtrapolation OMSimulator passes the pendulum's output derivatives (F_free,
    M_app) on to the cart as input derivatives (issue 29): halving the step quarters the
    cart's error (100 kg cart, 2 s, 0.04 and 0.02 s), where the held inputs only halve it."""
    require_omsimulator()
    stop, steps, mass = 2.0, (0.04, 0.02), 100.0
    times = np.linspace(0.0, stop, round(stop / steps[-1]) + 1)
    truth = coupled.reference(times, coupled.SCENE, cart_parameters(m_cart=mass))
    errors = {}
    for option in ((), ("--inputExtrapolation=true",)):
        runs = {}
        for step in steps:
            path = ssp.write_package(
                tmp_path / f"{step}.ssp", *fmus, cart_mass=mass, step=step, stop_time=stop
            )
            run = ssp_tools.run_omsimulator(
                path.absolute(), "apparent-mass", (tmp_path / f"{step}{option}").absolute(), option
            )
            assert run.refused is None and run.ended is None, run.refused or run.ended
            runs[step] = run.as_run()
        errors[option] = [e.cart_error for e in coupled.coupling_errors(runs, truth, "apparent-mass", mass)]
    held, extrapolated = errors[()], errors[("--inputExtrapolation=true",)]
    assert 1.8 < held[1] / held[0] < 2.2  # sorted by step: (0.02, 0.04)
    assert 3.6 < extrapolated[1] / extrapolated[0] < 4.4
    assert extrapolated[0] < held[0] / 10
