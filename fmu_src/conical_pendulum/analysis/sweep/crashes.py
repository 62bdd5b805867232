"""Crash forensics: each worker process notes the run it is in, in a file of its host, and
faulthandler adds the fatal signal that kills it; the client reads the notes the dead left
and fails a run that killed its worker twice, with the signal."""

from __future__ import annotations

import contextlib
import os
import tempfile
import time
from pathlib import Path

LOST_TIMES = 4  # a run lost with its worker this often, no note saying it was running, fails

# faulthandler's words for the fatal signals it catches
FATAL_SIGNALS = {
    "Segmentation fault": "SIGSEGV",
    "Floating-point exception": "SIGFPE",
    "Aborted": "SIGABRT",
    "Bus error": "SIGBUS",
    "Illegal instruction": "SIGILL",
}


def notes_folder(plugin: str) -> Path:
    """Where a host's worker processes of one sweep note the run they are in."""
    return Path(tempfile.gettempdir()) / plugin


def read_notes(plugin: str) -> dict[int, tuple[int | None, str]]:
    """On a worker: the notes its host's dead worker processes of this sweep left, as
    {pid: (the run it was in or None, faulthandler's words for the signal or "")}; read
    once, then removed."""
    found = {}
    folder = notes_folder(plugin)
    for note in folder.iterdir() if folder.is_dir() else ():
        if process_runs(int(note.name)):
            continue
        first, _, rest = note.read_text().partition("\n")
        fatal = [line for line in rest.splitlines() if line.startswith("Fatal Python error: ")]
        cause = fatal[0].removeprefix("Fatal Python error: ") if fatal else ""
        found[int(note.name)] = (int(first) if first.isdigit() else None, cause)
        note.unlink()
    return found


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


def death_message(causes: list[str]) -> str:
    """A failed run's message when its worker process died: twice running it, as the notes
    say, or lost LOST_TIMES times with it and no note saying why."""
    fatal = causes[-1] if causes else ""
    if fatal:
        cause = f"{FATAL_SIGNALS[fatal]}, {fatal.lower()}" if fatal in FATAL_SIGNALS else fatal
    elif causes:
        cause = "no fatal signal caught: killed from outside, e.g. SIGKILL or out of memory"
    else:
        return f"the worker process was lost {LOST_TIMES} times with this run, with no note of why"
    return f"the worker process died running this run, twice ({cause})"


class Deaths:
    """The worker processes that died, read from their notes: which run each was in and the
    signal; a task lost with its worker may have been only waiting there, the notes tell."""

    def __init__(self, client, plugin: str):
        self.client, self.plugin = client, plugin
        self.notes, self.of_run, self.lost = {}, {}, {}

    def read(self, pid: int | None = None, wait: float = 5.0):
        """Reads the notes left; with `pid`, waits up to `wait` s for that process's (a host
        whose only worker died has none to read it until the nanny starts another)."""
        end = time.monotonic() + wait
        while True:
            for found in self.client.run(
                read_notes, self.plugin, on_error="ignore"
            ).values():  # some may be dying
                for dead, (run, cause) in found.items():
                    self.notes[dead] = run, cause
                    if run is not None:
                        self.of_run.setdefault(run, []).append(cause)
            if pid is None or pid in self.notes or time.monotonic() > end:
                return
            time.sleep(0.25)

    def failed(self, run: int, pid: int | None) -> str | None:
        """After the task of that run alone was lost with its worker: the run's message when
        it has killed a worker twice (or was lost LOST_TIMES times, no note saying why), else
        None: try it again."""
        self.read(pid)
        self.lost[run] = self.lost.get(run, 0) + 1
        causes = self.of_run.get(run, [])
        if len(causes) >= 2 or (self.lost[run] >= LOST_TIMES and not causes):
            return death_message(causes)
        return None


def stop_workers_noting(deaths: Deaths, plugin: str):
    """The dead workers' notes read (and removed), then the plugin unregistered."""
    deaths.read()
    deaths.client.unregister_worker_plugin(plugin)
    deaths.client.run(_removenotes_folder, plugin, on_error="ignore")  # emptied by teardowns and reads


def _removenotes_folder(plugin: str):
    with contextlib.suppress(OSError):
        notes_folder(plugin).rmdir()
