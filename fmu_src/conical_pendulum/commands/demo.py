"""`conical-pendulum demo`: the pendulum on a cart, co-simulated in ecospy by two schemes
against one monolithic model (demos/coupled.py; the cosim extra)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..demos import coupled, ecospy_run
from ..errors import UserError, needs
from .common import check_cart_masses, check_steps, choices, numbers, output_folder


def schemes(text: str) -> list[str]:
    return choices(text, coupled.SCHEMES, "scheme")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    steps, masses, names = coupled.STEPS, coupled.CART_MASSES, list(coupled.SCHEMES)
    parser.description = coupled.__doc__
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("dist") / "coupled",
        help="folder for the FMUs, coupling_error.csv and coupling.png (dist/coupled)",
    )
    parser.add_argument(
        "--steps",
        type=numbers,
        default=sorted(steps),
        metavar="DT,DT,...",
        help="communication steps [s], comma-separated; each must divide the stop "
        f"time and be a multiple of the smallest ({','.join(map(str, steps))})",
    )
    parser.add_argument(
        "--stop-time",
        type=float,
        default=coupled.STOP_TIME,
        metavar="SECONDS",
        help=f"simulated seconds ({coupled.STOP_TIME:g})",
    )
    parser.add_argument(
        "--cart-mass",
        type=numbers,
        default=sorted(masses, reverse=True),
        metavar="KG,KG,...",
        help="m_cart [kg], comma-separated; lighter than the chain's apparent mass "
        "(3 to 5 kg) the explicit exchange diverges at any step "
        f"({','.join(f'{m:g}' for m in masses)})",
    )
    parser.add_argument(
        "--scheme",
        type=schemes,
        default=names,
        metavar="NAME,NAME,...",
        help="how the FMUs exchange the pivot force: explicit (F_pivot_x) or "
        "apparent-mass (F_free_x and M_pivot_xx, the cart moving the "
        f"chain's apparent mass in its own step) ({','.join(names)})",
    )


def run(args) -> int:
    """Build both FMUs, co-simulate each scheme and cart mass at each step, compare with the
    monolithic model, write coupling_error.csv and coupling.png. 0; a UserError of status 1
    when ecospy failed, of status 2 for bad options or without the cosim extra."""
    check_steps("--steps", args.steps, args.stop_time)
    check_cart_masses(args.cart_mass)
    lacking = ecospy_run.missing()
    if lacking:  # before the builds and the reference, which take a while
        raise UserError(needs(lacking, "cosim"))
    output_folder(args.out)
    try:
        errors = coupled.demo(args.out, args.steps, args.stop_time, args.cart_mass, args.scheme)
    except RuntimeError as exc:
        raise UserError(str(exc), status=1) from None
    print("\n".join("\t".join(row) for row in coupled.write(errors, args.out)))
    for e in errors:
        if e.diverged:
            why = e.ended or f"cart error {e.cart_error:.2g} m"
            print(
                f"{e.scheme}, cart {e.cart_mass:g} kg, step {e.step:g} s: the exchange diverged ({why})"
                + (
                    "; the cart is too light against the chain's apparent mass for an explicit "
                    "exchange (added-mass effect): --scheme apparent-mass"
                    if e.scheme == "explicit"
                    else ""
                )
            )
    print(f"wrote {args.out / 'coupling_error.csv'} and {args.out / 'coupling.png'}")
    return 0
