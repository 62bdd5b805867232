"""`conical-pendulum show`: the plot and the animation of an fmpy results CSV (viz/plots.py)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import UserError
from ..viz import plots


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "results",
        type=Path,
        metavar="RESULTS.csv",
        help="fmpy results CSV (fmpy.util.write_csv), e.g. build's dist/ConicalPendulum.csv",
    )
    parser.add_argument("--plot", type=Path, metavar="PNG", help="PNG of angles, paths from above and energy")
    parser.add_argument("--gif", type=Path, metavar="GIF", help="animated GIF of the chain in 3D")
    parser.add_argument(
        "--books",
        type=Path,
        metavar="PNG",
        help="PNG of the energy's books: energy, each force's work, energy less the work (scenes with forces)",
    )
    parser.add_argument("--fps", type=float, default=30.0, help="frames per simulated second (30)")


def run(args) -> int:
    """The plot and/or the animation of a results CSV; what the results cannot give is left
    out, and said in one line."""
    if not (args.plot or args.gif or args.books):
        raise UserError("give --plot, --gif and/or --books")
    if not args.fps > 0:
        raise UserError(f"--fps: must be positive, got {args.fps:g}")
    for option, path in (("--plot", args.plot), ("--gif", args.gif), ("--books", args.books)):
        if path and path.is_dir():
            raise UserError(f"{option} {path}: is a directory")
        if path and not path.parent.is_dir():
            raise UserError(f"{option} {path}: {path.parent} is not a directory")
    results = plots.load_results(args.results)
    asked = {"the paths": args.plot, "the energy drift": args.plot, "the animation": args.gif}
    lacking = {what: why for what, why in plots.missing(results).items() if asked[what]}
    try:
        if args.plot:
            plots.plot(results, args.plot)
            print(f"wrote {args.plot}")
        if args.books:
            plots.books(results, args.books)
            print(f"wrote {args.books}")
        if args.gif and "the animation" not in lacking:
            seconds = plots.animate(results, args.gif, fps=args.fps)
            print(f"wrote {args.gif} in {seconds:.1f} s")
    except OSError as exc:  # a folder that is not there, or not writable
        raise UserError(f"{exc.filename or 'writing'}: {exc.strerror or exc}") from None
    if lacking:
        print(plots.left_out(lacking))
    return 0
