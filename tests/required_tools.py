"""Tests that need a tool from outside Python (valgrind, wine, chromium, ...).

On a machine without the tool such a test is skipped, with a reason saying what to
install; under CI=true (GitHub Actions and most CI services set it) a missing tool fails
the test instead, so that CI cannot go green by skipping what it was meant to run
(.ci/run installs every tool these tests need).
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest

from conical_pendulum.demos import ssp_tools


def require_tool(
    name: str, path_or_check: str | Path | Callable[[], object] | None = None, install_hint: str = ""
) -> str | Path | object:
    """What was found for the tool `name`, or skip the calling test (fail it under CI=true).

    `path_or_check`: None to look `name` up on PATH; a command to look up on PATH (a str
    without a slash); a path that must exist (a Path, or a str with a slash); a callable
    whose result is falsy when the tool is missing; or any other value, falsy when it is
    missing (e.g. a shutil.which() result that is None).
    """
    if path_or_check is None:
        found = shutil.which(name)
    elif callable(path_or_check):
        found = path_or_check()
    elif isinstance(path_or_check, Path) or (isinstance(path_or_check, str) and "/" in path_or_check):
        found = path_or_check if os.path.exists(path_or_check) else None
    elif isinstance(path_or_check, str):
        found = shutil.which(path_or_check)
    else:
        found = path_or_check
    if found:
        return found
    reason = f"needs {name}" + (f": {install_hint}" if install_hint else "")
    if os.environ.get("CI") == "true":
        pytest.fail(f"{reason} (CI=true: a missing tool is a failure, not a skip)", pytrace=False)
    pytest.skip(reason)


def require_omsimulator() -> Path:
    """OpenModelica's OMSimulator (ssp_tools.omsimulator: $OMSIMULATOR or PATH), or skip (fail under CI=true)."""
    return require_tool(
        "OMSimulator",
        ssp_tools.omsimulator,
        f"OpenModelica's OMSimulator, named by ${ssp_tools.OMSIMULATOR} or on PATH (.ci/run sets "
        f"{ssp_tools.OMSIMULATOR} for ../shared/hosts/omsimulator; it needs Debian's libicu72)",
    )
