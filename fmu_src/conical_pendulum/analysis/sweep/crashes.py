"""Crash forensics: each worker process notes the run it is in, in a file of its host;
faulthandler adds the fatal signal that kills it, its nanny (guard.py) how it ended and
whether it ran out of time. The client reads the notes the dead left, fails a run that
killed its worker twice, or ran out of time once, naming the signal, and removes what
they left behind."""

from __future__ import annotations

import logging
import os
import re
import shutil
import signal
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

logger = logging.getLogger(__name__)
LOST_TIMES = 4  # a run lost with its worker this often, no note saying it was running, fails
EXIT, EXCEEDED = "exit ", "exceeded "  # the lines a nanny's guard adds to a dead worker's note

# faulthandler's words for the fatal signals it catches
FATAL_SIGNALS = {
    "Segmentation fault": "SIGSEGV",
    "Floating-point exception": "SIGFPE",
    "Aborted": "SIGABRT",
    "Bus error": "SIGBUS",
    "Illegal instruction": "SIGILL",
}


def notes_folder(plugin: str) -> Path:
    """Where a host's worker processes of one sweep note the run they are in (a file named
    by the process id) and extract the FMU (`<pid>.fmu`)."""
    return Path(tempfile.gettempdir()) / plugin


def extracted(plugin: str, pid: int) -> Path:
    return notes_folder(plugin) / f"{pid}.fmu"


def watched(plugin: str, pid: int) -> Path:
    """A mark that a nanny watches that worker process and will note how it ended."""
    return notes_folder(plugin) / f"{pid}.watched"


@dataclass(frozen=True)
class Death:
    """A dead worker process, as its note tells: the run it was in (None: none), faulthandler's
    words for the fatal signal, the exit code its nanny saw, and the time it exceeded."""

    run: int | None
    fatal: str = ""
    exit_code: int | None = None
    exceeded: str = ""

    def cause(self) -> str:
        """How the process ended, the signal first."""
        if self.fatal:
            return (
                f"{FATAL_SIGNALS[self.fatal]}, {self.fatal.lower()}"
                if self.fatal in FATAL_SIGNALS
                else self.fatal
            )
        if self.exit_code is not None and self.exit_code < 0:
            number = -self.exit_code
            name = signal.Signals(number).name if number in signal.valid_signals() else f"signal {number}"
            outside = name == "SIGKILL" and not self.exceeded  # not the guard's own
            return f"{name}, killed from outside, e.g. out of memory" if outside else name
        if self.exit_code is not None:
            return f"exit status {self.exit_code}"
        return "no fatal signal caught: killed from outside, e.g. SIGKILL or out of memory"

    @classmethod
    def of(cls, text: str) -> Death:
        first, _, rest = text.partition("\n")
        fatal = re.search(r"^Fatal Python error: (.*)$", rest, re.MULTILINE)
        code = re.search(rf"^{EXIT}(-?\d+)$", rest, re.MULTILINE)
        exceeded = re.search(rf"^({EXCEEDED}.*)$", rest, re.MULTILINE)
        return cls(
            int(first) if first.isdigit() else None,
            fatal.group(1) if fatal else "",
            int(code.group(1)) if code else None,
            exceeded.group(1) if exceeded else "",
        )


def read_notes(plugin: str) -> dict[int, Death]:
    """On a worker or nanny (or a local cluster's client): the notes this host's dead worker
    processes of this sweep left, once their nanny has added how each ended; read once,
    then removed with the FMU each extracted."""
    found = {}
    folder = notes_folder(plugin)
    for entry in folder.iterdir() if folder.is_dir() else ():
        name, dot, kind = entry.name.partition(".")
        if not name.isdigit() or process_runs(int(name)):
            continue
        pid = int(name)
        if not dot:
            claimed = folder / f"{pid}.read-by-{os.getpid()}"
            try:  # the host's workers and nannies may read at once: the one that renames it reads it
                if watched(plugin, pid).exists() and f"\n{EXIT}" not in entry.read_text(errors="replace"):
                    continue  # its nanny has yet to say how it ended
                entry.rename(claimed)
            except FileNotFoundError:
                continue
            found[pid] = Death.of(claimed.read_text(errors="replace"))
            claimed.unlink()
        elif kind == "fmu" and not (folder / name).exists():
            shutil.rmtree(entry, ignore_errors=True)
    return found


def remove_notes(plugin: str):
    """The sweep's notes folder of this host removed, whatever is left in it."""
    shutil.rmtree(notes_folder(plugin), ignore_errors=True)


def process_runs(pid: int) -> bool:
    """Whether that process runs (a zombie, dead but not yet reaped by its nanny, does not)."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rpartition(")")[2].split()[0] != "Z"
    except FileNotFoundError:
        return False
    except OSError:  # no /proc
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return False
        return True


def verdict(deaths: list[Death], lost: int) -> str | None:
    """A run's message from the deaths noted while it ran and the times its task was lost
    alone, or None: run it again. Out of time once, or killing the worker twice, fails it."""
    for death in deaths:
        if death.exceeded:
            return f"{death.exceeded}: its worker process was ended ({death.cause()})"
    if len(deaths) >= 2:
        return f"the worker process died running this run, twice ({deaths[-1].cause()})"
    if lost >= LOST_TIMES and not deaths:
        return f"the worker process was lost {LOST_TIMES} times with this run, with no note of why"
    return None


class Deaths:
    """The worker processes that died, read from their notes: which run each was in and how
    it ended; a task lost with its worker may have been only waiting there, the notes tell.
    A local cluster's notes are read here, a running cluster's by its workers and nannies."""

    def __init__(self, client, plugin: str, local: bool):
        self.client, self.plugin, self.local = client, plugin, local
        self.notes, self.of_run, self.lost = {}, {}, {}

    def read(self, pid: int | None = None, wait: float = 5.0):
        """Reads the notes left; with `pid`, waits up to `wait` s for that process's (its
        nanny notes how it ended; on a running cluster, a host whose only worker died has
        none to read it until the nanny starts another)."""
        end = time.monotonic() + wait
        while True:
            for found in self._found():
                for dead, death in found.items():
                    if dead in self.notes:  # read by two processes of its host at once
                        continue
                    self.notes[dead] = death
                    if death.run is not None:
                        self.of_run.setdefault(death.run, []).append(death)
            if pid is None or pid in self.notes or time.monotonic() > end:
                return
            time.sleep(0.1)

    def _found(self) -> list[dict[int, Death]]:
        if self.local:
            return [read_notes(self.plugin)]
        found = []
        for nanny in (False, True):  # some may be dying: ignored
            found += self.client.run(read_notes, self.plugin, nanny=nanny, on_error="ignore").values()
        return found

    def lost_with(self, first: int, last: int, pid: int | None) -> tuple[list, list[int]]:
        """After the task of runs first..last was lost with its worker: the runs failed now,
        as summary rows, and those to run again, each alone."""
        self.read(pid, wait=5.0 if self.local else 30.0)
        killer = self.notes[pid].run if pid in self.notes else None
        failed, again = [], []
        for run in range(first, last + 1):
            if first == last and killer in (None, run):  # not only waiting on a worker another run killed
                self.lost[run] = self.lost.get(run, 0) + 1
            message = verdict(self.of_run.get(run, []), self.lost.get(run, 0))
            if message:
                failed.append((run, False, message, 0))
            else:
                again.append(run)
        return failed, again

    def stop(self):
        """The dead workers' notes read, the plugins unregistered, the notes folders removed."""
        self.read()
        for nanny in (False, True):
            try:  # a worker dying now does not answer: its folder goes below
                self.client.unregister_worker_plugin(self.plugin, nanny=nanny)
            except Exception as exc:
                logger.debug("sweep: unregistering %s: %s", self.plugin, exc)
        for nanny in (False, True):
            self.client.run(remove_notes, self.plugin, nanny=nanny, on_error="ignore")
        if self.local:
            remove_notes(self.plugin)
