"""Where every build of the package keeps what it compiled, and the Python ABI it compiles for:
shared by the compiled core (builder.compiler), pythonfmu's export library and the host-side
runner, with no import of the package's own."""

import os
from pathlib import Path

LIMITED_API = "0x030B0000"  # CPython 3.11: one compiled file serves 3.11 and newer


def cache_root() -> Path:
    """$CONICAL_PENDULUM_CACHE, or conical_pendulum under $XDG_CACHE_HOME or ~/.cache."""
    root = os.environ.get("CONICAL_PENDULUM_CACHE")
    if root:
        return Path(root)
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "conical_pendulum"
