"""pydy.viz's page (the seed's viewer) fed with the FMU's trajectories."""
import json

import numpy as np
import pytest

from conical_pendulum import Link, Scene
from conical_pendulum.check import run_fmu
from conical_pendulum.pydy_viz import PREFIX, write_pydy_page


def test_the_page_carries_the_fmu_trajectories(seed_fmu, tmp_path):
    run = run_fmu(seed_fmu, stop_time=1.0, output_interval=1 / 60,
                  start_values={"alpha0": 1.0, "delta2": 2.0})
    results = {name: run[name] for name in run.dtype.names}
    address = write_pydy_page(Scene.uniform(3), results, tmp_path)
    page = tmp_path / address.split("?")[0]
    assert page.exists() and address.endswith(f"?load={PREFIX}_scene_desc.json")
    description = json.loads((page.parent / f"{PREFIX}_scene_desc.json").read_text())
    data = json.loads((page.parent / f"{PREFIX}_simulation_data.json").read_text())
    assert description["timeSteps"] == len(run["time"])
    assert description["timeDelta"] == pytest.approx(1 / 60)
    shapes = {obj["name"]: (obj["type"], key) for key, obj in description["objects"].items()}
    assert set(shapes) == {"link0", "link1", "link2", "bob0", "bob1", "bob2"}
    for name, (kind, key) in shapes.items():
        assert kind == ("Cylinder" if name.startswith("link") else "Sphere")
        matrices = np.array(data[key])  # a column-major 4x4 per step
        assert matrices.shape == (len(run["time"]), 16)
        where = np.column_stack([run[f"{name}_{c}"] for c in "xyz"])
        np.testing.assert_allclose(matrices[:, 12:15], where, rtol=0, atol=1e-9)
        rotation = matrices[:, [0, 1, 2, 4, 5, 6, 8, 9, 10]].reshape(-1, 3, 3)
        np.testing.assert_allclose(rotation @ rotation.transpose(0, 2, 1),
                                   np.broadcast_to(np.eye(3), rotation.shape), atol=1e-12)


def test_a_scene_without_bobs_draws_only_links(seed_fmu, tmp_path, fmu_dir):
    from conical_pendulum.fmu import build_fmu

    scene = Scene(links=(Link(has_bob=False), Link(has_bob=False)))
    path = build_fmu(scene, fmu_dir / "NoBobs.fmu").path
    run = run_fmu(path, stop_time=0.2, output_interval=0.05)
    address = write_pydy_page(scene, {n: run[n] for n in run.dtype.names}, tmp_path)
    description = json.loads((tmp_path / address.split("?")[0]).parent.joinpath(
        f"{PREFIX}_scene_desc.json").read_text())
    assert sorted(o["name"] for o in description["objects"].values()) == ["link0", "link1"]


def test_uneven_times_are_refused(tmp_path):
    scene = Scene.uniform(1)
    results = {name: np.zeros(3) for name in scene.state_names()}
    results["time"] = np.array([0.0, 0.1, 0.3])
    with pytest.raises(ValueError, match="uniform time grid"):
        write_pydy_page(scene, results, tmp_path)
