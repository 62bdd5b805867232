"""`conical-pendulum page`: pydy.viz's page of an FMU run (viz/pydy_page.py), written and
served."""

from __future__ import annotations

import argparse
import functools
import http.server
import signal
from pathlib import Path

from fmpy import read_model_description
from fmpy.simulation import settable_in_initialization_mode, settable_in_instantiated

from ..analysis import fmpy_runs
from ..errors import UserError, needs
from ..viz.pydy_page import write_pydy_page
from .common import fmu_scene, positive, start_value


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description += (
        "\n\nRuns the FMU with fmpy (an output every 1/60 s) and writes pydy.viz's page of the\n"
        "scene it was built from (a cylinder per link, a sphere per bob) and of that run into\n"
        "DIR/pydy-resources. The page fetches its data from the web root: serve that folder,\n"
        "with --serve or `python -m http.server`, and open the address printed. Needs pydy."
    )
    parser.add_argument("fmu", type=Path, metavar="FMU", help="an FMU built by conical-pendulum build")
    parser.add_argument(
        "--out",
        type=Path,
        required=True,
        metavar="DIR",
        help="folder for the page (its pydy-resources folder)",
    )
    parser.add_argument(
        "--stop-time", type=float, default=10.0, metavar="SECONDS", help="simulated seconds (10)"
    )
    parser.add_argument(
        "--start",
        type=start_value,
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="a parameter or state start value, e.g. alpha0=0.5 or l0=8; repeat for more",
    )
    parser.add_argument(
        "--serve", action="store_true", help="serve the page on 127.0.0.1 until Ctrl-C (or SIGTERM)"
    )
    parser.add_argument(
        "--port", type=int, default=8000, help="with --serve: the port (8000; 0 picks a free one)"
    )


def start_values(fmu: Path, given: list[tuple[str, float]]) -> dict:
    """The --start values as the FMU's types; unknown and calculated variables refused."""
    variables = {v.name: v for v in read_model_description(str(fmu)).modelVariables}
    values = {}
    for name, value in given:
        variable = variables.get(name)
        if variable is None:
            raise UserError(f"--start {name}={value:g}: the FMU has no variable {name!r}")
        if not (settable_in_instantiated(variable) or settable_in_initialization_mode(variable)):
            raise UserError(f"--start {name}={value:g}: {name} is calculated; set parameters and states")
        if variable.type in fmpy_runs.WHOLE_TYPES:
            if not value.is_integer():
                raise UserError(f"--start {name}={value:g}: {name} is an {variable.type} variable")
            value = int(value)
        values[name] = value
    return values


def run(args) -> int:
    positive("--stop-time", args.stop_time)
    if not 0 <= args.port < 65536:
        raise UserError(f"--port: {args.port} is not a port number")
    try:
        import pydy  # noqa: F401 - before any work; write_pydy_page imports it when it runs
    except ModuleNotFoundError as exc:
        raise UserError(f"{needs(exc.name, 'test')} (or pip install pydy)") from None
    if args.out.exists() and not args.out.is_dir():
        raise UserError(f"--out {args.out}: not a directory")
    scene = fmu_scene(args.fmu)
    values = start_values(args.fmu, args.start)
    results = fmpy_runs.run_fmu(args.fmu, args.stop_time, 1.0 / 60.0, values)
    try:
        folder, address = write_pydy_page(
            scene, {name: results[name] for name in results.dtype.names}, args.out
        )
    except OSError as exc:
        raise UserError(f"--out {args.out}: {exc.strerror or exc}") from None
    print(f"wrote the pydy.viz page of {args.fmu} ({args.stop_time:g} s) into {folder}")
    if args.serve:
        return serve(folder, address, args.port)
    print(
        f"serve that folder and open the page:\n"
        f"    python -m http.server --bind 127.0.0.1 --directory {folder} {args.port or 8000}\n"
        f"    http://127.0.0.1:{args.port or 8000}/{address}\n"
        f"(or add --serve)"
    )
    return 0


def _stop(signum, frame):
    raise KeyboardInterrupt


def serve(folder: Path, address: str, port: int) -> int:
    """Serve `folder` on 127.0.0.1 until Ctrl-C or SIGTERM; 0. Both are caught here, since a
    process started in the background inherits SIGINT ignored (and Python then installs
    no KeyboardInterrupt for it), and SIGTERM would end it without a word."""

    class Handler(http.server.SimpleHTTPRequestHandler):
        def log_message(self, format, *args):  # format: http.server's name
            pass  # quiet: a page load is some hundred requests

    try:
        server = http.server.ThreadingHTTPServer(
            ("127.0.0.1", port), functools.partial(Handler, directory=str(folder))
        )
    except OSError as exc:
        raise UserError(f"--port {port}: cannot serve there ({exc.strerror or exc})") from None
    with server:
        print(
            f"serving {folder} at http://127.0.0.1:{server.server_address[1]}/ ; open\n"
            f"    http://127.0.0.1:{server.server_address[1]}/{address}\n"
            f"Ctrl-C stops.",
            flush=True,
        )
        previous = {number: signal.signal(number, _stop) for number in (signal.SIGINT, signal.SIGTERM)}
        try:
            server.serve_forever()
        except KeyboardInterrupt:
            print("stopped")
        finally:
            for number, handler in previous.items():
                signal.signal(number, handler)
    return 0
