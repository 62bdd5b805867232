"""Plots and an animation of simulation results, with matplotlib.

    conical-pendulum show dist/ConicalPendulum.csv --plot seed.png --gif seed.gif

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
from ..progress import Bar
from ..scene import WORKS

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


LEGEND_LINKS = 6  # up to this many links, a legend beside the axes; beyond, a colour scale
SNAPSHOTS = 5  # chains drawn faintly in the side view, evenly over the run


def _link_names(results: dict) -> list[int]:
    """The links' numbers in order (0 at the pivot), from the alpha<i> columns: never sorted as text."""
    return sorted(int(name[5:]) for name in results if name.startswith("alpha") and name[5:].isdigit())


def _colours(n: int):
    """A colour per link: distinct ones for a legend, or a scale from the pivot to the tip."""
    import matplotlib

    if n <= LEGEND_LINKS:
        return [matplotlib.colormaps["tab10"](i) for i in range(n)]
    scale = matplotlib.colormaps["viridis"]
    return [scale(i / (n - 1)) for i in range(n)]


def wrapped(t: np.ndarray, angle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Times and the angle in degrees wrapped to [-180, 180), with a NaN where it wraps, so
    that a link turning round draws no line across the axes (nor runs them to -800)."""
    degrees = (np.degrees(angle) + 180.0) % 360.0 - 180.0
    breaks = np.flatnonzero(np.abs(np.diff(degrees)) > 180.0) + 1
    return np.insert(np.asarray(t, dtype=float), breaks, np.nan), np.insert(degrees, breaks, np.nan)


def swing_plane(points: np.ndarray) -> np.ndarray:
    """The horizontal unit vector (plot x, y) along which the joints move most (principal
    axis of their horizontal positions): the seed swings in one vertical plane, which seen
    from above is a line, so the plot looks at that plane side-on and across it."""
    horizontal = points[:, 1:, :2].reshape(-1, 2)
    horizontal = horizontal - horizontal.mean(axis=0)
    if not np.any(horizontal):
        return np.array([1.0, 0.0])
    _, _, axes = np.linalg.svd(horizontal, full_matrices=False)
    along = axes[0]
    return along if along[np.argmax(np.abs(along))] > 0 else -along


def _link_key(fig, axes, colours, styles: bool) -> None:
    """Which colour is which link: a legend outside `axes` (few links) or a colour scale
    beside the whole figure (many)."""
    import matplotlib
    from matplotlib.lines import Line2D

    n = len(colours)
    if n <= LEGEND_LINKS:
        handles = [Line2D([], [], color=c, label=f"link {i}") for i, c in enumerate(colours)]
        if styles:
            handles += [
                Line2D([], [], color="0.3", label="alpha (solid)"),
                Line2D([], [], color="0.3", linestyle="--", label="beta (dashed)"),
            ]
        axes.legend(
            handles=handles, fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0
        )
    else:
        scale = matplotlib.cm.ScalarMappable(
            norm=matplotlib.colors.Normalize(-0.5, n - 0.5), cmap=matplotlib.colormaps["viridis"]
        )
        bar = fig.colorbar(scale, ax=fig.axes, pad=0.01, shrink=0.6, aspect=30)
        bar.set_label("link (0 at the pivot)" + ("; alpha solid, beta dashed" if styles else ""))


def plot(results: dict, path) -> None:
    """The figure (figure()) as a PNG."""
    import matplotlib.pyplot as plt

    fig = figure(results)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def figure(results: dict):
    """Joint angles (wrapped to +-180 degrees), the chain side-on in its plane of swing with
    its joints' paths, the paths seen from above across that plane, and the energy drift;
    links told apart by a legend beside the axes or, beyond LEGEND_LINKS, a colour scale.
    A panel the results cannot give (missing()) says so instead."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = results["time"]
    links = _link_names(results)
    colours = _colours(len(links))
    fig, axes = plt.subplots(2, 2, figsize=(13, 8.5), layout="constrained")
    (angles, side), (above, drift) = axes
    width = 1.2 if len(links) <= 10 else 0.7
    for i, colour in zip(links, colours):
        for name, style in ((f"alpha{i}", "-"), (f"beta{i}", "--")):
            if name in results:
                angles.plot(*wrapped(t, results[name]), style, color=colour, lw=width)
    apart = max(
        (
            np.abs((np.degrees(results[f"beta{i}"] - results[f"alpha{i}"]) + 180.0) % 360.0 - 180.0).max()
            for i in links
            if f"beta{i}" in results
        ),
        default=np.inf,
    )
    angles.set(
        xlabel="time [s]",
        ylabel="angle [deg], wrapped to [-180, 180)",
        # curves that overlap in pairs say why: the seed's links stay near one vertical plane
        title="joint angles" + (f" (each beta within {apart:.2g} deg of its alpha)" if apart < 2.0 else ""),
    )
    _link_key(fig, angles, colours, styles=True)
    if _chain_outputs(results) is None:
        for ax in (side, above):
            ax.set_axis_off()
            ax.text(0.5, 0.5, "no link poses or bobs on every link", ha="center", transform=ax.transAxes)
    else:
        points = joints(results)
        along = swing_plane(points)
        across = np.array([-along[1], along[0]])
        s, c, height = points[..., :2] @ along, points[..., :2] @ across, points[..., 2]
        for i, colour in enumerate(colours):
            side.plot(s[:, i + 1], height[:, i + 1], color=colour, lw=width, alpha=0.7)
            above.plot(s[:, i + 1], c[:, i + 1], color=colour, lw=width)
        for k in np.linspace(0, len(t) - 1, SNAPSHOTS).round().astype(int):  # over the paths
            side.plot(s[k], height[k], "-", color="black", lw=1.0, alpha=0.6)
        side.plot([0], [0], "ks", markersize=5)
        side.set(
            xlabel="along the plane of swing [m]",
            ylabel="height [m]",
            title=f"side-on: the joints' paths, and the chain at {SNAPSHOTS} times",
        )
        side.set_aspect("equal", adjustable="datalim")
        spread = np.ptp(c[:, 1:]), np.ptp(s[:, 1:])
        stretched = spread[0] < spread[1] / 5  # a (nearly) planar swing: across it drawn larger
        above.set(
            xlabel="along the plane of swing [m]",
            ylabel="across it [m]",
            title="from above" + (", across the plane stretched" if stretched else ""),
        )
        if not stretched:
            above.set_aspect("equal", adjustable="datalim")
    if "energy" in results:
        drift.plot(t, books_drift(results))
        works = [name for name in WORKS if name in results]
        drift.set(
            xlabel="time [s]",
            ylabel="(B - B0) / |E0|, B = E" + "".join(f" - {name}" for name in works),
            title="energy drift" + (", less the forces' work (the energy's books)" if works else ""),
        )
    else:
        drift.set_axis_off()
        drift.text(0.5, 0.5, "no energy output", ha="center", transform=drift.transAxes)
    return fig


def books(results: dict, path) -> None:
    """The energy's books of a run as a PNG: the energy, the work of each force the results
    keep books of (W_damping, W_external, W_pivot), and the energy less that work, which
    stays constant; below, its drift (books_drift)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    works = [name for name in WORKS if name in results]
    if "energy" not in results or not works:
        raise UserError("results: the energy's books need the energy and a W_ output (a scene with forces)")
    t, energy = results["time"], results["energy"]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 7), sharex=True, height_ratios=(3, 1))
    top.plot(t, energy - energy[0], label="energy E - E0", lw=1.6)
    for name in works:
        top.plot(t, results[name], label=f"{name} (work done on the chain)", lw=1.2)
    kept = energy - sum(results[name] for name in works)
    top.plot(t, kept - kept[0], "k--", label="E - " + " - ".join(works) + " (less its start)", lw=1.2)
    top.set(ylabel="[J]", title="the energy's books")
    top.legend(fontsize=8)
    bottom.plot(t, books_drift(results), "k", lw=0.8)
    bottom.set(xlabel="time [s]", ylabel="drift / |E0|")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def books_drift(results) -> np.ndarray:
    """(B - B0) / |E0| with B the energy less the work of the forces the results keep books of
    (W_damping, ...): constant to the solver's accuracy, where the energy alone is not."""
    books = results["energy"] - sum((results[name] for name in WORKS if name in results), 0.0)
    return (books - books[0]) / abs(results["energy"][0])


def chain_figure(points: np.ndarray, size: float = 5.0):
    """The animation's 3D axes for joints `points` (time, joint, xyz): (figure, axes, (the
    chain's line, its joints' markers, the tip's trail)), all empty."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    n = points.shape[1] - 1
    low, high = points[..., 2].min(), max(points[..., 2].max(), 0.0)
    margin = 0.05 * (high - low) or 1.0
    # true proportions, the box no narrower than 0.7 of its height: a hanging chain fills the frame
    horizontal = max(np.abs(points[..., :2]).max() * 1.05, 0.35 * (high - low + 2 * margin)) or 1.0
    fig = plt.figure(figsize=(size, size))
    fig.subplots_adjust(left=0, right=1, bottom=0, top=1)
    ax = fig.add_subplot(projection="3d")
    ax.set(
        xlim=(-horizontal, horizontal),
        ylim=(-horizontal, horizontal),
        zlim=(low - margin, high + margin),
        xlabel="x [m]",
        ylabel="z [m]",
        zlabel="y (up) [m]",
    )
    ax.set_box_aspect((2 * horizontal, 2 * horizontal, high - low + 2 * margin), zoom=0.85)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(4))
    ax.tick_params(labelsize=7)
    across = swing_plane(points) @ np.array([[0.0, 1.0], [-1.0, 0.0]])  # turned a quarter
    ax.view_init(elev=15, azim=np.degrees(np.arctan2(across[1], across[0])))
    ax.plot([0], [0], [0], "ks", markersize=6)
    (line,) = ax.plot([], [], [], "-", color="0.15", linewidth=2 if n <= 30 else 1.2)
    (bobs,) = ax.plot(
        [],
        [],
        [],
        "o",
        color="tab:red",
        alpha=0.8,
        markersize=float(np.clip(24 / n, 1.0, 6.0)),
        markeredgewidth=0,
    )
    (trail,) = ax.plot([], [], [], "-", color="tab:blue", linewidth=1.0, alpha=0.8)
    return fig, ax, (line, bobs, trail)


def animate(results: dict, path, fps: float = 30.0, size: float = 5.0) -> float:
    """A GIF of the chain in 3D, seen slightly from above and across its plane of swing
    (swing_plane), at about `fps` frames per simulated second: the chain a dark line, its
    joints' markers shrinking with the number of links so they never hide it, the tip's
    last two seconds as a trail, the box in the chain's true proportions.

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
    fig, ax, (line, bobs, trail) = chain_figure(points, size)
    label = ax.text2D(0.02, 0.95, "", transform=ax.transAxes)

    def draw(k):
        p = points[k]
        line.set_data_3d(p[:, 0], p[:, 1], p[:, 2])
        bobs.set_data_3d(p[1:, 0], p[1:, 1], p[1:, 2])
        tail = points[max(0, k - int(len(t) * 2 / max(duration, 1e-9))) : k + 1, -1]
        trail.set_data_3d(tail[:, 0], tail[:, 1], tail[:, 2])
        label.set_text(f"t = {t[k]:6.2f} s")
        return line, bobs, trail, label

    rendering = Bar(len(frames), f"  rendering {path}")

    def progress(i, total):
        rendering.update(i + 1)

    animation = FuncAnimation(fig, draw, frames=frames, blit=False)
    animation.save(path, writer=PillowWriter(fps=fps), progress_callback=progress)
    plt.close(fig)
    return time.perf_counter() - start
