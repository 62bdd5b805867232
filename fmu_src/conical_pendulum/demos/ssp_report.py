"""The SSP package's runs in each tool against the monolithic model and today's demo.

For each cart mass and step one package (demos/ssp.py), run by each scheme in each tool
(demos/ssp_tools.py); each run's largest errors against the monolithic model
(coupled.coupling_errors) go to ssp_runs.csv, the cart's position error over time to
ssp_runs.png, and ecos-from-the-package (ecospy) is compared with today's demo
(coupled.cosimulate, the same FMUs wired in Python): the same master, so the same
numbers. system.png draws the two FMUs and what flows between them in each scheme.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import coupled, ssp, ssp_tools
from .monolithic import cart_parameters

WORK = "work"  # under the output folder: each tool's unpacked packages, outputs and logs, per package


@dataclass
class ToolResult:
    tool: str
    scheme: str
    cart_mass: float  # [kg]
    step: float  # [s]
    run: ssp_tools.ToolRun
    error: coupled.CouplingError | None  # None when the tool refused
    curve: tuple  # (times, |x - x_ref|) at the run's points


def package_path(out: Path, cart_mass: float, step: float) -> Path:
    return out / f"PendulumOnCart-{cart_mass:g}kg-{step:g}s.ssp"


def write_packages(
    out: Path, pendulum_fmu: Path, cart_fmu: Path, cart_masses, steps, stop_time
) -> list[Path]:
    """One validated package per cart mass and step; RuntimeError naming what the schema refused."""
    packages = []
    for mass in cart_masses:
        for step in steps:
            package = ssp.write_package(
                package_path(out, mass, step), pendulum_fmu, cart_fmu, mass, step, stop_time
            )
            problems = ssp.validate(package)
            if problems:
                raise RuntimeError(f"{package.name} is not valid SSP 1.0: {'; '.join(problems[:3])}")
            packages.append(package)
    return packages


def compare(
    out: Path, pendulum_fmu: Path, cart_fmu: Path, cart_masses, steps, stop_time: float, tools
) -> tuple[list[ToolResult], dict]:
    """Each tool's run of each package and scheme against the monolithic model; and, with
    ecospy among the tools, {(cart mass, scheme): the largest difference of any recorded
    variable between ecospy from the package and today's demo}."""
    steps = sorted(steps)
    times = np.linspace(0.0, stop_time, round(stop_time / steps[0]) + 1)
    results, agreement = [], {}
    for mass in cart_masses:
        truth = coupled.reference(times, coupled.SCENE, cart_parameters(m_cart=mass))
        for scheme in ssp.VARIANTS:
            demo = None
            if "ecospy" in tools:
                demo = coupled.cosimulate(
                    pendulum_fmu, cart_fmu, steps, stop_time, cart_parameters(m_cart=mass), scheme
                )
            for tool in tools:
                runs = {}
                for step in steps:
                    package = package_path(out, mass, step)
                    runs[step] = ssp_tools.run(tool, package, scheme, out / WORK / package.stem)
                ran = {step: run.as_run() for step, run in runs.items() if not run.refused}
                errors = {e.step: e for e in coupled.coupling_errors(ran, truth, scheme, mass)} if ran else {}
                for step, run in runs.items():
                    curve = ()
                    if not run.refused:
                        ref = coupled.on_times(truth, run.values["time"], steps[0])
                        curve = (run.values["time"], np.abs(run.values["x"] - ref["x_cart"]))
                    results.append(ToolResult(tool, scheme, mass, step, run, errors.get(step), curve))
                if tool == "ecospy" and demo is not None:
                    agreement[mass, scheme] = max(
                        np.abs(run.values[name] - demo[step][name]).max()
                        for step, run in runs.items()
                        if not run.refused
                        for name in run.values
                    )
    return results, agreement


HEADER = [
    "tool",
    "scheme",
    "cart_mass_kg",
    "step_s",
    "cart_error_m",
    "angle_error_rad",
    "diverged",
    "seconds",
    "note",
]


def write(results: list[ToolResult], out: Path) -> list[list[str]]:
    """ssp_runs.csv and ssp_runs.png in the folder `out`; the CSV's rows, header first."""
    rows = []
    for r in results:
        note = r.run.refused or "; ".join(r.run.warnings) or (r.error.ended if r.error else "") or ""
        rows.append(
            [
                r.tool,
                r.scheme,
                f"{r.cart_mass:g}",
                f"{r.step:g}",
                f"{r.error.cart_error:.3e}" if r.error else "",
                f"{r.error.angle_error:.3e}" if r.error else "",
                str(r.error.diverged).lower() if r.error else "",
                f"{r.run.seconds:.3f}",
                note.replace("\n", " ")[:300],
            ]
        )
    with open(out / "ssp_runs.csv", "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows([HEADER, *rows])
    plot(results, out / "ssp_runs.png")
    return [HEADER, *rows]


def plot(results: list[ToolResult], path: Path) -> None:
    """|x - x_ref| over time: a row per cart mass, a column per scheme, a colour per tool,
    a line style per step."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    masses = sorted({r.cart_mass for r in results}, reverse=True)
    schemes = list(dict.fromkeys(r.scheme for r in results))
    steps = sorted({r.step for r in results}, reverse=True)
    colours = dict(zip(ssp_tools.TOOLS, plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    styles = dict(zip(steps, ["-", "--", ":", "-."]))
    # ecos' lines lie on ecospy's
    widths = {"ecospy": 3.0, "ecos": 1.2, "libcosim": 1.6, "fmpy": 1.2, "omsimulator": 1.6}
    fig, axes = plt.subplots(
        len(masses), len(schemes), figsize=(6 * len(schemes), 3.6 * len(masses)), squeeze=False
    )
    for row, mass in enumerate(masses):
        for column, scheme in enumerate(schemes):
            ax = axes[row][column]
            for r in results:
                if (r.cart_mass, r.scheme) != (mass, scheme) or not r.curve:
                    continue
                times, error = r.curve
                ax.semilogy(
                    times[1:] if times[0] == 0 else times,
                    np.maximum(error[1:] if times[0] == 0 else error, 1e-12),
                    styles[r.step],
                    color=colours[r.tool],
                    lw=widths.get(r.tool, 1.2),
                    alpha=0.55 if r.tool == "ecospy" else 1.0,
                    label=f"{r.tool}, step {r.step:g} s",
                )
            ax.set(
                title=f"{scheme}, cart {mass:g} kg",
                xlabel="time [s]",
                ylabel="|cart x - monolithic| [m]",
            )
            ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=7, ncol=2)
    fig.suptitle(
        "The SSP package in each tool: the cart's position against the monolithic model", fontsize=11
    )
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def draw_system(path: Path) -> None:
    """The two FMUs and what flows between them, a panel per scheme (from coupled.SCHEMES)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import FancyBboxPatch

    titles = {
        "p": "ConicalPendulum.fmu (p)\n3-link chain, native FMI 2.0",
        "cart": "Cart.fmu (cart)\nmass, spring, damper",
    }
    fig, axes = plt.subplots(1, len(coupled.SCHEMES), figsize=(6.2 * len(coupled.SCHEMES), 2.6))
    for ax, (scheme, (connections, settings)) in zip(axes, coupled.SCHEMES.items()):
        ax.set(xlim=(0, 10), ylim=(1.2, 4.8), title=f"{ssp.VARIANTS[scheme]}: {scheme}")
        ax.axis("off")
        boxes = {"cart": (0.3, 1.5), "p": (6.2, 1.5)}
        for instance, (x, y) in boxes.items():
            ax.add_patch(
                FancyBboxPatch((x, y), 3.5, 3.0, boxstyle="round,pad=0.1", fc="#eef3fb", ec="#3366aa")
            )
            ax.text(x + 1.75, y + 2.5, titles[instance], ha="center", va="center", fontsize=8.5)
        ax.text(
            2.05,
            2.0,
            "m_cart, k_cart, c_cart, "
            + ", ".join(f"{k} = {v}" for k, v in settings.items())
            + f"\n(resources/{scheme}.ssv)",
            ha="center",
            va="center",
            fontsize=7.5,
            color="#555555",
        )
        for k, (start, end) in enumerate(connections):
            y = 3.9 - 0.8 * k
            forward = start.startswith("cart::")
            x0, x1 = (3.9, 6.1) if forward else (6.1, 3.9)
            ax.annotate("", xy=(x1, y), xytext=(x0, y), arrowprops={"arrowstyle": "->", "lw": 1.6})
            ax.text(5.0, y + 0.12, f"{start.split('::')[1]} -> {end.split('::')[1]}", ha="center", fontsize=8)
    fig.suptitle(
        "PendulumOnCart.ssp: the two FMUs and what they exchange at each communication step", fontsize=10
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
