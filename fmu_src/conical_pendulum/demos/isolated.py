"""A co-simulation engine in a process of its own, its result as JSON on the last line of stdout.

The engines' libraries (ecos, libcosim) are loaded into a fresh interpreter: ecos needs
libtbb loaded first, a library's fatal error (libcosim panics by abort()) must not take the
caller down, and pythonfmu 0.7's exit-time destructor can abort an interpreter that still
has an FMU's library mapped, so the child leaves with os._exit once it has replied.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys


def call(module: str, job: dict, timeout: float, engine: str) -> subprocess.CompletedProcess:
    """`python -m module JOB_JSON` in a fresh interpreter, as it ended; RuntimeError naming
    `engine` when it did not end within `timeout` seconds."""
    try:
        return subprocess.run(
            [sys.executable, "-m", module, json.dumps(job)],
            check=False,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
    except subprocess.TimeoutExpired:
        raise RuntimeError(f"{engine} did not finish the co-simulations within {timeout:g} s") from None


def answer(run: subprocess.CompletedProcess, engine: str):
    """What the child replied (its last line of stdout); RuntimeError with its stderr's end
    when it failed."""
    if run.returncode != 0:
        raise RuntimeError(f"{engine} failed (exit {run.returncode}):\n{run.stderr[-3000:]}")
    return json.loads(run.stdout.strip().splitlines()[-1])


def reply(result) -> None:
    """In the child: print the result as the last line and leave at once (os._exit, see above)."""
    print(json.dumps(result))
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)
