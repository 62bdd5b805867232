"""The coupled demo: the monolithic reference, ecospy's co-simulation (the cart: test_cart.py)."""

import csv

import numpy as np
import pytest

from conical_pendulum.builder.compiler import load_core
from conical_pendulum.cli import main as cli
from conical_pendulum.demos.coupled import SCENE, SCHEMES
from conical_pendulum.demos.monolithic import cart_parameters, monolithic


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


@pytest.mark.tools
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
        (
            ["--steps", "0.3", "--stop-time", "1"],
            "--steps: 0.3 does not divide --stop-time 1 (1 / 0.3 = 3.333)",
        ),
        (["--steps", "0.2,0.5"], "--steps: 0.5 is not a multiple of the smallest step 0.2"),
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


@pytest.mark.tools
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
