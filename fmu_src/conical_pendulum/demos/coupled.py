"""The coupled demo: the pendulum hanging from a cart on a spring, co-simulated in ecospy.

Two FMUs built here (the coupled pendulum and `Cart`) exchange the pivot's acceleration
and the force on the support at every communication step, in ecospy's fixed-step
master; one monolithic sympy model of cart and pendulum (kane_reference), integrated
natively at 1e-12, is the truth. The coupling error against the communication step is
the co-simulation's own face of the speed/accuracy trade.

    python -m conical_pendulum.demos.coupled [--out dist/coupled] [--steps 0.1,0.05,...]

ecospy (the `cosim` extra) runs in a subprocess: it needs libtbb loaded first, and its
interpreter can abort at exit while pythonfmu's library is mapped.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..scene import Scene
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


ECOSPY_SCRIPT = r"""
import ctypes, json, os, sys, time
ctypes.CDLL(os.path.join(sys.prefix, "lib", "libtbb.so.12"), mode=ctypes.RTLD_GLOBAL)
from ecospy import EcosLib, EcosSimulation, EcosSimulationStructure

job = json.loads(sys.argv[1])
EcosLib.set_log_level("warn")
runs = {}
for warm_up, dt in [(True, max(job["steps"]))] + [(False, dt) for dt in job["steps"]]:
    stepping = 0.0
    with EcosSimulationStructure() as structure:
        structure.add_model("p", job["pendulum"])
        structure.add_model("cart", job["cart"])
        structure.make_real_connection("cart::a", "p::a_pivot_x")
        structure.make_real_connection("p::F_pivot_x", "cart::F_x")
        structure.add_parameter_set("cart", {"cart::" + k: v for k, v in job["cart_parameters"].items()})
        with EcosSimulation(structure=structure, step_size=dt) as sim:
            sim.init(parameter_set="cart")
            run = {name: [] for name in ["time"] + job["record"]}
            steps = 1 if warm_up else round(job["stop_time"] / dt)
            for k in range(steps + 1):
                if k:
                    start = time.perf_counter()
                    sim.step()
                    stepping += time.perf_counter() - start
                run["time"].append(sim.get_time())
                for name in job["record"]:
                    run[name].append(sim.get_real(name))
            sim.terminate()
    run["seconds"] = stepping
    if not warm_up:  # the first run pays the imports (the cart's scipy)
        runs[repr(dt)] = run
print(json.dumps(runs))
sys.stdout.flush()
os._exit(0)
"""


def cosimulate(pendulum_fmu: Path, cart_fmu: Path, steps=STEPS, stop_time: float = STOP_TIME,
               cart: dict | None = None) -> dict:
    """{step: {variable: array}} from ecospy's fixed-step master, one run per step size."""
    job = {"pendulum": str(Path(pendulum_fmu).resolve()), "cart": str(Path(cart_fmu).resolve()),
           "cart_parameters": cart or cart_parameters(),
           "steps": list(steps), "stop_time": stop_time, "record": EXCHANGED}
    try:
        run = subprocess.run([sys.executable, "-c", ECOSPY_SCRIPT, json.dumps(job)],
                             capture_output=True, text=True, timeout=1800)
    except subprocess.TimeoutExpired:
        raise RuntimeError("ecospy did not finish the co-simulations within 30 minutes") from None
    if run.returncode != 0:
        if "No module named 'ecospy'" in run.stderr or "libtbb" in run.stderr:
            raise RuntimeError("the coupled demo needs ecospy and tbb: pip install -e \".[cosim]\"")
        raise RuntimeError(f"ecospy failed (exit {run.returncode}):\n{run.stderr[-3000:]}")
    runs = json.loads(run.stdout.strip().splitlines()[-1])
    return {float(dt): {name.split("::")[-1]: np.array(values) for name, values in result.items()}
            for dt, result in runs.items()}  # "seconds": wall time in ecospy's step()


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


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m conical_pendulum.demos.coupled", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("dist") / "coupled",
                        help="folder for the FMUs, coupling_error.csv and coupling.png")
    parser.add_argument("--steps", default=",".join(map(str, STEPS)),
                        help="communication steps [s], comma-separated; each must divide the stop "
                             "time and be a multiple of the smallest")
    parser.add_argument("--stop-time", type=float, default=STOP_TIME)
    parser.add_argument("--cart-mass", type=float, default=cart_parameters()["m_cart"],
                        help="m_cart [kg]; below a few kg the explicit exchange diverges at any step")
    args = parser.parse_args(argv)
    try:
        steps = sorted({float(s) for s in args.steps.split(",")})
    except ValueError:
        parser.error(f"--steps: expected numbers separated by commas, got {args.steps!r}")
    for dt in steps:
        if not (dt > 0 and abs(args.stop_time / dt - round(args.stop_time / dt)) < 1e-9
                and abs(dt / steps[0] - round(dt / steps[0])) < 1e-9):
            parser.error(f"--steps: {dt:g} must be positive, divide --stop-time {args.stop_time:g} "
                         f"and be a multiple of the smallest step {steps[0]:g}")
    if not args.cart_mass > 0:
        parser.error(f"--cart-mass: must be a positive number of kg, got {args.cart_mass!r}")
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
    rows = ["step_s,cart_error_m,angle_error_rad,force_error_N,ecospy_seconds"]
    rows += [f"{e.step:g},{e.cart_error:.3e},{e.angle_error:.3e},{e.force_error:.3e},{e.seconds:.3f}"
             for e in errors]
    (args.out / "coupling_error.csv").write_text("\n".join(rows) + "\n")
    plot(runs, errors, reference, args.out / "coupling.png")
    print("\n".join(rows).replace(",", "\t"))
    for e in errors:
        if e.diverged:
            print(f"step {e.step:g} s: the exchange diverged (cart error {e.cart_error:.2g} m): the "
                  "cart is too light for an explicit exchange, at any step (added-mass effect)")
    print(f"wrote {args.out / 'coupling_error.csv'} and {args.out / 'coupling.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
