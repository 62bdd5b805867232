"""pydy.viz's page (the seed's viewer) fed with the FMU's trajectories."""

import json

import numpy as np
import pytest

from conical_pendulum import Link, Scene
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.viz.pydy_page import PREFIX, write_pydy_page
from required_tools import require_tool


def test_the_page_carries_the_fmu_trajectories(seed_fmu, tmp_path):
    run = run_fmu(
        seed_fmu, stop_time=1.0, output_interval=1 / 60, start_values={"alpha0": 1.0, "delta2": 2.0}
    )
    results = {name: run[name] for name in run.dtype.names}
    folder, address = write_pydy_page(Scene.uniform(3), results, tmp_path)
    assert (folder / "index.html").exists() and address.endswith(f"?load={PREFIX}_scene_desc.json")
    description = json.loads((folder / f"{PREFIX}_scene_desc.json").read_text())
    data = json.loads((folder / f"{PREFIX}_simulation_data.json").read_text())
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
        np.testing.assert_allclose(
            rotation @ rotation.transpose(0, 2, 1), np.broadcast_to(np.eye(3), rotation.shape), atol=1e-12
        )


def test_a_scene_without_bobs_draws_only_links(seed_fmu, tmp_path, built_fmu):
    scene = Scene(links=(Link(has_bob=False), Link(has_bob=False)))
    path = built_fmu(scene)
    run = run_fmu(path, stop_time=0.2, output_interval=0.05)
    folder, _ = write_pydy_page(scene, {n: run[n] for n in run.dtype.names}, tmp_path)
    description = json.loads((folder / f"{PREFIX}_scene_desc.json").read_text())
    assert sorted(o["name"] for o in description["objects"].values()) == ["link0", "link1"]


def test_uneven_times_are_refused(tmp_path):
    scene = Scene.uniform(1)
    results = {name: np.zeros(3) for name in scene.state_names()}
    results["time"] = np.array([0.0, 0.1, 0.3])
    with pytest.raises(ValueError, match="uniform time grid"):
        write_pydy_page(scene, results, tmp_path)


@pytest.mark.tools
def test_the_page_plays_in_headless_chromium(seed_fmu, tmp_path):
    """Served on localhost, loaded in Debian's chromium through chromedriver (.ci/run
    installs both): no JavaScript errors, and the first frame, as loaded, shows the whole
    chain: three red links and three blue bobs, each apart, inside the canvas and not specks."""
    import functools
    import http.server
    import threading
    import time

    from PIL import Image
    from scipy import ndimage
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    browser = require_tool("chromium", None, "Debian's chromium (.ci/run installs it)")
    driver_path = require_tool("chromedriver", None, "Debian's chromium-driver (.ci/run installs it)")
    run = run_fmu(seed_fmu, stop_time=1.0, output_interval=1 / 60, start_values={"alpha0": 1.0})
    folder, address = write_pydy_page(Scene.uniform(3), {n: run[n] for n in run.dtype.names}, tmp_path)
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    options = webdriver.ChromeOptions()
    options.binary_location = browser
    for flag in [
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--use-gl=swiftshader",
        "--enable-unsafe-swiftshader",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--window-size=1000,800",
        f"--user-data-dir={tmp_path / 'profile'}",
    ]:
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(driver_path), options=options)
    try:
        driver.set_page_load_timeout(30)
        driver.get(f"http://127.0.0.1:{server.server_address[1]}/{address}")
        canvas = None
        for _ in range(50):
            messages = " ".join(entry["message"] for entry in driver.get_log("browser"))
            if "Created Time Array" in messages:  # pydy loaded both JSON files
                canvas = driver.find_element("tag name", "canvas")
                break
            time.sleep(0.2)
        assert canvas is not None, "pydy never loaded the simulation data"
        shot = tmp_path / "page.png"
        driver.save_screenshot(str(shot))
        errors = [
            entry["message"]
            for entry in driver.get_log("browser")
            if entry["level"] == "SEVERE"
            and not any(benign in entry["message"] for benign in ("favicon.ico", "/fonts/"))
        ]
        box = canvas.rect
    finally:
        driver.quit()
        server.shutdown()
    assert errors == []
    pixels = np.asarray(Image.open(shot).convert("RGB"), dtype=int)
    inside = pixels[
        int(box["y"]) : int(box["y"] + box["height"]), int(box["x"]) : int(box["x"] + box["width"])
    ]
    # pydy's Lambert shading draws links in shades of pure red (k, 0, 0) and bobs in shades
    # of pure blue (0, 0, k) on a grey (155, 155, 151) background. The axes' 1-pixel lines
    # (red to orange along x, from the pivot to beyond the canvas) go with an opening.
    r, g, b = np.moveaxis(inside, -1, 0)
    for colour, mask, count, smallest in [
        ("red", r - np.maximum(g, b) > 50, 3, 60),
        ("blue", b - np.maximum(r, g) > 50, 3, 30),
    ]:
        labels, found = ndimage.label(ndimage.binary_opening(mask, np.ones((3, 3))))
        assert found == count, f"{found} {colour} blobs, expected {count}"  # each apart, none hidden
        for where in ndimage.find_objects(labels):
            rows, cols = where
            assert rows.start > 0 and rows.stop < inside.shape[0], f"a {colour} blob at the canvas's edge"
            assert cols.start > 0 and cols.stop < inside.shape[1], f"a {colour} blob at the canvas's edge"
        sizes = ndimage.sum_labels(np.ones_like(labels), labels, range(1, found + 1))
        assert sizes.min() >= smallest, f"{colour} blobs of {sizes} pixels: the chain is too far away"
