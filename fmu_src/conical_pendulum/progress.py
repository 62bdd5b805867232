"""A one-line text progress bar on stderr, shared by the GIF renderer and the sweeps."""

from __future__ import annotations

import sys

WIDTH = 30


def bar(done: int, total: int, label: str, extra: str = "") -> None:
    """Print `\\r<label>: [#####.....] done/total<extra>` to stderr; a newline once done == total."""
    filled = WIDTH * done // total if total else WIDTH
    print(
        f"\r{label}: [{'#' * filled}{'.' * (WIDTH - filled)}] {done}/{total}{extra}",
        end="\n" if done == total else "",
        file=sys.stderr,
        flush=True,
    )
