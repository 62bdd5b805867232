"""`conical-pendulum check`: an FMU run with fmpy against the native reference of its scene."""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import CHECK_BOUND, compare, fmu_scene, positive


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description += (
        "\n\nThe scene comes from the FMU (the one it was built from, in its resources). The FMU\n"
        "runs with fmpy, its DOP853 at --rtol; the native reference is scipy's DOP853 on the same\n"
        "output grid. Prints every output's largest difference and the angles' bound, and exits\n"
        f"with status 1 when the angles disagree by more than it:\n{CHECK_BOUND}."
    )
    parser.add_argument("fmu", type=Path, metavar="FMU", help="an FMU built by conical-pendulum build")
    parser.add_argument(
        "--stop-time", type=float, default=10.0, metavar="SECONDS", help="simulated seconds (10)"
    )
    parser.add_argument(
        "--interval",
        type=float,
        default=1.0 / 60.0,
        metavar="SECONDS",
        help="output interval, where the runs are compared (1/60)",
    )
    parser.add_argument(
        "--rtol", type=float, default=1e-12, help="the FMU's relative (and absolute) tolerance (1e-12)"
    )


def run(args) -> int:
    for option in ("stop_time", "interval", "rtol"):
        positive(f"--{option.replace('_', '-')}", getattr(args, option))
    scene = fmu_scene(args.fmu)
    _, ok = compare(args.fmu, scene, args.stop_time, args.interval, args.rtol)
    return 0 if ok else 1
