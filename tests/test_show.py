"""Plots and the animation from an FMU run, as `conical-pendulum show` makes them."""

import itertools
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
        (["RESULTS"], "give --plot, --gif and/or --books"),
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


# ---- the pictures' design, on made-up runs of 1 to 100 links


def made_up_run(n: int, steps: int = 121) -> dict:
    """A chain swinging in the vertical plane x = -z (the seed's diagonal from above), its bobs' positions
    and angles as an FMU's CSV names them; alpha0 turns round and round (to -800 degrees)."""
    from conical_pendulum.viz import plots

    t = np.linspace(0.0, 10.0, steps)
    results = {"time": t, "energy": 1e3 * (1 + 1e-12 * np.sin(t))}
    tilt = np.radians(10.0) * np.cos(t[:, None] * (1 + np.arange(n)) / 3)
    drift = 1e-3 * np.sin(t)[:, None]  # a little out of the plane
    down = np.cumsum(np.stack([np.sin(tilt), -np.cos(tilt), drift + 0 * tilt], axis=-1) * 10.0, axis=1)
    diagonal = np.array([[1, 0, 1], [0, 1, 0], [-1, 0, 1]]) / np.array([[2**0.5], [1], [2**0.5]])
    positions = down @ diagonal.T  # x and z along the diagonal, y up
    for i in range(n):
        results[f"alpha{i}"] = tilt[:, i] - (np.radians(80.0) * t if i == 0 else 0)
        results[f"beta{i}"] = tilt[:, i] + 0.01
        for k, c in enumerate("xyz"):
            results[f"bob{i}_{c}"] = positions[:, i, k]
    assert plots.missing(results) == {}
    return results


@pytest.mark.parametrize("n", [1, 3, 10, 30, 100])
def test_the_plot_keeps_its_key_off_the_data_and_wraps_the_angles(n):
    import matplotlib.pyplot as plt

    from conical_pendulum.viz import plots

    fig = plots.figure(made_up_run(n))
    fig.canvas.draw()
    angles, side, above, drift = fig.axes[:4]
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    if n <= plots.LEGEND_LINKS:
        (legend,) = legends  # one, beside the angles, in the links' order (never alpha0, alpha1, alpha10)
        labels = [text.get_text() for text in legend.get_texts()]
        assert labels == [f"link {i}" for i in range(n)] + ["alpha (solid)", "beta (dashed)"]
        box = legend.get_window_extent()
        assert all(not box.overlaps(ax.get_window_extent()) for ax in (angles, side, above, drift))
    else:
        assert not legends and len(fig.axes) == 5  # a colour scale instead
        scale = fig.axes[4]
        assert scale.get_ylim() == (-0.5, n - 0.5) and "link" in scale.get_ylabel()
        assert all(not scale.get_window_extent().overlaps(ax.get_window_extent()) for ax in fig.axes[:4])
    low, high = angles.get_ylim()
    assert low > -200 and high < 200  # wrapped: alpha0 does not run the axis to -800 degrees
    # the swing is seen side-on (along x = -z) and, stretched, across it: not a diagonal line
    assert np.ptp(side.get_xlim()) > 10 and "stretched" in above.get_title()
    assert np.ptp(above.get_ylim()) < 0.1 * np.ptp(above.get_xlim())
    plt.close(fig)


def test_wrapping_breaks_the_line_where_the_angle_turns_round():
    from conical_pendulum.viz import plots

    times, degrees = plots.wrapped(np.array([0.0, 1.0, 2.0]), np.radians([170.0, 179.0, 190.0]))
    assert (
        np.allclose(degrees[:2], [170.0, 179.0])
        and np.isnan(degrees[2])
        and degrees[3] == pytest.approx(-170.0)
    )
    assert np.isnan(times[2]) and times[3] == 2.0


@pytest.mark.parametrize("n", [1, 3, 30, 100])
def test_the_animation_shows_the_chain_across_its_plane_with_readable_ticks(n):
    import matplotlib.pyplot as plt

    from conical_pendulum.viz import plots

    points = plots.joints(made_up_run(n))
    fig, ax, (line, bobs, _) = plots.chain_figure(points)
    fig.canvas.draw()
    along = plots.swing_plane(points)
    assert abs(abs(along @ np.array([1, -1]) / 2**0.5) - 1) < 1e-3  # the plane x = z (plot y = -inertial z)
    assert abs(ax.azim - np.degrees(np.arctan2(along[0], -along[1]))) < 1e-6  # looked at across it
    assert bobs.get_markersize() <= max(1.0, 24 / n) and bobs.get_markersize() < 3 * line.get_linewidth() + 1
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        boxes = [label.get_window_extent() for label in axis.get_ticklabels() if label.get_text()]
        assert not any(a.overlaps(b) for a, b in itertools.combinations(boxes, 2))
    plt.close(fig)


def test_angles_that_overlap_in_pairs_say_so():
    """The seed's alpha_i and beta_i stay within half a degree: the title says so, where
    curves that overlap in pairs would otherwise look like half of them missing."""
    import matplotlib.pyplot as plt

    from conical_pendulum.viz import plots

    run = made_up_run(3)
    assert plots.figure(run).axes[0].get_title() == "joint angles"  # alpha0 turns round, beta0 does not
    run["alpha0"] = run["beta0"] - 0.01
    assert plots.figure(run).axes[0].get_title() == "joint angles (each beta within 0.57 deg of its alpha)"
    plt.close("all")
