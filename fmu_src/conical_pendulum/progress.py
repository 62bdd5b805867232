"""A progress bar on stderr, shared by the GIF renderer and the sweeps: in a terminal one line
updated in place; in a file or a CI log a few plain lines, one a quarter, none rewritten."""

from __future__ import annotations

import sys

WIDTH = 30  # the bar's characters in a terminal
LOGGED_STEPS = 4  # the plain lines written elsewhere: at each quarter of the work


class Bar:
    """`<label>: [#####.....] done/total<extra>`: redrawn in a terminal when a # more shows, and
    written as a line of its own elsewhere when a quarter more is done; always at the end."""

    def __init__(self, total: int, label: str, stream=None):
        self.total, self.label = total, label
        self.stream = stream or sys.stderr
        self.in_place = self.stream.isatty()
        self.steps = WIDTH if self.in_place else LOGGED_STEPS
        self.drawn = -1  # the last step drawn: none yet
        self.open = False  # a line in place not yet ended

    def update(self, done: int, extra: str = "") -> None:
        step = self.steps * done // self.total if self.total else self.steps
        finished = done >= self.total
        redraw = self.in_place and (bool(extra) or (finished and self.open))  # a new rate, the end
        if step == self.drawn and not redraw:
            return
        filled = WIDTH * done // self.total if self.total else WIDTH
        text = f"{self.label}: [{'#' * filled}{'.' * (WIDTH - filled)}] {done}/{self.total}{extra}"
        if self.in_place:
            print(f"\r{text}", end="\n" if finished else "", file=self.stream, flush=True)
            self.open = not finished
        else:
            print(text, file=self.stream, flush=True)
        self.drawn = step

    def stop(self) -> None:
        """End a line drawn in place when the work stops short."""
        if self.open:
            print(file=self.stream, flush=True)
            self.open = False
