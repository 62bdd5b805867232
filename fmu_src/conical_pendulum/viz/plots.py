"""Plots and an animation of simulation results, with matplotlib.

    conical-pendulum show dist/results.csv --plot dist/pendulum.png --gif dist/pendulum.gif

The CSV is fmpy's (`fmpy.util.write_csv`): a `time` column and one per variable. Links
are drawn from their mass-centre positions (`link<i>_x/y/z`, the midpoint of each link),
or from the bob positions when the scene has a bob on every link. Results with neither
still give the angles and the energy: `missing` says what they cannot give, and why.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ..errors import UserError
from ..progress import WIDTH, bar

NO_CHAIN = (
    "the results have neither link poses (link<i>_x/y/z, the scene's output 'poses') "
    "nor a bob on every link (bob<i>_x/y/z)"
)
NO_ENERGY = "the results have no energy output"


def load_results(path) -> dict[str, np.ndarray]:
    """Columns of an fmpy results CSV by name, read with fmpy's own reader."""
    from fmpy.util import read_csv

    path = Path(path)
    try:
        data = read_csv(path)
    except OSError as exc:
        raise UserError(f"{path}: {exc.strerror or exc}") from None
    except (IndexError, ValueError):  # empty, a header alone, not numbers, or not text
        data = None
    if data is None or data.dtype.names is None or "time" not in data.dtype.names:
        raise UserError(f"{path}: expected fmpy's CSV with a 'time' column")
    return {name: data[name] for name in data.dtype.names}


def _chain_outputs(results: dict) -> str | None:
    """What the chain is drawn from: "link" (poses), "bob" (a bob on every link) or None."""
    n = sum(1 for name in results if name.startswith("alpha"))
    for prefix in ("link", "bob"):
        if all(f"{prefix}{i}_x" in results for i in range(n)):
            return prefix
    return None


def missing(results: dict) -> dict[str, str]:
    """What of the plot and the animation these results cannot give, each with why:
    the paths and the animation need the chain's positions, the energy drift the energy."""
    lacking = {}
    if _chain_outputs(results) is None:
        lacking["the paths"] = lacking["the animation"] = NO_CHAIN
    if "energy" not in results:
        lacking["the energy drift"] = NO_ENERGY
    return lacking


def left_out(lacking: dict[str, str]) -> str:
    """One line saying what was left out and why, from (a selection of) missing()."""
    by_reason: dict[str, list[str]] = {}
    for what, why in lacking.items():
        by_reason.setdefault(why, []).append(what)
    return "left out " + "; ".join(f"{' and '.join(whats)}: {why}" for why, whats in by_reason.items())


def joints(results: dict) -> np.ndarray:
    """Joint positions (time, joint, xyz) from the pivot down, in plot axes (x, z, y up).
    UserError when the results have neither link poses nor a bob on every link."""
    n = sum(1 for name in results if name.startswith("alpha"))
    count = len(results["time"])
    points = np.zeros((count, n + 1, 3))
    source = _chain_outputs(results)
    if source is None:
        raise UserError(f"cannot draw the chain: {NO_CHAIN}")
    for i in range(n):
        where = np.column_stack([results[f"{source}{i}_{c}"] for c in "xyz"])
        # a link's pose is its mass centre, the midpoint between its joints
        points[:, i + 1] = 2 * where - points[:, i] if source == "link" else where
    return points[:, :, [0, 2, 1]]  # inertial Y is up: draw it as the plot's z


def plot(results: dict, path) -> None:
    """Angles, paths from above and energy drift; a panel the results cannot give (missing())
    says so instead."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = results["time"]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    for name in sorted(k for k in results if k.rstrip("0123456789") in ("alpha", "beta")):
        axes[0].plot(t, np.degrees(results[name]), label=name)
    axes[0].set(xlabel="time [s]", ylabel="angle [deg]", title="joint angles")
    axes[0].legend(fontsize=7, ncol=2)
    if _chain_outputs(results) is None:
        axes[1].set_axis_off()
        axes[1].text(0.5, 0.5, "no link poses or bobs on every link", ha="center")
    else:
        points = joints(results)
        for i in range(1, points.shape[1]):
            axes[1].plot(points[:, i, 0], points[:, i, 1], label=f"end of link {i - 1}")
        axes[1].set(xlabel="x [m]", ylabel="z [m]", title="paths seen from above")
        axes[1].set_aspect("equal", adjustable="datalim")
        axes[1].legend(fontsize=7)
    if "energy" in results:
        energy = results["energy"]
        axes[2].plot(t, (energy - energy[0]) / abs(energy[0]))
        axes[2].set(xlabel="time [s]", ylabel="(E - E0) / |E0|", title="energy drift")
    else:
        axes[2].set_axis_off()
        axes[2].text(0.5, 0.5, "no energy output", ha="center")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def animate(results: dict, path, fps: float = 30.0, size: float = 5.0) -> float:
    """A GIF of the chain from above and aside, at about `fps` frames per simulated second.

    Returns the seconds it took; prints a progress bar to stderr. UserError when the
    results cannot draw the chain (missing()).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter

    points = joints(results)  # before matplotlib's work: these results may not have the chain
    start = time.perf_counter()
    t = results["time"]
    duration = t[-1] - t[0]
    frames = np.unique(np.searchsorted(t, np.arange(t[0], t[-1] + 1e-12, 1.0 / fps)).clip(0, len(t) - 1))
    reach = np.abs(points).max() * 1.05 or 1.0
    fig = plt.figure(figsize=(size, size))
    ax = fig.add_subplot(projection="3d")
    ax.set(
        xlim=(-reach, reach),
        ylim=(-reach, reach),
        zlim=(-reach, 0.25 * reach),
        xlabel="x [m]",
        ylabel="z [m]",
        zlabel="y (up) [m]",
    )
    ax.view_init(elev=10, azim=-60)
    ax.plot([0], [0], [0], "ks", markersize=6)
    (line,) = ax.plot([], [], [], "-", color="tab:red", linewidth=3)
    (bobs,) = ax.plot([], [], [], "o", color="tab:blue", markersize=8)
    (trail,) = ax.plot([], [], [], "-", color="tab:blue", linewidth=0.8, alpha=0.5)
    label = ax.text2D(0.02, 0.95, "", transform=ax.transAxes)

    def draw(k):
        p = points[k]
        line.set_data_3d(p[:, 0], p[:, 1], p[:, 2])
        bobs.set_data_3d(p[1:, 0], p[1:, 1], p[1:, 2])
        tail = points[max(0, k - int(len(t) * 2 / max(duration, 1e-9))) : k + 1, -1]
        trail.set_data_3d(tail[:, 0], tail[:, 1], tail[:, 2])
        label.set_text(f"t = {t[k]:6.2f} s")
        return line, bobs, trail, label

    def progress(i, total):  # redrawn when a # more shows, and at the end
        if i + 1 == total or WIDTH * (i + 1) // total != WIDTH * i // total:
            bar(i + 1, total, f"  rendering {path}")

    animation = FuncAnimation(fig, draw, frames=frames, blit=False)
    animation.save(path, writer=PillowWriter(fps=fps), progress_callback=progress)
    plt.close(fig)
    return time.perf_counter() - start
