"""The one error class for what a user can act on, raised by library code and turned into a
message and an exit status by the command line alone (cli.py); and the one hint saying how
to install what is missing (`needs`), written for the way this copy was installed.

Library code (builder/, analysis/, viz/, demos/) raises UserError and never exits: a
program that imports it keeps control. `conical-pendulum` prints it as
`<command>: <message>` and exits with its `status`.
"""

from __future__ import annotations

import json
from importlib.metadata import PackageNotFoundError, distribution
from pathlib import Path
from urllib.parse import unquote, urlparse

DISTRIBUTION = "conical-pendulum-fmu"  # the name pip knows the package by (pyproject.toml)


class UserError(Exception):
    """A mistake the user can fix (a bad option or value, a missing or unreadable file), a
    missing optional package or tool (the message says what to install), or work that was
    tried and failed for a reason the message gives.

    `status` is the command's exit status: 2 (the default) for what was asked wrongly or
    cannot be done here, 1 for work that ran and failed."""

    def __init__(self, message: str, status: int = 2):
        super().__init__(message)
        self.status = status


def needs(package: str, extra: str) -> str:
    """`needs <package>: <the pip command that installs the extra holding it>`."""
    return f"needs {package}: {install_command(extra)}"


def install_command(extra: str) -> str:
    """The pip command that adds an extra to this copy: from its source checkout when it was
    installed editable from one (`pip install -e ".[sweep]"`, the folder named when it is not
    the current one), by name otherwise (`pip install "conical-pendulum-fmu[sweep]"`)."""
    source = source_checkout()
    if source is None:
        return f'pip install "{DISTRIBUTION}[{extra}]"'
    try:
        here = source.samefile(Path.cwd())
    except OSError:
        here = False
    return f'pip install -e "{"." if here else source}[{extra}]"'


def source_checkout() -> Path | None:
    """The source folder this copy runs from when it was installed editable (PEP 610's
    direct_url.json) or not installed at all (run from the checkout); None for a wheel."""
    try:
        installed = distribution(DISTRIBUTION)
    except PackageNotFoundError:  # run from the sources, e.g. with PYTHONPATH
        root = Path(__file__).resolve().parents[2]
        return root if (root / "pyproject.toml").is_file() else None
    try:
        origin = json.loads(installed.read_text("direct_url.json") or "{}")
    except json.JSONDecodeError:
        return None
    url = urlparse(origin.get("url", ""))
    if not origin.get("dir_info", {}).get("editable") or url.scheme != "file":
        return None
    return Path(unquote(url.path))
