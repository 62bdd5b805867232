"""The coupled demo: the pendulum hanging from a cart on a spring, co-simulated in ecospy.

Two FMUs built here (the coupled pendulum and `Cart`) exchange the pivot's acceleration
and the force on the support at every communication step, in ecospy's fixed-step
master, by one of two schemes (SCHEMES): the force itself (explicit), or its split
F_free - M_app a with the chain's apparent mass moved by the cart (apparent-mass). One
monolithic sympy model of cart and pendulum (demos/monolithic.py), integrated natively at
1e-12, is the truth. The coupling error against the communication step, for each scheme
and cart mass, is the co-simulation's own face of the speed/accuracy trade.

    conical-pendulum demo [--out dist/coupled] [--steps 0.1,0.05,...] [--stop-time 10]
                          [--cart-mass 100,5,2,0.5] [--scheme explicit,apparent-mass]

ecospy (the `cosim` extra) runs in a subprocess (demos/ecospy_run.py): it needs libtbb
loaded first, and its interpreter can abort at exit while pythonfmu's library is mapped.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..builder import fmu as builder
from ..builder.compiler import load_core
from ..builder.models.cart import build_cart
from ..scene import Scene
from . import ecospy_run
from .monolithic import cart_parameters, monolithic

STEPS = (0.2, 0.1, 0.05, 0.02, 0.01, 0.005)
STOP_TIME = 10.0
SCENE = Scene.uniform(3, coupling=True)
# How the two FMUs exchange (ecospy connections, from -> to, and the cart's parameters).
# Both give the pendulum the cart's acceleration. Explicit: the cart gets the pivot force
# as computed at the last acceleration exchanged, held over the step. Apparent-mass: the
# cart gets its split F_free - M_app a and moves the chain's apparent mass with its own in
# its step; F_free depends on the pendulum's state only, so the cart extrapolates it.
SCHEMES = {
    "explicit": ([["cart::a", "p::a_pivot_x"], ["p::F_pivot_x", "cart::F_x"]], {"F_x_order": 0}),
    "apparent-mass": (
        [["cart::a", "p::a_pivot_x"], ["p::F_free_x", "cart::F_x"], ["p::M_pivot_xx", "cart::M_x"]],
        {"F_x_order": 1},
    ),
}
CART_MASSES = (100.0, 5.0, 2.0, 0.5)  # [kg], against the chain's 45 kg
DIVERGED = 1000.0  # |cart x| [m] that ends a run as diverged: the truth stays within 1 m
EXCHANGED = ["cart::x", "cart::v", "cart::a", "p::F_pivot_x"] + [f"p::{name}" for name in SCENE.state_names()]


def build_cart_fmu(output: Path | str, fmi_version: int = 2) -> Path:
    """Cart.fmu: the cart as a native FMU (builder/models/cart.py, runtime/csrc/models/cart_model.c), FMI 2.0
    (what the demo's ecospy runs) or 3.0."""
    return build_cart(Path(output), fmi_version=fmi_version)


def cosimulate(
    pendulum_fmu: Path,
    cart_fmu: Path,
    steps=STEPS,
    stop_time: float = STOP_TIME,
    cart: dict | None = None,
    scheme: str = "explicit",
) -> dict:
    """{step: {variable: array}} from ecospy's fixed-step master by `scheme`, one run per
    step size (demos/ecospy_run.py, in a process of its own), after a warm-up run that pays
    the Python slaves' first imports; "seconds" is the wall time in ecospy's step(),
    "ended" why a run stopped early (the cart beyond DIVERGED), or None."""
    connections, cart_settings = SCHEMES[scheme]
    job = {
        "models": {"p": str(pendulum_fmu), "cart": str(cart_fmu)},
        "connections": connections,
        "parameters": {
            f"cart::{name}": value for name, value in {**(cart or cart_parameters()), **cart_settings}.items()
        },
        "steps": list(steps),
        "stop_time": stop_time,
        "record": EXCHANGED,
        "limits": {"cart::x": DIVERGED},
        "warm_up": True,
    }
    return {
        run["step"]: {
            **{name.split("::")[-1]: np.array(values) for name, values in run["values"].items()},
            "seconds": run["seconds"],
            "ended": run["ended"],
        }
        for run in ecospy_run.cosimulate(job)
    }


@dataclass
class CouplingError:
    scheme: str
    cart_mass: float  # [kg]
    step: float
    cart_error: float  # max |x - x_ref| over the communication points [m]
    angle_error: float  # max |angle - angle_ref| over the pendulum's angles [rad]
    force_error: float  # max |F_pivot_x - F_ref| [N]
    seconds: float  # wall time in ecospy's step() over the run
    ended: str | None  # why the run stopped early (the cart beyond DIVERGED), or None
    diverged: bool  # stopped early, or strayed further from the truth than it ever goes


def reference(times, scene: Scene = SCENE, cart: dict | None = None) -> dict:
    """The monolithic model on `times`, with F_pivot_x from the compiled core at the
    cart's acceleration."""
    truth = monolithic(times, scene, cart)
    core = load_core(scene)
    names = scene.state_names()
    column = scene.output_names().index("F_pivot_x")
    truth["F_pivot_x"] = np.array(
        [
            core.outputs(
                [truth[name][k] for name in names], scene.parameters({"a_pivot_x": truth["a_cart"][k]})
            )[column]
            for k in range(len(times))
        ]
    )
    return truth


def on_times(truth: dict, times, spacing: float) -> dict:
    """The reference (on a grid of `spacing` from 0) at `times`, each a point of the grid."""
    index = np.rint(np.asarray(times) / spacing).astype(int)
    return {name: values[index] for name, values in truth.items()}


def coupling_errors(
    runs: dict, truth: dict, scheme: str, cart_mass: float, scene: Scene = SCENE
) -> list[CouplingError]:
    """Each run against the reference (on the finest step's times) at its own communication
    points (its "time"), up to where it ended."""
    finest = min(runs)
    span = np.abs(truth["x_cart"]).max()
    angles = scene.state_names()[: 2 * scene.n]
    errors = []
    for dt, run in sorted(runs.items()):
        ref = on_times(truth, run["time"], finest)
        cart_error = np.abs(run["x"] - ref["x_cart"]).max()
        errors.append(
            CouplingError(
                scheme,
                cart_mass,
                dt,
                cart_error,
                max(np.abs(run[name] - ref[name]).max() for name in angles),
                np.abs(run["F_pivot_x"] - ref["F_pivot_x"]).max(),
                float(run["seconds"]),
                run["ended"],
                run["ended"] is not None or not cart_error < span,
            )
        )
    return errors


def plot(errors: list[CouplingError], path: Path) -> None:
    """The largest errors against the step: a colour per cart mass, a line style per
    scheme, diverged runs as crosses above the rest, a row per cart mass."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    masses = sorted({e.cart_mass for e in errors}, reverse=True)
    colours = dict(zip(masses, plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    styles = {
        "explicit": {"ls": "--", "marker": "o", "mfc": "none"},
        "apparent-mass": {"ls": "-", "marker": "s"},
    }
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    for ax, field, label in (
        (axes[0], "cart_error", "cart x [m]"),
        (axes[1], "angle_error", "pendulum angles [rad]"),
    ):
        bounded = [getattr(e, field) for e in errors if not e.diverged]
        top = 10 * max(bounded) if bounded else 1.0
        for scheme, mass in dict.fromkeys((e.scheme, e.cart_mass) for e in errors):
            runs = [e for e in errors if (e.scheme, e.cart_mass) == (scheme, mass)]
            stable = [e for e in runs if not e.diverged]
            ax.loglog(
                [e.step for e in stable],
                [getattr(e, field) for e in stable],
                color=colours[mass],
                label=f"{scheme}, cart {mass:g} kg",
                **styles.get(scheme, {}),
            )
            failed = [e.step for e in runs if e.diverged]
            row = top * 2.0 ** (masses.index(mass) + 1)
            ax.loglog(failed, [row] * len(failed), "x", color=colours[mass], ms=8, mew=2)
        if any(e.diverged for e in errors):
            ax.axhline(top, color="0.6", lw=0.8)
        ax.set(
            xlabel="communication step [s]",
            ylabel=f"largest error, {label}",
            title=f"{label.split(' [')[0]} against the monolithic model",
        )
    axes[0].legend(fontsize=7, loc="lower right")
    fig.suptitle(
        "3-link pendulum (45 kg) on a cart, co-simulated in ecospy: explicit against "
        "apparent-mass exchange (crosses above the line: diverged)",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def demo(
    out: Path, steps=STEPS, stop_time: float = STOP_TIME, cart_masses=CART_MASSES, schemes=tuple(SCHEMES)
) -> list[CouplingError]:
    """Build both FMUs into the folder `out`, co-simulate each scheme and cart mass (the
    heaviest first) at each step (the smallest first, each a multiple of it and dividing
    `stop_time`) and compare with the monolithic model. RuntimeError when ecospy failed."""
    steps = sorted(steps)
    pendulum = builder.build_fmu(SCENE, out / "ConicalPendulum.fmu").path
    cart = build_cart_fmu(out / "Cart.fmu")
    errors = []
    times = np.linspace(0.0, stop_time, round(stop_time / steps[0]) + 1)
    for mass in sorted(cart_masses, reverse=True):
        cart_values = cart_parameters(m_cart=mass)
        truth = reference(times, SCENE, cart_values)
        for scheme in schemes:
            runs = cosimulate(pendulum, cart, steps, stop_time, cart_values, scheme)
            errors += coupling_errors(runs, truth, scheme, mass)
    return errors


HEADER = [
    "scheme",
    "cart_mass_kg",
    "step_s",
    "cart_error_m",
    "angle_error_rad",
    "force_error_N",
    "ecospy_seconds",
    "diverged",
]


def write(errors: list[CouplingError], out: Path) -> list[list[str]]:
    """coupling_error.csv and coupling.png in the folder `out`; the CSV's rows, header first."""
    rows = [
        [
            e.scheme,
            f"{e.cart_mass:g}",
            f"{e.step:g}",
            f"{e.cart_error:.3e}",
            f"{e.angle_error:.3e}",
            f"{e.force_error:.3e}",
            f"{e.seconds:.3f}",
            str(e.diverged).lower(),
        ]
        for e in errors
    ]
    with open(out / "coupling_error.csv", "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows([HEADER, *rows])
    plot(errors, out / "coupling.png")
    return [HEADER, *rows]
