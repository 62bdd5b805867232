"""`conical-pendulum system`: the coupled demo as an SSP 1.0 package, and its runs in the
tools that read SSP (demos/ssp.py, demos/ssp_tools.py, demos/ssp_report.py)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..demos import coupled, ssp, ssp_report, ssp_tools
from ..errors import UserError, needs
from .common import check_cart_masses, check_steps, choices, numbers, output_folder


def tools(text: str) -> list[str]:
    return choices(text, ssp_tools.TOOLS, "tool", every="all")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description = (ssp.__doc__ or "") + "\n" + (ssp_tools.__doc__ or "")
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("dist") / "system",
        help="folder for the FMUs, the packages, system.png and, with --run, ssp_runs.csv and "
        "ssp_runs.png (dist/system)",
    )
    parser.add_argument(
        "--cart-mass",
        type=numbers,
        default=[100.0],
        metavar="KG,KG,...",
        help="the packages' m_cart [kg], comma-separated: one package per mass and step (100)",
    )
    parser.add_argument(
        "--step",
        type=numbers,
        default=[ssp.STEP],
        metavar="DT,DT,...",
        help=f"the packages' communication step [s] (the OSP and OMSimulator annotations), comma-separated; each must "
        f"divide the stop time and be a multiple of the smallest ({ssp.STEP:g})",
    )
    parser.add_argument(
        "--stop-time",
        type=float,
        default=coupled.STOP_TIME,
        metavar="SECONDS",
        help=f"the packages' default experiment [s] ({coupled.STOP_TIME:g})",
    )
    parser.add_argument(
        "--run",
        dest="tools",  # args.run is the command's entry (cli.py)
        type=tools,
        default=[],
        metavar="TOOL,TOOL,...",
        help=f"run every package by each scheme in these tools ({', '.join(ssp_tools.TOOLS)}, or all) "
        "against the monolithic model and today's demo",
    )


def run(args) -> int:
    """Build both FMUs, write and validate the packages and system.png; with --run, run
    them in each tool and write ssp_runs.csv and ssp_runs.png. 0; a UserError of status 2
    for bad options or a missing package, of status 1 when a tool ran and failed."""
    steps = args.step
    check_steps("--step", steps, args.stop_time)
    check_cart_masses(args.cart_mass)
    for tool in args.tools:
        lacking = ssp_tools.missing(tool)
        if lacking:  # before the builds, which take a while
            hint = f"needs {lacking}" if tool in ssp_tools.OUTSIDE_PIP else needs(lacking, "cosim")
            raise UserError(f"--run {tool}: {hint}")
    output_folder(args.out)
    from ..builder.fmu import build_fmu

    pendulum = build_fmu(coupled.SCENE, args.out / "ConicalPendulum.fmu", backend="native").path
    cart = coupled.build_cart_fmu(args.out / "Cart.fmu")
    try:
        packages = ssp_report.write_packages(args.out, pendulum, cart, args.cart_mass, steps, args.stop_time)
    except RuntimeError as exc:
        raise UserError(str(exc), status=1) from None
    ssp_report.draw_system(args.out / "system.png")
    print("\n".join(f"wrote {package} (valid SSP 1.0)" for package in packages))
    print(f"wrote {args.out / 'system.png'}")
    if not args.tools:
        return 0
    try:
        results, agreement = ssp_report.compare(
            args.out, pendulum, cart, args.cart_mass, steps, args.stop_time, args.tools
        )
    except RuntimeError as exc:
        raise UserError(str(exc), status=1) from None
    print("\n".join("\t".join(row) for row in ssp_report.write(results, args.out)))
    for (mass, scheme), difference in agreement.items():
        print(
            f"ecospy from the package against today's demo, {scheme}, cart {mass:g} kg: {difference:.3g} at most"
        )
    print(f"wrote {args.out / 'ssp_runs.csv'} and {args.out / 'ssp_runs.png'}")
    print(scratch_note(args.out / ssp_report.WORK))
    return 0


def scratch_note(work: Path) -> str:
    """What the runs leave behind, and where: kept to look into, a line says how much."""
    size = sum(f.stat().st_size for f in work.rglob("*") if f.is_file())
    return (
        f"left {size / 1e6:.0f} MB of the tools' scratch files (each one's unpacked packages, outputs "
        f"and logs) in {work}: delete the folder when done"
    )
