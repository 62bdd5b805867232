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

import argparse
import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import UserError
from ..scene import Scene
from . import ecospy_run
from .monolithic import CART_START, cart_parameters, monolithic

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
    "apparent-mass": ([["cart::a", "p::a_pivot_x"], ["p::F_free_x", "cart::F_x"],
                       ["p::M_pivot_xx", "cart::M_x"]], {"F_x_order": 1}),
}
CART_MASSES = (100.0, 5.0, 2.0, 0.5)  # [kg], against the chain's 45 kg
DIVERGED = 1000.0  # |cart x| [m] that ends a run as diverged: the truth stays within 1 m
EXCHANGED = ["cart::x", "cart::v", "cart::a", "p::F_pivot_x"] + [f"p::{name}" for name in SCENE.state_names()]


def build_cart_fmu(output: Path | str) -> Path:
    """Cart.fmu from runtime/cart_slave.py, packaged as the pendulum is."""
    from ..builder.fmu import package
    from ..runtime.cart_slave import PARAMETERS

    output = Path(output)
    starts = {**{name: value for name, (_, value) in PARAMETERS.items()}, **CART_START,
              "F_x": 0.0, "M_x": 0.0}
    package("cart_slave", [], output, starts, feedthrough=["a"])
    return output


def cosimulate(pendulum_fmu: Path, cart_fmu: Path, steps=STEPS, stop_time: float = STOP_TIME,
               cart: dict | None = None, scheme: str = "explicit") -> dict:
    """{step: {variable: array}} from ecospy's fixed-step master by `scheme`, one run per
    step size (demos/ecospy_run.py, in a process of its own), after a warm-up run that pays
    the Python slaves' first imports; "seconds" is the wall time in ecospy's step(),
    "ended" why a run stopped early (the cart beyond DIVERGED), or None."""
    connections, cart_settings = SCHEMES[scheme]
    job = {"models": {"p": str(pendulum_fmu), "cart": str(cart_fmu)}, "connections": connections,
           "parameters": {f"cart::{name}": value
                          for name, value in {**(cart or cart_parameters()), **cart_settings}.items()},
           "steps": list(steps), "stop_time": stop_time, "record": EXCHANGED,
           "limits": {"cart::x": DIVERGED}, "warm_up": True}
    return {run["step"]: {**{name.split("::")[-1]: np.array(values) for name, values in run["values"].items()},
                          "seconds": run["seconds"], "ended": run["ended"]} for run in ecospy_run.cosimulate(job)}


@dataclass
class CouplingError:
    scheme: str
    cart_mass: float     # [kg]
    step: float
    cart_error: float    # max |x - x_ref| over the communication points [m]
    angle_error: float   # max |angle - angle_ref| over the pendulum's angles [rad]
    force_error: float   # max |F_pivot_x - F_ref| [N]
    seconds: float       # wall time in ecospy's step() over the run
    ended: str | None    # why the run stopped early (the cart beyond DIVERGED), or None
    diverged: bool       # stopped early, or strayed further from the truth than it ever goes


def reference(times, scene: Scene = SCENE, cart: dict | None = None) -> dict:
    """The monolithic model on `times`, with F_pivot_x from the compiled core at the
    cart's acceleration."""
    from ..builder.compiler import load_core

    truth = monolithic(times, scene, cart)
    core = load_core(scene)
    names = scene.state_names()
    column = scene.output_names().index("F_pivot_x")
    truth["F_pivot_x"] = np.array([core.outputs([truth[name][k] for name in names],
                                                scene.parameters({"a_pivot_x": truth["a_cart"][k]}))[column]
                                   for k in range(len(times))])
    return truth


def coupling_errors(runs: dict, truth: dict, scheme: str, cart_mass: float,
                    scene: Scene = SCENE) -> list[CouplingError]:
    """Each run against the reference (on the finest step's times) at its own communication
    points, up to where it ended."""
    finest = min(runs)
    span = np.abs(truth["x_cart"]).max()
    angles = scene.state_names()[:2 * scene.n]
    errors = []
    for dt, run in sorted(runs.items()):
        count = len(run["x"])
        ref = {name: values[::round(dt / finest)][:count] for name, values in truth.items()}
        cart_error = np.abs(run["x"] - ref["x_cart"]).max()
        errors.append(CouplingError(
            scheme, cart_mass, dt, cart_error, max(np.abs(run[name] - ref[name]).max() for name in angles),
            np.abs(run["F_pivot_x"] - ref["F_pivot_x"]).max(), float(run["seconds"]), run["ended"],
            run["ended"] is not None or not cart_error < span))
    return errors


def plot(errors: list[CouplingError], path: Path) -> None:
    """The largest errors against the step: a colour per cart mass, a line style per
    scheme, diverged runs as crosses above the rest, a row per cart mass."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    masses = sorted({e.cart_mass for e in errors}, reverse=True)
    colours = dict(zip(masses, plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    styles = {"explicit": dict(ls="--", marker="o", mfc="none"), "apparent-mass": dict(ls="-", marker="s")}
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    for ax, field, label in ((axes[0], "cart_error", "cart x [m]"),
                             (axes[1], "angle_error", "pendulum angles [rad]")):
        bounded = [getattr(e, field) for e in errors if not e.diverged]
        top = 10 * max(bounded) if bounded else 1.0
        for (scheme, mass) in dict.fromkeys((e.scheme, e.cart_mass) for e in errors):
            runs = [e for e in errors if (e.scheme, e.cart_mass) == (scheme, mass)]
            stable = [e for e in runs if not e.diverged]
            ax.loglog([e.step for e in stable], [getattr(e, field) for e in stable], color=colours[mass],
                      label=f"{scheme}, cart {mass:g} kg", **styles.get(scheme, {}))
            failed = [e.step for e in runs if e.diverged]
            row = top * 2.0 ** (masses.index(mass) + 1)
            ax.loglog(failed, [row] * len(failed), "x", color=colours[mass], ms=8, mew=2)
        if any(e.diverged for e in errors):
            ax.axhline(top, color="0.6", lw=0.8)
        ax.set(xlabel="communication step [s]", ylabel=f"largest error, {label}",
               title=f"{label.split(' [')[0]} against the monolithic model")
    axes[0].legend(fontsize=7, loc="lower right")
    fig.suptitle("3-link pendulum (45 kg) on a cart, co-simulated in ecospy: explicit against "
                 "apparent-mass exchange (crosses above the line: diverged)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _numbers(text: str) -> list[float]:
    try:
        return sorted({float(s) for s in text.split(",")})
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected numbers separated by commas, got {text!r}") from None


def _schemes(text: str) -> list[str]:
    chosen = list(dict.fromkeys(text.split(",")))
    unknown = [name for name in chosen if name not in SCHEMES]
    if unknown:
        raise argparse.ArgumentTypeError(f"unknown scheme(s) {', '.join(map(repr, unknown))}; "
                                         f"choose from {', '.join(SCHEMES)}")
    return chosen


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The demo's options (`conical-pendulum demo`)."""
    parser.description = __doc__
    parser.add_argument("--out", type=Path, default=Path("dist") / "coupled",
                        help="folder for the FMUs, coupling_error.csv and coupling.png (dist/coupled)")
    parser.add_argument("--steps", type=_numbers, default=sorted(STEPS), metavar="DT,DT,...",
                        help="communication steps [s], comma-separated; each must divide the stop "
                             f"time and be a multiple of the smallest ({','.join(map(str, STEPS))})")
    parser.add_argument("--stop-time", type=float, default=STOP_TIME, metavar="SECONDS",
                        help=f"simulated seconds ({STOP_TIME:g})")
    parser.add_argument("--cart-mass", type=_numbers, default=sorted(CART_MASSES, reverse=True),
                        metavar="KG,KG,...",
                        help="m_cart [kg], comma-separated; lighter than the chain's apparent mass "
                             "(3 to 5 kg) the explicit exchange diverges at any step "
                             f"({','.join(f'{m:g}' for m in CART_MASSES)})")
    parser.add_argument("--scheme", type=_schemes, default=list(SCHEMES), metavar="NAME,NAME,...",
                        help="how the FMUs exchange the pivot force: explicit (F_pivot_x) or "
                             "apparent-mass (F_free_x and M_pivot_xx, the cart moving the "
                             f"chain's apparent mass in its own step) ({','.join(SCHEMES)})")


def run(args) -> int:
    """Build both FMUs, co-simulate each scheme and cart mass at each step, compare with the
    monolithic model, write coupling_error.csv and coupling.png. 0; a UserError of status 1
    when ecospy failed, of status 2 for bad options or without the cosim extra."""
    steps = args.steps
    for dt in steps:
        if not (dt > 0 and abs(args.stop_time / dt - round(args.stop_time / dt)) < 1e-9
                and abs(dt / steps[0] - round(dt / steps[0])) < 1e-9):
            raise UserError(f"--steps: {dt:g} must be positive, divide --stop-time {args.stop_time:g} "
                            f"and be a multiple of the smallest step {steps[0]:g}")
    for mass in args.cart_mass:
        if not (mass > 0 and math.isfinite(mass)):
            raise UserError(f"--cart-mass: must be a positive number of kg, got {mass!r}")
    lacking = ecospy_run.missing()
    if lacking:  # before the builds and the reference, which take a while
        raise UserError(f"needs {lacking}: pip install -e \".[cosim]\"")
    from ..builder.fmu import build_fmu

    if args.out.exists() and not args.out.is_dir():
        raise UserError(f"--out {args.out}: not a directory")
    try:
        args.out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:  # a file above the folder, or no permission
        raise UserError(f"--out {args.out}: {exc.strerror or exc}") from None
    pendulum = build_fmu(SCENE, args.out / "ConicalPendulum.fmu").path
    cart = build_cart_fmu(args.out / "Cart.fmu")
    errors = []
    times = np.linspace(0.0, args.stop_time, round(args.stop_time / steps[0]) + 1)
    for mass in sorted(args.cart_mass, reverse=True):
        cart_values = cart_parameters(m_cart=mass)
        truth = reference(times, SCENE, cart_values)
        for scheme in args.scheme:
            try:
                runs = cosimulate(pendulum, cart, steps, args.stop_time, cart_values, scheme)
            except RuntimeError as exc:
                raise UserError(str(exc), status=1) from None
            errors += coupling_errors(runs, truth, scheme, mass)
    header = ["scheme", "cart_mass_kg", "step_s", "cart_error_m", "angle_error_rad", "force_error_N",
              "ecospy_seconds", "diverged"]
    rows = [[e.scheme, f"{e.cart_mass:g}", f"{e.step:g}", f"{e.cart_error:.3e}", f"{e.angle_error:.3e}",
             f"{e.force_error:.3e}", f"{e.seconds:.3f}", str(e.diverged).lower()] for e in errors]
    with open(args.out / "coupling_error.csv", "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows([header, *rows])
    plot(errors, args.out / "coupling.png")
    print("\n".join("\t".join(row) for row in [header, *rows]))
    for e in errors:
        if e.diverged:
            why = e.ended or f"cart error {e.cart_error:.2g} m"
            print(f"{e.scheme}, cart {e.cart_mass:g} kg, step {e.step:g} s: the exchange diverged ({why})"
                  + ("; the cart is too light against the chain's apparent mass for an explicit "
                     "exchange (added-mass effect): --scheme apparent-mass" if e.scheme == "explicit" else ""))
    print(f"wrote {args.out / 'coupling_error.csv'} and {args.out / 'coupling.png'}")
    return 0
