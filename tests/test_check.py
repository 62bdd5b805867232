"""The check's bound (analysis/compare.py): measured from the reference's own error and what
the FMU's tolerance allows, so long chains pass, and tight enough that a wrong FMU fails."""

import pytest

from conical_pendulum import Link, Scene
from conical_pendulum.analysis import compare as comparison
from conical_pendulum.analysis import simulate


def test_the_seed_passes_with_a_bound_made_of_both_errors(seed_fmu):
    result = comparison.compare(seed_fmu, Scene.uniform(3))
    bound = result.bound
    assert result.passed()
    # at the FMU's rtol 1e-12 the settings' error is the two references' difference, the
    # reference's own a tenth of it; both far below the old fixed 1e-8 rad
    assert bound.tolerance == 1e-12 and bound.measured
    assert bound.reference_error == pytest.approx(bound.settings_error / 10)
    assert 1e-13 < bound.settings_error < 1e-10
    assert bound.value == pytest.approx(comparison.SAFETY * 1.1 * bound.settings_error)
    assert result.angle_error() < bound.value / 4  # with room to spare
    assert "DOP853's error at the FMU's rtol 1e-12" in bound.describe()


def test_a_loose_fmu_is_judged_by_what_its_tolerance_allows(seed_fmu):
    """rtol 1e-3: the bound is DOP853's own error at 1e-3 (measured, about 2.5e-3 rad), not
    the tight one's, and the FMU's run stays within it."""
    result = comparison.compare(seed_fmu, Scene.uniform(3), output_interval=1.0, rtol=1e-3, atol=1e-3)
    assert result.bound.tolerance == 1e-3 and result.bound.measured
    assert 1e-4 < result.bound.settings_error < 1e-1
    assert 1e-5 < result.angle_error() <= result.bound.value and result.passed()


def test_an_fmu_built_with_another_parameter_value_fails(seed_fmu):
    """The FMU's first link 1e-9 longer or shorter, relatively, than the scene says: 6e-10 rad,
    which a fixed 1e-8 rad let through, is 40 times the seed's bound."""
    scene = Scene(links=(Link(length=10.0 * (1 + 1e-9)), Link(), Link()))
    result = comparison.compare(seed_fmu, scene)
    assert not result.passed()
    assert result.angle_error() > 10 * result.bound.value


class Broken:
    """A core whose right-hand side is off by a part in 1e10: what a broken build would give."""

    def __init__(self, core):
        self.core = core

    def rhs(self, x, p):
        return self.core.rhs(x, p) * (1 + 1e-10)

    def __getattr__(self, name):
        return getattr(self.core, name)


def test_an_fmu_whose_core_differs_from_the_model_fails(seed_fmu, monkeypatch):
    load_core = simulate.load_core
    monkeypatch.setattr(simulate, "load_core", lambda scene: Broken(load_core(scene)))
    result = comparison.compare(seed_fmu, Scene.uniform(3))
    assert not result.passed()
    assert result.angle_error() > 10 * result.bound.value


def test_a_nan_fails():
    bound = comparison.Bound(1e-12, 1e-12, 1e-13)
    result = comparison.Comparison(["alpha0"], [float("nan")], 0.0, None, bound)
    assert not result.passed()


@pytest.mark.slow
def test_a_long_chain_passes(chain_fmu):
    """30 links, 10 s: chaotic, so the two references differ by about 1e-7 rad and the FMU by
    6e-8 from the tighter one; a fixed 1e-8 rad failed it."""
    result = comparison.compare(chain_fmu(30), Scene.uniform(30))
    assert result.passed(), result.bound.describe()
    assert result.bound.settings_error > 1e-9  # the chain's error really is that large
