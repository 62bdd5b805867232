"""Sweeps of an FMU that segfaults for some parameter values: do they finish, and in what time.

    python benchmarks/sweep_crashes.py [--tries 3] [--workers 2 1] [--limit 900]

The issue-39 table: the tests' shapes FMU (tests/shapes_fmu.c, mode 4) as a third-party
FMU with a bad corner: every run segfaults past t = fail_at, drawn at random from
0 to `crash_below` s, and the runs stop at 1 s (an output every 0.01 s): below 1 every
run crashes, with 10 about a tenth. Each cell runs `conical-pendulum sweep` as a user
does, with a time limit (a run over it counts as hung), in a temporary directory of its
own (TMPDIR), and records whether it finished, its time, its exit status, the runs that
crashed and were failed naming SIGSEGV, whether it printed a traceback (a worker's, as
when the cluster closed while a worker restarted), and what was left in the temporary
directory.
Writes benchmarks/results/sweep_crashes.csv (rewritten after every sweep).
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))
from results_csv import write_rows
from shapes import build_shapes_fmus

SEGFAULTED = "the worker process died running this run, twice (SIGSEGV, segmentation fault)"
CELLS = [  # runs, crash_below: the rows
    (10, 0.9),  # all crash
    (10, 3.0),  # about 3
    (15, 0.9),
    (20, 0.9),
    (30, 3.0),  # about 10
    (30, 0.9),
    (100, 3.0),  # about 30
    (300, 10.0),  # about 30
]


def one_sweep(fmu: Path, runs: int, crash_below: float, workers: int, seed: int, limit: float) -> dict:
    with tempfile.TemporaryDirectory(prefix="sweep_crashes_") as folder:
        folder = Path(folder)
        temporary = folder / "tmp"
        temporary.mkdir()
        out = folder / "s.parquet"
        command = [str(Path(sys.executable).with_name("conical-pendulum")), "sweep", str(fmu)]
        command += ["--random", "mode=4:4", "--random", f"fail_at=0:{crash_below}", "--random", "gain=0:1"]
        command += ["--samples", str(runs), "--seed", str(seed), "--stop-time", "1", "--interval", "0.01"]
        command += ["--workers", str(workers), "--out", str(out), "--no-progress"]
        start = time.monotonic()
        try:
            done = subprocess.run(
                command,
                env={**os.environ, "TMPDIR": str(temporary)},
                stdin=subprocess.DEVNULL,
                capture_output=True,
                text=True,
                timeout=limit,
                check=False,
            )
            status, finished, traceback = done.returncode, True, "Traceback" in done.stderr
        except subprocess.TimeoutExpired:
            status, finished, traceback = None, False, None
        seconds = time.monotonic() - start
        row = {"runs": runs, "crash_below": crash_below, "workers": workers, "seed": seed}
        row |= {"finished": finished, "seconds": round(seconds, 1), "exit_status": status}
        row["traceback"] = traceback
        if finished and (out / "_sweep.json").exists():
            frame = pd.read_parquet(out, columns=["run", "fail_at", "status", "message"]).drop_duplicates(
                "run"
            )
            crashing = frame["fail_at"] < 1.0  # the last step ends at 1 s
            row |= {
                "runs_written": len(frame),
                "crashing": int(crashing.sum()),
                "failed_with_sigsegv": int((frame.loc[crashing, "message"] == SEGFAULTED).sum()),
                "other_runs_ok": bool((frame.loc[~crashing, "status"] == "ok").all()),
            }
        row["left_in_tmp"] = len(list(temporary.iterdir()))
        return row


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tries", type=int, default=3)
    parser.add_argument("--workers", type=int, nargs="+", default=[2, 1])
    parser.add_argument(
        "--limit", type=float, default=900.0, help="seconds after which a sweep counts as hung"
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        fmu = build_shapes_fmus(Path(folder))[True]
        rows = []
        for seed in range(2, 2 + args.tries):
            for runs, crash_below in CELLS:
                for workers in args.workers:
                    rows.append(one_sweep(fmu, runs, crash_below, workers, seed, args.limit))
                    print(rows[-1], flush=True)
                    write_rows("sweep_crashes", rows)


if __name__ == "__main__":
    main()
