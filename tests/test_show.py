"""Plots and the animation from an FMU run, as `conical-pendulum show` makes them."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy.util import write_csv
from PIL import Image

from conical_pendulum.analysis.fmpy_runs import run_fmu


@pytest.fixture(scope="module")
def results_csv(seed_fmu, tmp_path_factory):
    path = tmp_path_factory.mktemp("show") / "results.csv"
    write_csv(
        str(path),
        run_fmu(seed_fmu, stop_time=1.0, output_interval=1 / 60, start_values={"alpha0": 1.0, "delta2": 2.0}),
    )
    return path


def show(*args):
    return subprocess.run(
        [str(Path(sys.executable).with_name("conical-pendulum")), "show", *map(str, args)],
        check=False,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_plot_and_animation(results_csv, tmp_path):
    png, gif = tmp_path / "p.png", tmp_path / "p.gif"
    run = show(results_csv, "--plot", png, "--gif", gif, "--fps", "20")
    assert run.returncode == 0, run.stderr
    assert "rendering" in run.stderr and "21/21" in run.stderr  # the progress bar
    picture = np.asarray(Image.open(png).convert("L"))
    assert picture.std() > 10  # axes and curves, not a blank page
    animation = Image.open(gif)
    assert animation.n_frames == 21  # 1 s at 20 frames per second, both ends
    frames = []
    for k in (0, 20):
        animation.seek(k)
        frames.append(np.asarray(animation.convert("L"), dtype=float))
    assert frames[0].std() > 10
    assert np.abs(frames[0] - frames[1]).mean() > 0.1  # the chain moved


@pytest.mark.parametrize(
    "args, message",
    [
        (["missing.csv", "--plot", "x.png"], "missing.csv"),
        (["RESULTS"], "give --plot and/or --gif"),
    ],
)
def test_refusals(results_csv, args, message):
    run = show(*[results_csv if a == "RESULTS" else a for a in args])
    assert run.returncode == 2
    assert message in run.stderr
    assert run.stderr.startswith("conical-pendulum show: ") and run.stderr.count("\n") == 1  # one line
    assert "Traceback" not in run.stderr


def test_results_without_positions_give_what_they_can_and_say_what_they_left_out(tmp_path, seed_fmu):
    """Angles only: the plot of the angles, without paths and energy drift, and no animation."""
    path = tmp_path / "state.csv"
    write_csv(
        str(path),
        run_fmu(seed_fmu, stop_time=0.1, output=["alpha0", "beta0", "alpha1", "beta1", "alpha2", "beta2"]),
    )
    png, gif = tmp_path / "p.png", tmp_path / "p.gif"
    run = show(path, "--plot", png, "--gif", gif)
    assert run.returncode == 0, run.stderr
    assert run.stdout.splitlines() == [
        f"wrote {png}",
        "left out the paths and the animation: the results have neither link poses (link<i>_x/y/z, "
        "the scene's output 'poses') nor a bob on every link (bob<i>_x/y/z); "
        "the energy drift: the results have no energy output",
    ]
    assert np.asarray(Image.open(png).convert("L")).std() > 10 and not gif.exists()
    assert run.stderr == ""
    run = show(path, "--gif", gif)  # what is left out is only what was asked for
    assert run.returncode == 0 and run.stdout.startswith("left out the animation: the results have neither")
