"""The `conical-pendulum` command (also `python -m conical_pendulum`): one entry point, six subcommands.

Each option is defined once: build, check and page here; show in viz/plots.py, sweep in
analysis/sweep.py and demo in demos/coupled.py, each as `add_arguments(parser)` and
`run(args) -> int`. Only the chosen subcommand's module is imported, so `--help` is quick
and `build` needs neither the sweep extra (Dask) nor the cosim one (ecospy). Being this
package's code, a sweep's tasks pickle by reference to conical_pendulum.analysis.sweep,
which the workers import, and not as code of a `__main__` they do not have.

A mistake the user can fix (a bad option or value, a missing or unreadable file, a missing
optional package) is one line on stderr, `conical-pendulum <command>: <what is wrong>`, and
exit status 2, never a traceback; Ctrl-C is `<command>: interrupted` and status 130. Library
code raises errors.UserError (or its own ValueError, which the commands here translate)
and never prints them or exits: only this module turns them into a line and a status.
`build_fmu.py` runs `build` the same way, as `build_fmu.py: ...`.
"""
from __future__ import annotations

import argparse
import importlib
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from .errors import UserError

PROG = "conical-pendulum"
ANGLE_TOLERANCE = 1e-8  # rad: the FMU against the native reference, for build and check


class UsageError(UserError):
    """A bad command line, found while parsing it: `<prog>: <message>` on one line, exit
    status 2; `prog` names the (sub)command when the error comes before it is chosen."""

    def __init__(self, message: str, prog: str | None = None):
        super().__init__(message)
        self.prog = prog


class Parser(argparse.ArgumentParser):
    """argparse, with its errors raised as UsageError: one line, not the usage block."""

    def error(self, message):
        raise UsageError(f"{message} (see --help)", self.prog)


@dataclass(frozen=True)
class Command:
    summary: str
    examples: tuple[str, ...]
    module: str      # where add_arguments and run are, imported only when the command runs
    extra: str = ""  # the pip extra of the optional dependencies the module imports


COMMANDS = {
    "build": Command(
        "build a scene's FMU, check it against the native reference, draw its run",
        ("conical-pendulum build --links 5 --no-bobs --output dist/Chain5.fmu",
         "conical-pendulum build --scene scenes/seed.toml --no-check"),
        "conical_pendulum.cli"),
    "check": Command(
        "run an FMU with fmpy against the native reference of its scene",
        ("conical-pendulum check dist/ConicalPendulum.fmu --stop-time 5",),
        "conical_pendulum.cli"),
    "show": Command(
        "plot and animate an fmpy results CSV",
        ("conical-pendulum show dist/results.csv --plot out.png --gif out.gif --fps 30",),
        "conical_pendulum.viz.plots"),
    "page": Command(
        "write (and serve) the pydy.viz page of an FMU run, to play in a browser",
        ("conical-pendulum page dist/ConicalPendulum.fmu --out dist/page --serve",),
        "conical_pendulum.cli"),
    "sweep": Command(
        "run an FMU over a grid or random sample of values on Dask, into Parquet",
        ("conical-pendulum sweep dist/ConicalPendulum.fmu --grid l0=5,10 --grid alpha0=0.1,0.2",
         "conical-pendulum sweep dist/ConicalPendulum.fmu --random l0=5:15 --samples 100"),
        "conical_pendulum.analysis.sweep", "sweep"),
    "demo": Command(
        "co-simulate the pendulum on a cart in ecospy by two schemes, against one monolithic model",
        ("conical-pendulum demo --out dist/coupled --steps 0.1,0.05,0.025",
         "conical-pendulum demo --scheme apparent-mass --cart-mass 0.5 --steps 0.2,0.01"),
        "conical_pendulum.demos.coupled", "cosim"),
}


def main(argv=None, prog: str = PROG) -> int:
    """Run the command line `argv` (default: sys.argv[1:]); its exit status."""
    argv = list(sys.argv[1:] if argv is None else argv)
    # the subcommand: the first word that is not an option (the top level has only -h, --version)
    chosen = next((word for word in argv if not word.startswith("-")), None)

    def parse():
        args, extra = _parser(prog, chosen).parse_known_args(argv)
        if extra:
            args.parser.error(f"unrecognized arguments: {' '.join(extra)}")
        return args

    return _exit_status(prog, parse)


def run_command(name: str, argv=None, prog: str | None = None) -> int:
    """One subcommand as a program of its own (`build_fmu.py` is `build`)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    prog = prog or f"{PROG} {name}"

    def parse():
        parser = Parser(prog=prog, formatter_class=argparse.RawDescriptionHelpFormatter)
        _load(name, parser)
        return parser.parse_args(argv)

    return _exit_status(prog, parse)


def _exit_status(prog: str, parse) -> int:
    """Run the command parse() returns, as a program: a UserError is one line on stderr
    and its status (2 for a UsageError), Ctrl-C status 130, each named after the command
    once it is parsed."""
    args = None

    def named():
        return prog if args is None else args.parser.prog

    try:
        args = parse()
        return args.run(args)
    except UserError as exc:
        print(f"{getattr(exc, 'prog', None) or named()}: {exc}", file=sys.stderr)
        return exc.status
    except KeyboardInterrupt:
        print(f"{named()}: interrupted", file=sys.stderr)
        return 130


class _CommandsFormatter(argparse.RawDescriptionHelpFormatter):
    """The top level's help: each command's summary and examples on lines of their own."""

    def _split_lines(self, text, width):
        return text.splitlines()


def _parser(prog: str, chosen: str | None) -> Parser:
    parser = Parser(
        prog=prog, formatter_class=_CommandsFormatter,
        description="An n-link conical pendulum as an FMI 2.0 co-simulation FMU: build it, check it\n"
                    "against the native reference, look at its runs, sweep it, co-simulate it.",
        epilog="Start with 'conical-pendulum build': it writes dist/ConicalPendulum.fmu (the seed scene),\n"
               "checks it and draws its run in dist/pendulum.png and dist/pendulum.gif.\n"
               f"'{prog} COMMAND --help' explains a command's options.\n"
               "Exit status: 0 on success, 1 when a check, some runs or a co-simulation failed, 2 for\n"
               "bad options, a bad file or a missing package (one line on stderr), 130 on Ctrl-C.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    commands = parser.add_subparsers(title="commands", metavar="COMMAND", dest="command", required=True,
                                     parser_class=Parser)
    for name, command in COMMANDS.items():
        examples = "\n".join(f"  $ {example}" for example in command.examples)
        # listed verbatim (_CommandsFormatter): the summary, then the examples below it
        sub = commands.add_parser(name, help=f"{command.summary}\n{examples}",
                                  formatter_class=argparse.RawDescriptionHelpFormatter)
        if name == chosen:
            _load(name, sub)
    return parser


def _load(name: str, parser: Parser) -> None:
    """The command's options on `parser`, and what runs it."""
    command = COMMANDS[name]
    examples = "\n".join(f"  {example}" for example in command.examples)
    parser.description = f"{command.summary[0].upper()}{command.summary[1:]}.\n\nExample:\n{examples}"
    try:
        module = importlib.import_module(command.module)
    except ModuleNotFoundError as exc:
        if not command.extra:
            raise
        raise UsageError(f"needs {exc.name}: pip install -e \".[{command.extra}]\"", parser.prog) from None
    if module.__name__ == __name__:  # build, check and page live here
        add_arguments, run = getattr(module, f"_{name}_arguments"), getattr(module, f"_{name}")
    else:
        add_arguments, run = module.add_arguments, module.run
    add_arguments(parser)
    parser.set_defaults(run=run, parser=parser)


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("conical-pendulum-fmu")
    except PackageNotFoundError:
        return "(not installed)"


# ---- build ----

def _build_arguments(parser: argparse.ArgumentParser) -> None:
    from .scene import KINEMATICS, MAX_LINKS

    parser.description += (
        "\n\nWithout --scene, the options describe a uniform chain (3 links with bobs by default).\n"
        "After the build, unless --no-check, the FMU runs with fmpy (10 s, an output every 1/60 s,\n"
        "DOP853 at 1e-12) against the native scipy integration of the same scene; the run goes to\n"
        "results.csv, pendulum.png and pendulum.gif next to the FMU. Exit status 1 when the\n"
        "angles disagree by more than 1e-8 rad.")
    scene = parser.add_argument_group("the scene")
    scene.add_argument("--scene", type=Path, metavar="FILE",
                       help="a scene file (TOML or JSON, see scenes/seed.toml), instead of the options below")
    scene.add_argument("--links", type=int, metavar="N", help=f"number of links, 1 to {MAX_LINKS} (3)")
    scene.add_argument("--massless-links", action="store_true", help="links without mass or inertia")
    scene.add_argument("--no-bobs", action="store_true", help="no bobs at the joints")
    scene.add_argument("--kinematics", choices=KINEMATICS,
                       help="'pydy-example' reproduces the published (energy-violating) equations "
                            "(default: consistent)")
    scene.add_argument("--coupling", action="store_true",
                       help="inputs a_pivot_x/y/z (the support's acceleration) and outputs "
                            "F_pivot_x/y/z (the force on it), with its split F_free_x/y/z, M_pivot_xx..zz")
    parser.add_argument("--output", type=Path, default=Path("dist/ConicalPendulum.fmu"), metavar="PATH",
                        help="the FMU to write, ending in .fmu (dist/ConicalPendulum.fmu)")
    parser.add_argument("--native", action="store_true",
                        help="the native FMU: FMI glue in C, no Python at run time (docs/native.md)")
    parser.add_argument("--win64", action="store_true",
                        help="with --native: also a Windows binary, cross-compiled (needs mingw-w64)")
    parser.add_argument("--no-check", action="store_true",
                        help="only build; skip the fmpy run against the native integrator, "
                             "its plot and its animation")


def _choose_scene(args):
    from .scene import Scene, load_scene

    options = [name for name, given in [("--links", args.links is not None),
                                        ("--massless-links", args.massless_links),
                                        ("--no-bobs", args.no_bobs),
                                        ("--kinematics", args.kinematics is not None),
                                        ("--coupling", args.coupling)] if given]
    if args.scene:
        if options:
            raise UsageError(f"--scene describes the whole scene; drop {', '.join(options)}")
        return load_scene(args.scene)
    return Scene.uniform(3 if args.links is None else args.links,
                         massless_links=args.massless_links, bobs=not args.no_bobs,
                         kinematics=args.kinematics or "consistent", coupling=args.coupling)


def _build(args) -> int:
    from .scene import SceneError

    try:
        scene = _choose_scene(args)
    except SceneError as exc:
        raise UsageError(str(exc)) from None
    if args.win64 and not args.native:
        raise UsageError("--win64: only the native FMU carries a Windows binary; add --native")
    from .builder.fmu import build_fmu

    try:
        build = build_fmu(scene, args.output, backend="native" if args.native else "pythonfmu",
                          platforms=("linux64", "win64") if args.win64 else ("linux64",))
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    how = "from cache" if build.core.cached else "compiled " + ", ".join(
        f"{k} {v:.1f} s" for k, v in build.core.seconds.items())
    print(f"built {build.path} ({build.path.stat().st_size / 1024:.0f} KiB) in {build.seconds:.1f} s: "
          f"{scene.n} links, {len(scene.parameter_names())} parameters, {len(scene.input_names())} inputs, "
          f"{len(scene.output_names())} calculated outputs; {'native, ' if args.native else ''}core {how}")
    if args.no_check:
        return 0
    comparison, ok = _compare(build.path, scene)
    _draw(comparison.result, args.output.parent)
    return 0 if ok else 1


def _compare(fmu: Path, scene, stop_time: float = 10.0, interval: float = 1.0 / 60.0, rtol: float = 1e-12):
    """Run the FMU against the native reference and print the report: (comparison, angles agree)."""
    from .analysis.compare import compare

    start = time.perf_counter()
    comparison = compare(fmu, scene, stop_time=stop_time, output_interval=interval, rtol=rtol, atol=rtol)
    print(f"fmpy.simulate_fmu, {stop_time:g} s at {1 / interval:g} outputs/s, DOP853 rtol = atol = {rtol:g}, "
          f"against native scipy DOP853 ({time.perf_counter() - start:.1f} s):")
    print(comparison.report())
    error = comparison.angle_error()
    ok = error <= ANGLE_TOLERANCE
    print(f"angles agree to {error:.2e} rad: {'OK' if ok else 'FAILED'}")
    return comparison, ok


def _draw(result, folder: Path) -> None:
    """The run as CSV, a plot and an animation, next to the FMU: as much of them as the
    scene's outputs allow, and one line saying what was left out and why."""
    from fmpy.util import write_csv

    from .viz import plots

    csv, png, gif = folder / "results.csv", folder / "pendulum.png", folder / "pendulum.gif"
    write_csv(str(csv), result)
    results = plots.load_results(csv)
    lacking = plots.missing(results)
    plots.plot(results, png)
    if "the animation" in lacking:
        print(f"wrote {csv} and {png}")
    else:
        seconds = plots.animate(results, gif)
        print(f"wrote {csv}, {png} and {gif} (animation rendered in {seconds:.1f} s)")
    if lacking:
        print(plots.left_out(lacking))


# ---- check ----

def _positive(option: str, value: float) -> float:
    if not (value > 0 and value != float("inf")):
        raise UsageError(f"{option}: must be a positive number, got {value:g}")
    return value


def _fmu_scene(path: Path):
    from .builder.fmu import fmu_scene

    try:
        return fmu_scene(path)
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def _check_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description += (
        "\n\nThe scene comes from the FMU (the one it was built from, in its resources). The FMU\n"
        "runs with fmpy, its DOP853 at --rtol; the native reference is scipy's DOP853 at 1e-12 (or\n"
        "--rtol if tighter) on the same output grid. Prints every output's largest difference.\n"
        "Exit status 1 when the angles disagree by more than 1e-8 rad.")
    parser.add_argument("fmu", type=Path, metavar="FMU", help="an FMU built by conical-pendulum build")
    parser.add_argument("--stop-time", type=float, default=10.0, metavar="SECONDS",
                        help="simulated seconds (10)")
    parser.add_argument("--interval", type=float, default=1.0 / 60.0, metavar="SECONDS",
                        help="output interval, where the runs are compared (1/60)")
    parser.add_argument("--rtol", type=float, default=1e-12,
                        help="the FMU's relative (and absolute) tolerance (1e-12)")


def _check(args) -> int:
    for option in ("stop_time", "interval", "rtol"):
        _positive(f"--{option.replace('_', '-')}", getattr(args, option))
    scene = _fmu_scene(args.fmu)
    _, ok = _compare(args.fmu, scene, args.stop_time, args.interval, args.rtol)
    return 0 if ok else 1


# ---- page ----

def _start_value(text: str) -> tuple[str, float]:
    name, equals, value = text.partition("=")
    try:
        if name and equals:
            return name, float(value)
    except ValueError:
        pass
    raise argparse.ArgumentTypeError(f"{text!r}: expected NAME=NUMBER")


def _page_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description += (
        "\n\nRuns the FMU with fmpy (an output every 1/60 s) and writes pydy.viz's page of the\n"
        "scene it was built from (a cylinder per link, a sphere per bob) and of that run into\n"
        "DIR/pydy-resources. The page fetches its data from the web root: serve that folder,\n"
        "with --serve or `python -m http.server`, and open the address printed. Needs pydy.")
    parser.add_argument("fmu", type=Path, metavar="FMU", help="an FMU built by conical-pendulum build")
    parser.add_argument("--out", type=Path, required=True, metavar="DIR",
                        help="folder for the page (its pydy-resources folder)")
    parser.add_argument("--stop-time", type=float, default=10.0, metavar="SECONDS",
                        help="simulated seconds (10)")
    parser.add_argument("--start", type=_start_value, action="append", default=[], metavar="NAME=VALUE",
                        help="a parameter or state start value, e.g. alpha0=0.5 or l0=8; repeat for more")
    parser.add_argument("--serve", action="store_true",
                        help="serve the page on 127.0.0.1 until Ctrl-C")
    parser.add_argument("--port", type=int, default=8000,
                        help="with --serve: the port (8000; 0 picks a free one)")


def _start_values(fmu: Path, given: list[tuple[str, float]]) -> dict:
    """The --start values as the FMU's types; unknown and calculated variables refused."""
    from fmpy import read_model_description
    from fmpy.simulation import settable_in_initialization_mode, settable_in_instantiated

    variables = {v.name: v for v in read_model_description(str(fmu)).modelVariables}
    values = {}
    for name, value in given:
        variable = variables.get(name)
        if variable is None:
            raise UsageError(f"--start {name}={value:g}: the FMU has no variable {name!r}")
        if not (settable_in_instantiated(variable) or settable_in_initialization_mode(variable)):
            raise UsageError(f"--start {name}={value:g}: {name} is calculated; set parameters and states")
        if variable.type == "Integer":
            if not value.is_integer():
                raise UsageError(f"--start {name}={value:g}: {name} is an Integer variable")
            value = int(value)
        values[name] = value
    return values


def _page(args) -> int:
    _positive("--stop-time", args.stop_time)
    if not 0 <= args.port < 65536:
        raise UsageError(f"--port: {args.port} is not a port number")
    try:
        import pydy  # noqa: F401 - before any work; write_pydy_page imports it when it runs
    except ModuleNotFoundError as exc:
        raise UsageError(f"needs {exc.name}: pip install pydy (or -e \".[test]\")") from None
    if args.out.exists() and not args.out.is_dir():
        raise UsageError(f"--out {args.out}: not a directory")
    scene = _fmu_scene(args.fmu)
    start_values = _start_values(args.fmu, args.start)
    from .analysis.fmpy_runs import run_fmu
    from .viz.pydy_page import write_pydy_page

    run = run_fmu(args.fmu, args.stop_time, 1.0 / 60.0, start_values)
    try:
        folder, address = write_pydy_page(scene, {name: run[name] for name in run.dtype.names}, args.out)
    except OSError as exc:
        raise UsageError(f"--out {args.out}: {exc.strerror or exc}") from None
    print(f"wrote the pydy.viz page of {args.fmu} ({args.stop_time:g} s) into {folder}")
    if args.serve:
        return _serve(folder, address, args.port)
    print(f"serve that folder and open the page:\n"
          f"    python -m http.server --bind 127.0.0.1 --directory {folder} {args.port or 8000}\n"
          f"    http://127.0.0.1:{args.port or 8000}/{address}\n"
          f"(or add --serve)")
    return 0


def _serve(folder: Path, address: str, port: int) -> int:
    import functools
    import http.server

    class Handler(http.server.SimpleHTTPRequestHandler):
        def log_message(self, format, *args):  # noqa: A002 - http.server's name
            pass  # quiet: a page load is some hundred requests

    try:
        server = http.server.ThreadingHTTPServer(
            ("127.0.0.1", port), functools.partial(Handler, directory=str(folder)))
    except OSError as exc:
        raise UsageError(f"--port {port}: cannot serve there ({exc.strerror or exc})") from None
    with server:
        print(f"serving {folder} at http://127.0.0.1:{server.server_address[1]}/ ; open\n"
              f"    http://127.0.0.1:{server.server_address[1]}/{address}\n"
              f"Ctrl-C stops.", flush=True)
        try:
            server.serve_forever()
        except KeyboardInterrupt:
            print("stopped")
    return 0
