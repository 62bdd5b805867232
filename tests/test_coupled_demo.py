"""The coupled demo: the Cart FMU, the monolithic reference, ecospy's co-simulation."""

import csv
import math

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from conical_pendulum.builder.compiler import load_core
from conical_pendulum.cli import main as cli
from conical_pendulum.demos.coupled import SCENE, SCHEMES, build_cart_fmu
from conical_pendulum.demos.monolithic import cart_parameters, monolithic
from fmu_helpers import Instance


@pytest.fixture(scope="module")
def cart_fmu(tmp_path_factory):
    return build_cart_fmu(tmp_path_factory.mktemp("cart") / "Cart.fmu")


def test_cart_alone_is_the_exact_damped_oscillator(cart_fmu):
    assert validate_fmu(str(cart_fmu)) == []
    md = read_model_description(str(cart_fmu))
    dependencies = {u.variable.name: [v.name for v in u.dependencies] for u in md.outputs}
    assert dependencies == {"x": [], "v": [], "a": ["F_x", "M_x"]}  # only a answers the inputs at once
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


@pytest.mark.parametrize(
    "name, value, message",
    [
        ("m_cart", -1.0, "m_cart = -1.0: a mass must be positive"),
        ("M_x", -2.0, "M_x = -2.0: an apparent mass cannot be negative"),
        ("F_x_order", 2, "F_x_order = 2: choose 0 (held over the step) or 1 (extrapolated linearly)"),
    ],
)
def test_cart_with_a_bad_value_discards_its_step_and_says_why(cart_fmu, name, value, message):
    fmu = Instance(cart_fmu, start_values={name: value})
    with pytest.raises(FMICallException) as failure:
        fmu.step(0.1)
    assert failure.value.status == 2  # fmi2Discard
    assert any(message in text for _, text in fmu.messages), fmu.messages
    fmu.close()


def test_monolithic_model_is_the_coupled_pieces_physics():
    """Along the one-model reference, the pendulum's core driven by the cart's acceleration
    gives the same accelerations, and its pivot force is what moves the cart."""
    reference = monolithic(np.linspace(0.0, 3.0, 31), SCENE)
    core = load_core(SCENE)
    m, k, c = cart_parameters().values()
    names, n = SCENE.state_names(), SCENE.n
    force = SCENE.output_names().index("F_pivot_x")
    for i in range(31):
        state = [reference[name][i] for name in names]
        p = SCENE.parameters({"a_pivot_x": reference["a_cart"][i]})
        rates = core.rhs(state, p)[2 * n :]
        expected = [reference[f"d{name}"][i] for name in names[2 * n :]]
        assert np.abs(rates - expected).max() < 1e-9 * max(1.0, np.abs(expected).max())
        cart_force = core.outputs(state, p)[force] - k * reference["x_cart"][i] - c * reference["v_cart"][i]
        assert m * reference["a_cart"][i] == pytest.approx(cart_force, rel=1e-9, abs=1e-9)
    assert np.abs(reference["a_cart"]).max() > 0.5  # the cart does move


def _demo(tmp_path, *argv) -> dict:
    """{(scheme, cart mass, step): row of coupling_error.csv} of a demo run."""
    assert cli(["demo", "--out", str(tmp_path), *argv]) == 0
    with open(tmp_path / "coupling_error.csv") as f:
        return {(r["scheme"], float(r["cart_mass_kg"]), float(r["step_s"])): r for r in csv.DictReader(f)}


def test_the_demo_command_converges_at_first_order_in_both_schemes(tmp_path):
    rows = _demo(tmp_path, "--steps", "0.1,0.05,0.025", "--stop-time", "4", "--cart-mass", "100")
    assert len(rows) == 6
    for scheme in SCHEMES:
        for field in ("cart_error_m", "angle_error_rad", "force_error_N"):
            errors = [float(rows[scheme, 100.0, dt][field]) for dt in (0.1, 0.05, 0.025)]
            assert 1.7 < errors[0] / errors[1] < 2.3 and 1.7 < errors[1] / errors[2] < 2.3, (scheme, field)
    for dt in (0.1, 0.05, 0.025):  # where both are stable, the apparent mass is no less accurate
        for field in ("cart_error_m", "angle_error_rad", "force_error_N"):
            assert float(rows["apparent-mass", 100.0, dt][field]) <= float(rows["explicit", 100.0, dt][field])
    assert float(rows["explicit", 100.0, 0.025]["cart_error_m"]) < 0.02
    assert (tmp_path / "coupling.png").stat().st_size > 20_000


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--steps", "0.1,x"], "--steps: expected numbers"),
        (["--steps", "0.3", "--stop-time", "1"], "must be positive, divide --stop-time"),
        (["--steps", "0.1,0.15"], "multiple of the smallest"),
        (["--cart-mass", "-1"], "--cart-mass: must be a positive number of kg, got -1.0"),
        (["--cart-mass", "5,nan"], "--cart-mass: must be a positive number of kg, got nan"),
        (
            ["--scheme", "explicit,implicit"],
            "--scheme: unknown scheme(s) 'implicit'; choose from explicit, apparent-mass",
        ),
    ],
)
def test_bad_demo_options_are_named(argv, message, capsys, tmp_path):
    assert cli(["demo", "--out", str(tmp_path / "out"), *argv]) == 2
    err = capsys.readouterr().err
    assert message in err
    assert err.startswith("conical-pendulum demo: ") and err.count("\n") == 1  # one line
    assert not (tmp_path / "out").exists()


def test_a_light_cart_diverges_explicitly_and_not_with_its_apparent_mass(tmp_path, capsys):
    """The added-mass limit: 2 and 0.5 kg carts under the 45 kg chain. The explicit exchange
    runs away (stopped beyond 1000 m); the apparent-mass one follows the truth."""
    rows = _demo(tmp_path, "--steps", "0.2,0.01", "--stop-time", "2", "--cart-mass", "2,0.5")
    out = capsys.readouterr().out
    for mass in (2.0, 0.5):
        for dt in (0.2, 0.01):
            assert rows["explicit", mass, dt]["diverged"] == "true"
            assert f"explicit, cart {mass:g} kg, step {dt:g} s: the exchange diverged (" in out
            assert rows["apparent-mass", mass, dt]["diverged"] == "false"
        assert float(rows["apparent-mass", mass, 0.01]["cart_error_m"]) < 0.03
        assert float(rows["apparent-mass", mass, 0.2]["cart_error_m"]) < 0.7
    assert "apparent-mass, cart" not in out
    assert (tmp_path / "coupling.png").exists()
