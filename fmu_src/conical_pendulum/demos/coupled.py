"""The coupled demo: the pendulum hanging from a cart on a spring, co-simulated in ecospy.

Two FMUs built here (the coupled pendulum and `Cart`) exchange the pivot's acceleration
and the force on the support at every communication step, in ecospy's fixed-step
master; one monolithic sympy model of cart and pendulum (kane_reference), integrated
natively at 1e-12, is the truth. The coupling error against the communication step is
the co-simulation's own face of the speed/accuracy trade.

    conical-pendulum demo [--out dist/coupled] [--steps 0.1,0.05,...] [--stop-time 10] [--cart-mass KG]

ecospy (the `cosim` extra) runs in a subprocess (demos/ecospy_run.py): it needs libtbb
loaded first, and its interpreter can abort at exit while pythonfmu's library is mapped.
"""
from __future__ import annotations

import argparse
import csv
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..scene import Scene
from . import ecospy_run
from .monolithic import CART_START, cart_parameters, monolithic

STEPS = (0.2, 0.1, 0.05, 0.02, 0.01, 0.005)
STOP_TIME = 10.0
SCENE = Scene.uniform(3, coupling=True)
EXCHANGED = ["cart::x", "cart::v", "cart::a", "p::F_pivot_x"] + [f"p::{name}" for name in SCENE.state_names()]


def build_cart_fmu(output: Path | str) -> Path:
    """Cart.fmu from runtime/cart_slave.py, packaged as the pendulum is."""
    from ..build.fmu import package
    from ..runtime.cart_slave import PARAMETERS

    output = Path(output)
    starts = {**{name: value for name, (_, value) in PARAMETERS.items()}, **CART_START, "F_x": 0.0}
    package("cart_slave", [], output, starts, feedthrough=["a"])
    return output


def cosimulate(pendulum_fmu: Path, cart_fmu: Path, steps=STEPS, stop_time: float = STOP_TIME,
               cart: dict | None = None) -> dict:
    """{step: {variable: array}} from ecospy's fixed-step master, one run per step size
    (demos/ecospy_run.py, in a process of its own), after a warm-up run that pays the
    imports (the cart's scipy); "seconds" is the wall time in ecospy's step()."""
    job = {"models": {"p": str(pendulum_fmu), "cart": str(cart_fmu)},
           "connections": [["cart::a", "p::a_pivot_x"], ["p::F_pivot_x", "cart::F_x"]],
           "parameters": {f"cart::{name}": value for name, value in (cart or cart_parameters()).items()},
           "steps": list(steps), "stop_time": stop_time, "record": EXCHANGED, "warm_up": True}
    return {run["step"]: {**{name.split("::")[-1]: np.array(values) for name, values in run["values"].items()},
                          "seconds": run["seconds"]} for run in ecospy_run.cosimulate(job)}


@dataclass
class CouplingError:
    step: float
    cart_error: float    # max |x - x_ref| over the communication points [m]
    angle_error: float   # max |angle - angle_ref| over the pendulum's angles [rad]
    force_error: float   # max |F_pivot_x - F_ref| [N]
    seconds: float       # wall time in ecospy's step() over the run
    diverged: bool       # the cart strayed further from the truth than the truth ever goes


def coupling_errors(runs: dict, scene: Scene = SCENE, cart: dict | None = None
                    ) -> tuple[list[CouplingError], dict]:
    """Each run against the monolithic reference at its own communication points."""
    finest = min(runs)
    reference = monolithic(runs[finest]["time"], scene, cart)
    reference["F_pivot_x"] = _reference_force(reference, scene)
    span = np.abs(reference["x_cart"]).max()
    angles = scene.state_names()[:2 * scene.n]
    errors = []
    for dt, run in sorted(runs.items()):
        every = round(dt / finest)
        ref = {name: values[::every] for name, values in reference.items()}
        cart_error = np.abs(run["x"] - ref["x_cart"]).max()
        errors.append(CouplingError(
            dt, cart_error, max(np.abs(run[name] - ref[name]).max() for name in angles),
            np.abs(run["F_pivot_x"] - ref["F_pivot_x"]).max(), float(run["seconds"]),
            not cart_error < span))
    return errors, reference


def _reference_force(reference: dict, scene: Scene) -> np.ndarray:
    """F_pivot_x along the reference, from the compiled core with the cart's acceleration."""
    from ..build.compiler import load_core

    core = load_core(scene)
    names = scene.state_names()
    column = scene.output_names().index("F_pivot_x")
    return np.array([core.outputs([reference[name][k] for name in names],
                                  scene.parameters({"a_pivot_x": reference["a_cart"][k]}))[column]
                     for k in range(len(reference["a_cart"]))])


def plot(runs: dict, errors: list[CouplingError], reference: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    finest = min(runs)
    times = runs[finest]["time"]
    fig, (ax_x, ax_e) = plt.subplots(1, 2, figsize=(12, 4.5))
    ax_x.plot(times, reference["x_cart"], "k", lw=2.5, label="monolithic (DOP853 1e-12)")
    for dt in sorted(runs, reverse=True)[:3]:
        ax_x.plot(runs[dt]["time"], runs[dt]["x"], lw=1, label=f"ecospy, step {dt:g} s")
    span = np.abs(reference["x_cart"]).max()
    ax_x.set(xlabel="time [s]", ylabel="cart position x [m]", title="cart carrying the 3-link pendulum",
             ylim=(-1.5 * span, 1.5 * span))  # a diverging exchange leaves the frame
    ax_x.legend(fontsize=8)
    bounded = [e for e in errors if not e.diverged]
    steps = np.array([e.step for e in bounded])
    for field, label in (("cart_error", "cart x [m]"), ("angle_error", "pendulum angles [rad]")):
        ax_e.loglog(steps, [getattr(e, field) for e in bounded], "o-", label=label)
    if bounded:
        ax_e.loglog(steps, bounded[0].cart_error * steps / steps[0], "k:", label="first order")
    diverged = ", ".join(f"{e.step:g} s" for e in errors if e.diverged)
    if diverged:
        ax_e.text(0.05, 0.9, f"diverged at {diverged}", transform=ax_e.transAxes, color="red")
    ax_e.set(xlabel="communication step [s]", ylabel="max error over 10 s",
             title="coupling error against the step")
    ax_e.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _steps(text: str) -> list[float]:
    try:
        return sorted({float(s) for s in text.split(",")})
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected numbers separated by commas, got {text!r}") from None


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The demo's options (`conical-pendulum demo`)."""
    parser.description = __doc__
    parser.add_argument("--out", type=Path, default=Path("dist") / "coupled",
                        help="folder for the FMUs, coupling_error.csv and coupling.png (dist/coupled)")
    parser.add_argument("--steps", type=_steps, default=sorted(STEPS), metavar="DT,DT,...",
                        help="communication steps [s], comma-separated; each must divide the stop "
                             f"time and be a multiple of the smallest ({','.join(map(str, STEPS))})")
    parser.add_argument("--stop-time", type=float, default=STOP_TIME, metavar="SECONDS",
                        help=f"simulated seconds ({STOP_TIME:g})")
    parser.add_argument("--cart-mass", type=float, default=cart_parameters()["m_cart"], metavar="KG",
                        help="m_cart [kg]; below a few kg the explicit exchange diverges at any step "
                             f"({cart_parameters()['m_cart']:g})")


def run(args) -> int:
    """Build both FMUs, co-simulate at each step, compare with the monolithic model, write
    coupling_error.csv and coupling.png. 0, or 1 when ecospy failed."""
    from ..cli import UsageError

    steps = args.steps
    for dt in steps:
        if not (dt > 0 and abs(args.stop_time / dt - round(args.stop_time / dt)) < 1e-9
                and abs(dt / steps[0] - round(dt / steps[0])) < 1e-9):
            raise UsageError(f"--steps: {dt:g} must be positive, divide --stop-time {args.stop_time:g} "
                             f"and be a multiple of the smallest step {steps[0]:g}")
    if not args.cart_mass > 0:
        raise UsageError(f"--cart-mass: must be a positive number of kg, got {args.cart_mass!r}")
    cart_values = cart_parameters(m_cart=args.cart_mass)
    from ..build.fmu import build_fmu

    args.out.mkdir(parents=True, exist_ok=True)
    pendulum = build_fmu(SCENE, args.out / "ConicalPendulum.fmu").path
    cart = build_cart_fmu(args.out / "Cart.fmu")
    try:
        runs = cosimulate(pendulum, cart, steps, args.stop_time, cart_values)
    except RuntimeError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    errors, reference = coupling_errors(runs, SCENE, cart_values)
    header = ["step_s", "cart_error_m", "angle_error_rad", "force_error_N", "ecospy_seconds"]
    rows = [[f"{e.step:g}", f"{e.cart_error:.3e}", f"{e.angle_error:.3e}", f"{e.force_error:.3e}",
             f"{e.seconds:.3f}"] for e in errors]
    with open(args.out / "coupling_error.csv", "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows([header, *rows])
    plot(runs, errors, reference, args.out / "coupling.png")
    print("\n".join("\t".join(row) for row in [header, *rows]))
    for e in errors:
        if e.diverged:
            print(f"step {e.step:g} s: the exchange diverged (cart error {e.cart_error:.2g} m): the "
                  "cart is too light for an explicit exchange, at any step (added-mass effect)")
    print(f"wrote {args.out / 'coupling_error.csv'} and {args.out / 'coupling.png'}")
    return 0
