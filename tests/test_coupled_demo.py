"""The coupled demo: the Cart FMU, the monolithic reference, ecospy's co-simulation."""
import csv
import math

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from conical_pendulum.build.compiler import load_core
from conical_pendulum.cli import main as cli
from conical_pendulum.demos.coupled import SCENE, build_cart_fmu
from conical_pendulum.demos.monolithic import cart_parameters, monolithic
from fmu_helpers import Instance


@pytest.fixture(scope="module")
def cart_fmu(tmp_path_factory):
    return build_cart_fmu(tmp_path_factory.mktemp("cart") / "Cart.fmu")


def test_cart_alone_is_the_exact_damped_oscillator(cart_fmu):
    assert validate_fmu(str(cart_fmu)) == []
    md = read_model_description(str(cart_fmu))
    dependencies = {u.variable.name: [v.name for v in u.dependencies] for u in md.outputs}
    assert dependencies == {"x": [], "v": [], "a": ["F_x"]}  # only a answers its input at once
    fmu = Instance(cart_fmu, start_values={"x": 1.0, "v": 0.0})
    m, k, c = cart_parameters().values()
    rate, damping = math.sqrt(k / m - (c / (2 * m)) ** 2), c / (2 * m)
    for dt in (0.3, 1e-3, 2.0):  # exact whatever the step
        fmu.step(dt)
        t = fmu.time
        x = math.exp(-damping * t) * (math.cos(rate * t) + damping / rate * math.sin(rate * t))
        assert fmu.get("x")[0] == pytest.approx(x, abs=1e-13)
    fmu.set({"F_x": 50.0})  # the acceleration answers the input at once
    x, v = fmu.get("x", "v")
    assert fmu.get("a")[0] == pytest.approx((50.0 - k * x - c * v) / m, rel=1e-14)
    fmu.close()


def test_cart_with_a_bad_mass_discards_its_step_and_says_why(cart_fmu):
    fmu = Instance(cart_fmu, start_values={"m_cart": -1.0})
    with pytest.raises(FMICallException) as failure:
        fmu.step(0.1)
    assert failure.value.status == 2  # fmi2Discard
    assert any("m_cart = -1.0: a mass must be positive" in text for _, text in fmu.messages)
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
        rates = core.rhs(state, p)[2 * n:]
        expected = [reference[f"d{name}"][i] for name in names[2 * n:]]
        assert np.abs(rates - expected).max() < 1e-9 * max(1.0, np.abs(expected).max())
        cart_force = core.outputs(state, p)[force] - k * reference["x_cart"][i] - c * reference["v_cart"][i]
        assert m * reference["a_cart"][i] == pytest.approx(cart_force, rel=1e-9, abs=1e-9)
    assert np.abs(reference["a_cart"]).max() > 0.5  # the cart does move


def test_the_demo_command_converges_at_first_order(tmp_path):
    assert cli(["demo", "--out", str(tmp_path), "--steps", "0.1,0.05,0.025", "--stop-time", "4"]) == 0
    with open(tmp_path / "coupling_error.csv") as f:
        rows = {float(r["step_s"]): r for r in csv.DictReader(f)}
    assert sorted(rows) == [0.025, 0.05, 0.1]
    for field in ("cart_error_m", "angle_error_rad", "force_error_N"):
        errors = [float(rows[dt][field]) for dt in (0.1, 0.05, 0.025)]
        assert 1.7 < errors[0] / errors[1] < 2.3 and 1.7 < errors[1] / errors[2] < 2.3, field
    assert float(rows[0.025]["cart_error_m"]) < 0.02
    assert (tmp_path / "coupling.png").stat().st_size > 20_000


@pytest.mark.parametrize("argv, message", [
    (["--steps", "0.1,x"], "--steps: expected numbers"),
    (["--steps", "0.3", "--stop-time", "1"], "must be positive, divide --stop-time"),
    (["--steps", "0.1,0.15"], "multiple of the smallest"),
    (["--cart-mass", "-1"], "--cart-mass: must be a positive number of kg, got -1.0"),
])
def test_bad_demo_options_are_named(argv, message, capsys, tmp_path):
    assert cli(["demo", "--out", str(tmp_path / "out"), *argv]) == 2
    err = capsys.readouterr().err
    assert message in err
    assert err.startswith("conical-pendulum demo: ") and err.count("\n") == 1  # one line
    assert not (tmp_path / "out").exists()


def test_a_too_light_cart_is_reported_as_diverged(tmp_path, capsys):
    """The added-mass limit: a 2 kg cart under the 45 kg chain, explicit exchange."""
    assert cli(["demo", "--out", str(tmp_path), "--steps", "0.01", "--stop-time", "0.2", "--cart-mass", "2"]) == 0
    assert "step 0.01 s: the exchange diverged" in capsys.readouterr().out
    assert (tmp_path / "coupling.png").exists()
