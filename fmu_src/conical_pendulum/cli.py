"""The `conical-pendulum` command (also `python -m conical_pendulum`): one entry point, eight subcommands.

This module is the entry point only: the table of commands (COMMANDS), argparse, the
dispatch, and the one place where errors become a line and an exit status. Each
subcommand is a module of its own in commands/ (build, check, linearize, show, page, sweep, demo, system),
with `add_arguments(parser)` and `run(args) -> int`, its options defined once there.
Only the chosen subcommand's module is imported, so `--help` is quick and `build` needs
neither the sweep extra (Dask) nor the cosim one (ecospy). Being this package's code, a
sweep's tasks pickle by reference to conical_pendulum.analysis.sweep's modules, which the workers
import, and not as code of a `__main__` they do not have.

A mistake the user can fix (a bad option or value, a missing or unreadable file, a missing
optional package) is one line on stderr, `conical-pendulum <command>: <what is wrong>`, and
exit status 2, never a traceback; Ctrl-C is `<command>: interrupted` and status 130. Library
code raises errors.UserError (or its own ValueError, which the commands translate) and
never prints them or exits: only this module turns them into a line and a status.
`build_fmu.py` runs `build` the same way, as `build_fmu.py: ...`.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version

from .errors import DISTRIBUTION, UserError, needs

PROG = "conical-pendulum"


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
    module: str  # where add_arguments and run are, imported only when the command runs
    extra: str = ""  # the pip extra of the optional dependencies the module imports


COMMANDS = {
    "build": Command(
        "build a scene's FMU, check it against the native reference, draw its run",
        (
            "conical-pendulum build --links 5 --no-bobs --output dist/Chain5.fmu",
            "conical-pendulum build --scene scenes/seed.toml --no-check",
        ),
        "conical_pendulum.commands.build",
    ),
    "check": Command(
        "run an FMU with fmpy against the native reference of its scene",
        ("conical-pendulum check dist/ConicalPendulum.fmu --stop-time 5",),
        "conical_pendulum.commands.check",
    ),
    "linearize": Command(
        "A, B, C, D of an FMU at an operating point, its modes, as .npz or .mat",
        (
            "conical-pendulum linearize dist/ConicalPendulum_native.fmu --state 'alpha*=0' --state 'beta*=0'",
            "conical-pendulum linearize dist/Chain30.fmu --state 'alpha*=0' --state 'beta*=0' --out chain.mat",
        ),
        "conical_pendulum.commands.linearize",
    ),
    "show": Command(
        "plot and animate an fmpy results CSV",
        ("conical-pendulum show dist/ConicalPendulum.csv --plot out.png --gif out.gif --fps 30",),
        "conical_pendulum.commands.show",
    ),
    "page": Command(
        "write (and serve) the pydy.viz page of an FMU run, to play in a browser",
        ("conical-pendulum page dist/ConicalPendulum.fmu --out dist/page --serve",),
        "conical_pendulum.commands.page",
    ),
    "sweep": Command(
        "run an FMU over a grid or random sample of values on Dask, into Parquet",
        (
            "conical-pendulum sweep dist/ConicalPendulum.fmu --grid l0=5,10 --grid alpha0=0.1,0.2",
            "conical-pendulum sweep dist/ConicalPendulum.fmu --random l0=5:15 --samples 100",
        ),
        "conical_pendulum.commands.sweep",  # its --help without the extra; a sweep needs it
    ),
    "demo": Command(
        "co-simulate the pendulum on a cart in ecospy by two schemes, against one monolithic model",
        (
            "conical-pendulum demo --out dist/coupled --steps 0.1,0.05,0.025",
            "conical-pendulum demo --scheme apparent-mass --cart-mass 0.5 --steps 0.2,0.01",
        ),
        "conical_pendulum.commands.demo",
        "cosim",
    ),
    "system": Command(
        "write the coupled demo as an SSP 1.0 package and run it in ecos, libcosim and FMPy",
        (
            "conical-pendulum system --out dist/system",
            "conical-pendulum system --cart-mass 100,5 --step 0.1,0.01 --run all",
        ),
        "conical_pendulum.commands.system",
    ),
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

    def add_argument(self, action):
        super().add_argument(action)
        # argparse measures the commands' names at the list's indent, but writes them two
        # columns further in: a name as long as 'linearize' would push its summary down a line
        if isinstance(action, argparse._SubParsersAction):
            self._action_max_length += 2


def _parser(prog: str, chosen: str | None) -> Parser:
    parser = Parser(
        prog=prog,
        formatter_class=_CommandsFormatter,
        description="An n-link conical pendulum as FMI 2.0 and 3.0 FMUs: build one, check it against\n"
        "the native reference, look at its runs, sweep it, co-simulate it.",
        epilog="Start with 'conical-pendulum build': it writes dist/ConicalPendulum.fmu (the seed scene),\n"
        "checks it and draws its run in dist/ConicalPendulum.png and dist/ConicalPendulum.gif.\n"
        f"'{prog} COMMAND --help' explains a command's options.\n"
        "Exit status: 0 on success, 1 when a check, some runs or a co-simulation failed, 2 for\n"
        "bad options, a bad file or a missing package (one line on stderr), 130 on Ctrl-C.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    commands = parser.add_subparsers(
        title="commands", metavar="COMMAND", dest="command", required=True, parser_class=Parser
    )
    for name, command in COMMANDS.items():
        examples = "\n".join(f"  $ {example}" for example in command.examples)
        # listed verbatim (_CommandsFormatter): the summary, then the examples below it
        sub = commands.add_parser(
            name, help=f"{command.summary}\n{examples}", formatter_class=argparse.RawDescriptionHelpFormatter
        )
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
        raise UsageError(needs(exc.name, command.extra), parser.prog) from None
    module.add_arguments(parser)
    parser.set_defaults(run=module.run, parser=parser)


def _version() -> str:
    try:
        return version(DISTRIBUTION)
    except PackageNotFoundError:
        return "(not installed)"
