"""On a nanny: its worker process watched. A run that exceeds the sweep's time limit has
the process ended (SIGKILL: an FMU stuck in C answers nothing else); a process that
ended, however, has its exit code added to its note and its extracted FMU removed."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import shutil
import signal
import time

from distributed import NannyPlugin

from .crashes import EXCEEDED, EXIT, extracted, notes_folder, watched

logger = logging.getLogger(__name__)
CHECK_SECONDS = 0.1  # how often the nanny looks at its worker


class Guard(NannyPlugin):
    """Registered on every nanny of the cluster for one sweep; `run_timeout` None: no limit."""

    def __init__(self, plugin: str, run_timeout: float | None):
        self.plugin, self.run_timeout = plugin, run_timeout

    def setup(self, nanny):
        self.nanny, self.process, self.ended = nanny, None, set()
        notes_folder(self.plugin).mkdir(exist_ok=True)
        self.task = asyncio.ensure_future(self._watch())  # on the nanny's event loop

    def teardown(self, nanny):
        self.task.cancel()
        if self.process is not None:
            watched(self.plugin, self.process.pid).unlink(missing_ok=True)

    async def _watch(self):
        while True:
            try:
                self.check()
            except OSError as exc:  # the folder removed under it: the sweep is ending
                logger.debug("sweep guard: %s", exc)
            await asyncio.sleep(CHECK_SECONDS)

    def check(self):
        if self.process is not None and self.process.exitcode is not None:
            self._note_end(self.process)
            self.process = None
        current = getattr(self.nanny.process, "process", None)  # the WorkerProcess's AsyncProcess
        if self.process is None and current is not None and current.pid and current.exitcode is None:
            self.process = current
            watched(self.plugin, current.pid).touch()
        if self.process is not None and self.run_timeout is not None:
            self._limit(self.process.pid)

    def _note_end(self, process):
        with open(notes_folder(self.plugin) / str(process.pid), "a") as note:
            note.write(f"\n{EXIT}{process.exitcode}\n")
        shutil.rmtree(extracted(self.plugin, process.pid), ignore_errors=True)
        watched(self.plugin, process.pid).unlink(missing_ok=True)

    def _limit(self, pid: int):
        """Ends the process when the run it noted began more than run_timeout s ago."""
        note = notes_folder(self.plugin) / str(pid)
        try:
            began = note.stat().st_mtime
            run = note.read_text(errors="replace").partition("\n")[0]
        except FileNotFoundError:
            return
        if run.isdigit() and pid not in self.ended and time.time() - began > self.run_timeout:
            with open(note, "a") as written:
                written.write(f"\n{EXCEEDED}{self.run_timeout:g} s\n")
            self.ended.add(pid)
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
