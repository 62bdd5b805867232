"""`conical-pendulum linearize`: A, B, C, D of an FMU at an operating point (analysis/linearize/),
its modes printed, the model written as .npz or .mat, a chain's mode shapes drawn."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from ..analysis import linearize as linear
from ..builder.fmu import fmu_scene
from ..errors import UserError
from .common import positive, start_value


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description += (
        "\n\nThe model x' - dx0 = A (x - x0) + B (u - u0), y - y0 = C (x - x0) + D (u - u0) of any FMI 2.0\n"
        "or 3.0 FMU with Model Exchange, at its start after initialization or at states, inputs\n"
        "and parameters given by name (a * or ? matches many: 'alpha*=0'). From the FMU's\n"
        "directional derivatives, grouped by its ModelStructure's sparsity, where it gives them;\n"
        "from extrapolated central differences with an error estimate where it does not. This\n"
        "project's FMUs start swinging at 10 degrees: --state 'alpha*=0' --state 'beta*=0' is the\n"
        "chain hanging at rest. Prints how stiff A is (its fastest mode and stiffness ratio), the\n"
        "modes (frequency in rad/s and Hz, damping ratio, the largest components) and writes the\n"
        "model with its names (docs/linear.md)."
    )
    parser.add_argument("fmu", type=Path, metavar="FMU", help="an FMI 2.0 or 3.0 FMU with Model Exchange")
    for option, what in (("state", "state"), ("input", "input"), ("parameter", "parameter or start value")):
        parser.add_argument(
            f"--{option}",
            type=start_value,
            action="append",
            default=[],
            metavar="NAME=VALUE",
            help=f"a {what} at the operating point; repeat for more",
        )
    parser.add_argument(
        "--time", type=float, default=0.0, metavar="SECONDS", help="the time of the point (0)"
    )
    parser.add_argument(
        "--method",
        choices=("auto", "directional", "differences"),
        default="auto",
        help="the FMU's directional derivatives, differences, or the first it allows (auto)",
    )
    parser.add_argument(
        "--one-per-column", action="store_true", help="one call per column instead of grouping by sparsity"
    )
    parser.add_argument(
        "--out",
        type=Path,
        action="append",
        default=[],
        metavar="FILE",
        help="write the model to FILE.npz or FILE.mat (names included); repeat for both",
    )
    parser.add_argument("--modes", type=int, default=12, metavar="N", help="print the lowest N modes (12)")
    parser.add_argument(
        "--plot", type=Path, metavar="PNG", help="draw a chain's lowest mode shapes (this project's FMUs)"
    )


def run(args) -> int:
    positive("--modes", args.modes)
    if args.plot is not None:  # before the work: the chain's lengths come from its scene
        try:
            scene = fmu_scene(args.fmu)
        except ValueError as exc:
            raise UserError(f"--plot: draws this project's chains only: {exc}") from None
    for path in args.out:
        if path.suffix not in (".npz", ".mat"):
            raise UserError(f"--out {path}: write a linear model to a .npz or a .mat file")
    begin = time.perf_counter()
    model = linear.linearize(
        args.fmu,
        states=dict(args.state),
        inputs=dict(args.input),
        parameters=dict(args.parameter),
        time=args.time,
        method=args.method,
        grouped=not args.one_per_column,
    )
    seconds = time.perf_counter() - begin
    print(
        f"{args.fmu}: {len(model.states)} states, {len(model.inputs)} inputs, {len(model.outputs)} outputs "
        f"at t = {model.time:g}; {model.method}: {model.calls} calls, {seconds:.3g} s"
    )
    if model.error is not None:
        print(f"differences' largest error estimate: {model.error.max():.2g} (per entry: the files' 'error')")
    print(model.stiffness().describe())
    modes = model.modes()
    print("\n".join(linear.describe_modes(modes[: args.modes])))
    if len(modes) > args.modes:
        print(f"... {len(modes) - args.modes} more (--modes N)")
    for path in args.out:
        print(f"wrote {model.save(path)}")
    if args.plot is not None:
        from ..viz.modes import plot_chain_modes

        lengths = [dict(args.parameter).get(f"l{i}", link.length) for i, link in enumerate(scene.links)]
        print(f"wrote {plot_chain_modes(model, lengths, args.plot)}")
    return 0
