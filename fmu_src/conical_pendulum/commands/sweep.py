"""`conical-pendulum sweep`: many runs of an FMU as Dask tasks, streamed into a Parquet
dataset (analysis/sweep/; the sweep extra)."""

from __future__ import annotations

import argparse
import math
import shlex
import sys
import time
from pathlib import Path

from ..analysis.runner import LOOPS
from ..errors import UserError, needs


def _assignment(text: str, form: str) -> tuple[str, str]:
    name, equals, value = text.partition("=")
    if not (name and equals and value):
        raise argparse.ArgumentTypeError(f"{text!r}: expected {form}")
    return name, value


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None


def grid_axis(text: str) -> tuple[str, list[float]]:
    name, values = _assignment(text, "NAME=V1,V2,...")
    return name, [_number(value) for value in values.split(",")]


def value_range(text: str) -> tuple[str, tuple[float, float]]:
    name, bounds = _assignment(text, "NAME=LOW:HIGH")
    low, colon, high = bounds.partition(":")
    if not colon:
        raise argparse.ArgumentTypeError(f"{text!r}: expected NAME=LOW:HIGH")
    return name, (_number(low), _number(high))


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a whole number of at least 1")
    return value


def seconds(text: str) -> float:
    value = _number(text)
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r}: expected a positive number of seconds")
    return value


EXTRA = "sweep"  # the pip extra holding what a sweep imports (Dask, pandas, pyarrow)

EPILOG = """Variables: the FMU's parameters (l0, m0, M0, Ixx0, g, rtol, solver, ...) and state
start values (alpha0, beta0, omega0, delta0, ...). The output is a folder of Parquet
files (pandas.read_parquet, dask, duckdb read it), one row per run and time: run, the
inputs (a state's start value as <name>_start), status ('ok' or 'failed'), message,
time, the outputs. A run that kills its worker process twice, or exceeds --run-timeout
once, fails with the signal that ended it, and the sweep goes on. An interrupted sweep
(Ctrl-C, a killed command, a lost cluster, no worker for --no-workers-timeout) keeps
what it wrote: the same command with --resume runs only what is missing.
Exit status: 0 when every run succeeded, 1 when some failed (they are in the output),
2 for bad options or when the sweep could not run, 130 on Ctrl-C."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    try:  # the sweep package's own account of itself; without the sweep extra, what to install
        from ..analysis import sweep as sweeps

        parser.description = "\n\n".join(sweeps.__doc__.split("\n\n")[:2])
    except ModuleNotFoundError as exc:
        parser.description += f"\n\nThis copy cannot run it yet: it {needs(exc.name, EXTRA)}."
    parser.epilog = EPILOG
    parser.add_argument("fmu", type=Path, help="the FMU (FMI 2.0 co-simulation)")
    runs = parser.add_mutually_exclusive_group(required=True)
    runs.add_argument(
        "--grid",
        type=grid_axis,
        action="append",
        metavar="NAME=V1,V2,...",
        help="values of one variable; repeat for more: every combination is run",
    )
    runs.add_argument(
        "--random",
        type=value_range,
        action="append",
        metavar="NAME=LOW:HIGH",
        help="a range of one variable, sampled uniformly; repeat for more",
    )
    parser.add_argument("--samples", type=positive_int, help="with --random: how many runs")
    parser.add_argument("--seed", type=int, help="with --random: seed for reproducible samples")
    parser.add_argument("--stop-time", type=float, default=10.0, help="simulated seconds per run (10)")
    parser.add_argument("--interval", type=float, default=1.0 / 60.0, help="output interval [s] (1/60)")
    parser.add_argument(
        "--outputs",
        type=lambda text: text.split(","),
        metavar="NAME,NAME,...",
        help="variables to record (default: every output)",
    )
    parser.add_argument(
        "--workers", type=positive_int, help="worker processes of the local cluster made for the sweep (2)"
    )
    parser.add_argument(
        "--scheduler", metavar="ADDRESS", help="run on an existing cluster instead, e.g. tcp://host:8786"
    )
    parser.add_argument(
        "--connect-timeout",
        type=float,
        default=10.0,
        metavar="SECONDS",
        help="with --scheduler: how long to try to connect (10)",
    )
    parser.add_argument(
        "--run-timeout",
        type=seconds,
        metavar="SECONDS",
        help="end a run's worker process when the run takes longer, and fail the run (no limit)",
    )
    parser.add_argument(
        "--no-workers-timeout",
        type=seconds,
        default=60.0,
        metavar="SECONDS",
        help="stop the sweep (resumable) when no worker has been alive this long (60)",
    )
    parser.add_argument("--batch", type=positive_int, help="runs per task (default: automatic)")
    parser.add_argument(
        "--loop",
        choices=LOOPS,
        default="runner",
        help="the communication loop: the compiled runner (default; fmpy's where it cannot "
        "be compiled) or fmpy's own; the same results",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("sweep.parquet"),
        help="the Parquet dataset, a folder (sweep.parquet); an existing one is refused unless "
        "--resume or --overwrite",
    )
    existing = parser.add_mutually_exclusive_group()
    existing.add_argument(
        "--resume",
        action="store_true",
        help="finish the interrupted sweep in --out: only the runs it misses (the same arguments)",
    )
    existing.add_argument("--overwrite", action="store_true", help="replace the sweep in --out")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")


def check_options(args) -> None:
    """What argparse cannot say alone: options that go together or exclude each other."""
    given = args.grid or args.random
    if len({name for name, _ in given}) < len(given):
        raise UserError("a variable is given twice")
    if args.random and args.samples is None:
        raise UserError("--random needs --samples")
    if args.grid and (args.samples is not None or args.seed is not None):
        raise UserError("--samples and --seed go with --random")
    if args.scheduler and args.workers is not None:
        raise UserError("--workers is for the local cluster; drop it with --scheduler")


def run(args) -> int:
    """0 when every run succeeded, 1 when some failed; UserError (exit 2) for bad options or
    when the sweep could not run."""
    check_options(args)
    try:  # the sweep extra (Dask, pandas, pyarrow), imported when a sweep runs
        from ..analysis import sweep as sweeps
    except ModuleNotFoundError as exc:
        raise UserError(needs(exc.name, EXTRA)) from None
    try:
        runs = (
            sweeps.grid(dict(args.grid))
            if args.grid
            else sweeps.random_samples(dict(args.random), args.samples, args.seed)
        )
        start = time.perf_counter()
        results = sweeps.sweep(
            args.fmu,
            runs,
            stop_time=args.stop_time,
            output_interval=args.interval,
            outputs=args.outputs,
            scheduler=args.scheduler,
            n_workers=args.workers or 2,
            batch=args.batch,
            out=args.out,
            progress=not args.no_progress,
            timeout=args.connect_timeout,
            loop=args.loop,
            resume=args.resume,
            overwrite=args.overwrite,
            run_timeout=args.run_timeout,
            no_workers_timeout=args.no_workers_timeout,
        )
    except (ValueError, ConnectionError) as exc:
        raise UserError(str(exc)) from None
    except KeyboardInterrupt:
        if (args.out / sweeps.SETTINGS_FILE).exists():  # begun: what is done is kept
            print(f"sweep: stopped; the runs done are kept in {args.out}: {resume_hint()}", file=sys.stderr)
        raise
    seconds = time.perf_counter() - start
    failed = results.failed()
    total = results.attrs["runs"]
    earlier = f", {total - results.ran} done before" if results.ran < total else ""
    print(
        f"wrote {args.out}: {total} runs ({len(failed)} failed), {results.rows()} rows, "
        f"in {seconds:.1f} s ({results.ran / seconds:.1f} runs/s{earlier})"
    )
    for number, row in failed.head(5).iterrows():
        values = ", ".join(f"{name} = {row[name]:g}" for name in results.attrs["inputs"])
        print(f"  run {number} ({values}) failed: {row['message']}")
    if len(failed) > 5:
        print(f"  ... and {len(failed) - 5} more: status == 'failed' in the output")
    return 1 if len(failed) else 0


def resume_hint() -> str:
    """How to finish an interrupted sweep: this command again, with --resume."""
    command = [arg for arg in sys.argv[1:] if arg != "--overwrite"]
    return shlex.join(["conical-pendulum", *command, *([] if "--resume" in command else ["--resume"])])
