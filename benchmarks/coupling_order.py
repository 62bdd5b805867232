"""The coupled demo's error and observed order in OMSimulator, with and without its
`--inputExtrapolation` (the FMUs' output derivatives passed on as input derivatives).

    python benchmarks/coupling_order.py [--steps 0.1,0.05,0.02,0.01] [--cart-mass 100,5,2,0.5]

For every cart mass and communication step, the SSP package `conical-pendulum system`
writes (native FMI 2.0 pendulum and cart, both declaring canInterpolateInputs and
maxOutputDerivativeOrder = 2), run by OMSimulator ($OMSIMULATOR or PATH)
by both schemes, as written ("held": OMSimulator's default, inputs constant over a step) and
with `--inputExtrapolation=true`; each run against the monolithic model at its communication
points over 10 s (coupled.coupling_errors: the largest cart-position error). The observed
order between two steps is log(e1 / e2) / log(dt1 / dt2). Writes
benchmarks/results/coupling_order.csv and docs/results/coupling_order.png.
"""

import argparse
import math
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from conical_pendulum.builder.fmu import build_fmu
from conical_pendulum.demos import coupled, ssp, ssp_tools
from conical_pendulum.demos.monolithic import cart_parameters
from results_csv import write_rows

ROOT = Path(__file__).resolve().parent.parent
OPTIONS = {"held": (), "inputExtrapolation": ("--inputExtrapolation=true",)}
SCHEMES = ("explicit", "apparent-mass")
STOP_TIME = 10.0


def floats(text):
    return tuple(float(x) for x in text.split(","))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=floats, default=(0.1, 0.05, 0.02, 0.01))
    parser.add_argument("--cart-mass", type=floats, default=(100.0, 5.0, 2.0, 0.5))
    args = parser.parse_args()
    if ssp_tools.omsimulator() is None:
        raise SystemExit(ssp_tools.missing("omsimulator"))
    steps = sorted(args.steps)
    rows = []
    with tempfile.TemporaryDirectory(prefix="coupling_order_") as tmp:
        tmp = Path(tmp)
        pendulum = build_fmu(coupled.SCENE, tmp / "ConicalPendulum.fmu", backend="native").path
        cart = coupled.build_cart_fmu(tmp / "Cart.fmu")
        times = np.linspace(0.0, STOP_TIME, round(STOP_TIME / steps[0]) + 1)
        for mass in args.cart_mass:
            truth = coupled.reference(times, coupled.SCENE, cart_parameters(m_cart=mass))
            for scheme in SCHEMES:
                for option, flags in OPTIONS.items():
                    runs, seconds = {}, {}
                    for step in steps:
                        package = ssp.write_package(
                            tmp / f"m{mass}_dt{step}.ssp", pendulum, cart, mass, step, STOP_TIME
                        )
                        work = tmp / f"work_m{mass}_dt{step}_{option}"
                        run = ssp_tools.run_omsimulator(package.absolute(), scheme, work.absolute(), flags)
                        if run.refused or run.ended:
                            print(
                                f"{mass:6g} kg {step:5g} s {scheme:13s} {option:18s} failed: "
                                f"{(run.refused or run.ended)[:100]}"
                            )
                            continue
                        runs[step] = run.as_run()
                        seconds[step] = run.seconds
                    errors = (
                        {e.step: e for e in coupled.coupling_errors(runs, truth, scheme, mass)}
                        if runs
                        else {}
                    )
                    previous = None
                    for step in reversed(steps):  # coarse to fine: the order between neighbours
                        e = errors.get(step)
                        error = e.cart_error if e and not e.diverged else math.nan
                        order = (
                            math.log(previous[1] / error) / math.log(previous[0] / step)
                            if previous and error > 0 and previous[1] > 0
                            else math.nan
                        )
                        rows.append(
                            {
                                "master": "OMSimulator",
                                "option": option,
                                "scheme": scheme,
                                "cart_mass": mass,
                                "step": step,
                                "cart_error": f"{error:.3e}",
                                "order": f"{order:.2f}",
                                "seconds": round(seconds.get(step, math.nan), 2),
                            }
                        )
                        print(
                            f"{mass:6g} kg {step:5g} s {scheme:13s} {option:18s} {error:10.3e} "
                            f"order {order:5.2f}  {seconds.get(step, math.nan):.2f} s"
                        )
                        previous = (step, error) if error == error else None
    print(write_rows("coupling_order", rows))
    plot(rows, ROOT / "docs" / "results" / "coupling_order.png")


def plot(rows, path):
    """Cart-position error against the step: a panel per scheme, a colour per cart, a line
    style per option."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
    masses = sorted({r["cart_mass"] for r in rows}, reverse=True)
    colours = dict(zip(masses, plt.cm.viridis(np.linspace(0, 0.85, len(masses)))))
    for ax, scheme in zip(axes, SCHEMES):
        for mass in masses:
            for option, style in (("held", "--"), ("inputExtrapolation", "-")):
                points = [
                    (r["step"], float(r["cart_error"]))
                    for r in rows
                    if r["scheme"] == scheme and r["cart_mass"] == mass and r["option"] == option
                ]
                points = sorted(p for p in points if p[1] == p[1])
                if points:
                    ax.loglog(
                        *zip(*points), style, marker="o", color=colours[mass], label=f"{mass:g} kg, {option}"
                    )
        steps = np.array(sorted({r["step"] for r in rows}))
        for order, anchor in ((1, 2e-2), (2, 2e-3)):
            ax.loglog(steps, anchor * (steps / steps[-1]) ** order, ":", color="grey", lw=1)
            ax.annotate(f"order {order}", (steps[-1], anchor), fontsize=8, color="grey")
        ax.set_title(f"OMSimulator, {scheme} scheme")
        ax.set_xlabel("communication step [s]")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("largest cart-position error over 10 s [m]")
    axes[1].legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    print(path)


if __name__ == "__main__":
    main()
