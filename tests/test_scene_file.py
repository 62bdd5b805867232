"""Scene files: what a user writes decides the equations, the variables and their start values."""

import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest

from conical_pendulum import Link, Scene, SceneError
from conical_pendulum.scene import load_scene

ROOT = Path(__file__).resolve().parent.parent


def variables(path):
    with zipfile.ZipFile(path) as archive:
        root = ET.fromstring(archive.read("modelDescription.xml"))
    return {v.get("name"): v for v in root.iter("ScalarVariable")}


def test_the_example_file_is_the_seed_scene():
    scene = load_scene(ROOT / "scenes" / "seed.toml")
    seed = Scene.uniform(3)
    assert scene.cache_fields() == seed.cache_fields()
    assert scene.parameter_defaults() == seed.parameter_defaults()


def test_a_scene_file_decides_equations_variables_and_starts(tmp_path, built_fmu):
    path = tmp_path / "two.toml"
    path.write_text("""
gravity = 3.7
outputs = ["energy"]
coupling = true

[[link]]
length = 2.0
mass = 0
bob = { mass = 1.5 }

[[link]]
length = 0.5
mass = 3.0
radius = 0.1
inertia = [0.07, 0.015, 0.07]
""")
    scene = load_scene(path)
    assert scene.links == (
        Link(has_mass=False, length=2.0, bob_mass=1.5),
        Link(has_bob=False, length=0.5, mass=3.0, radius=0.1, moments=(0.07, 0.015, 0.07)),
    )
    built = variables(built_fmu(scene))
    assert {"M0", "Ixx0", "m1", "bob0_x", "link0_qw"}.isdisjoint(built)
    starts = {
        name: float(built[name].find("Real").get("start"))
        for name in ["l0", "m0", "l1", "M1", "Ixx1", "Iyy1", "g"]
    }
    assert starts == {"l0": 2.0, "m0": 1.5, "l1": 0.5, "M1": 3.0, "Ixx1": 0.07, "Iyy1": 0.015, "g": 3.7}
    assert built["energy"].get("causality") == "output"
    assert built["a_pivot_y"].get("causality") == "input" and "F_pivot_y" in built


@pytest.mark.parametrize(
    "text, message",
    [
        ("", "link: give one [[link]] table per link"),
        ("[[link]]\nlenght = 3.0", "link[0]: unknown field(s) ['lenght']"),
        ("[[link]]\nlength = -3.0", "link[0].length: must be a positive finite number, got -3.0"),
        ("[[link]]\nmass = -1", "link[0].mass: must be a positive finite number (or 0 for a massless link"),
        ("[[link]]\nbob = { mass = 0 }", "link[0].bob.mass: must be a positive finite number, got 0"),
        ("[[link]]\nbob = 5.0", "link[0].bob: expected a table"),
        ("[[link]]\ninertia = [1.0, -2.0, 1.0]", "link[0].inertia: must be three finite numbers >= 0"),
        ("[[link]]\nmass = 0", "scene has no mass"),
        ('kinematics = "seed"\n[[link]]', "kinematics: 'seed' is not one of"),
        ('outputs = ["bobz"]\n[[link]]', "outputs: unknown group(s) ['bobz']"),
        ('gravity = "down"\n[[link]]', "gravity: expected a number"),
        ('coupling = "yes"\n[[link]]', "coupling: expected true or false, got 'yes'"),
        ("[[link]\nlength = 1", "Expected ']]' at the end of an array declaration (at line 1"),
    ],
)
def test_a_bad_scene_file_names_the_field(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as failure:
        load_scene(path)
    assert message in str(failure.value)
    assert "bad.toml" in str(failure.value)


def test_a_missing_or_foreign_file_is_named(tmp_path):
    with pytest.raises(SceneError, match="No such file"):
        load_scene(tmp_path / "nowhere.toml")
    (tmp_path / "scene.yaml").write_text("link: []")
    with pytest.raises(SceneError, match=r"expected a \.toml or \.json file"):
        load_scene(tmp_path / "scene.yaml")
