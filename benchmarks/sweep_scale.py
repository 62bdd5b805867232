"""Sweeps of 1,000, 10,000 and 100,000 runs as a user runs them, and one that loses a worker.

    python benchmarks/sweep_scale.py [--runs 1000,10000,100000] [--killed 20000] [--label after]

Each sweep is `conical-pendulum sweep` of the native seed FMU (10 s at 60 Hz, every
output recorded, l0 and alpha0 drawn at random) on a local cluster of 2 workers, run as
its own process, measured from outside: wall time, runs/s, and the peak resident memory
(VmHWM, read from /proc every 0.2 s) of the command's process (the client, with the
scheduler of its local cluster) and of each worker process. `--killed N` runs an N-run
sweep and kills (SIGKILL) one worker process once the progress bar shows half the runs
done; the nanny starts a new one and the sweep carries on. `--resume N` interrupts an
N-run sweep (SIGINT) half-way, then resumes it, and reports what resuming cost. Nothing
is extrapolated: every row is a sweep that ran to its end. Adds its rows to
benchmarks/results/sweep_scale.csv (replacing rows of the same label, kind and size).
"""

import argparse
import csv
import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import psutil

from conical_pendulum import Scene
from conical_pendulum.builder.fmu import build_fmu
from results_csv import RESULTS, write_rows

COMMAND = str(Path(sys.executable).with_name("conical-pendulum"))
DONE = re.compile(r"(\d+)/(\d+) runs")


def peak_kb(pid: int) -> int:
    """The process's peak resident set (VmHWM) in kB, 0 once it is gone."""
    try:
        with open(f"/proc/{pid}/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


def is_worker(process: psutil.Process) -> bool:
    """A Dask worker process: the local cluster's nannies start them with multiprocessing's spawn."""
    try:
        return "spawn_main" in " ".join(process.cmdline())
    except psutil.Error:
        return False


def sweep(fmu: Path, runs: int, out: Path, *, kill_at: float | None = None, interrupt_at=None, extra=()):
    """Run the command; returns its exit status, wall time, output and the peaks in MB."""
    args = [COMMAND, "sweep", str(fmu), "--random", "l0=5:15", "--random", "alpha0=0:0.5"]
    args += ["--samples", str(runs), "--seed", "1", "--out", str(out), *extra]
    start = time.perf_counter()
    process = subprocess.Popen(
        args,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # Ctrl-C's SIGINT as in a terminal, even when this script runs in the background (SIG_IGN)
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    client, workers, done, killed, stderr = psutil.Process(process.pid), {}, [0], [], []

    def read_progress():
        text = ""
        while chunk := process.stderr.read(1):
            text += chunk
            if chunk in "\r\n":
                stderr.append(text)
                match = DONE.search(text)
                if match:
                    done[0] = int(match.group(1))
                text = ""
        stderr.append(text)

    reader = threading.Thread(target=read_progress, daemon=True)
    reader.start()
    client_peak = 0
    while process.poll() is None:
        client_peak = max(client_peak, peak_kb(process.pid))
        try:
            children = client.children(recursive=True)
        except psutil.Error:
            children = []
        for child in children:
            if is_worker(child):
                workers[child.pid] = max(workers.get(child.pid, 0), peak_kb(child.pid))
        if kill_at is not None and not killed and done[0] >= kill_at * runs:
            alive = [child for child in children if is_worker(child) and child.is_running()]
            if alive:
                os.kill(alive[0].pid, signal.SIGKILL)
                killed.append((alive[0].pid, done[0], time.perf_counter() - start))
        if interrupt_at is not None and done[0] >= interrupt_at * runs:
            process.send_signal(signal.SIGINT)
            interrupt_at = None
        time.sleep(0.2)
    seconds = time.perf_counter() - start
    stdout = process.stdout.read()
    reader.join(5)
    return {
        "status": process.returncode,
        "seconds": seconds,
        "stdout": stdout,
        "stderr": "".join(stderr),
        "client_mb": client_peak / 1024,
        "worker_mb": [kb / 1024 for kb in workers.values()],
        "killed": killed,
    }


def row(label, kind, runs, result, note=""):
    workers = result["worker_mb"]
    line = {
        "label": label,
        "sweep": kind,
        "runs": runs,
        "exit status": result["status"],
        "wall s": round(result["seconds"], 1),
        "runs/s": round(runs / result["seconds"], 1),
        "client peak MB": round(result["client_mb"]),
        "worker processes": len(workers),
        "largest worker peak MB": round(max(workers, default=0)),
        "worker peaks MB": " ".join(str(round(mb)) for mb in workers),
        "note": note,
    }
    print(line, flush=True)
    return line


def save(label: str, rows: list[dict]):
    """The rows measured so far into the CSV (after each sweep: a long session keeps what it measured)."""
    path = RESULTS / "sweep_scale.csv"
    kept = []
    if path.exists():
        with open(path, newline="") as file:
            measured = {(line["label"], line["sweep"], str(line["runs"])) for line in rows}
            kept = [
                line
                for line in csv.DictReader(file)
                if (line["label"], line["sweep"], line["runs"]) not in measured
            ]
    return write_rows("sweep_scale", kept + rows)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", default="1000,10000,100000", help="sweep sizes, comma-separated")
    parser.add_argument(
        "--killed", type=int, default=20000, help="runs of the sweep that loses a worker (0: none)"
    )
    parser.add_argument(
        "--resume", type=int, default=0, help="runs of the sweep interrupted and resumed (0: none)"
    )
    parser.add_argument("--label", default="after", help="what this measures (e.g. before, after)")
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        fmu = build_fmu(Scene.uniform(3), Path(tmp) / "ConicalPendulum.fmu", backend="native").path
        for runs in [int(text) for text in args.runs.split(",") if text]:
            out = Path(tmp) / f"sweep{runs}.parquet"
            result = sweep(fmu, runs, out)
            rows.append(row(args.label, "plain", runs, result, result["stdout"].strip().splitlines()[0]))
            subprocess.run(["rm", "-rf", str(out)], check=True)
            save(args.label, rows)
        if args.resume:
            out = Path(tmp) / "resumed.parquet"
            first = sweep(fmu, args.resume, out, interrupt_at=0.5)
            last_line = first["stderr"].strip().splitlines()[-2]
            rows.append(row(args.label, "interrupted half-way (Ctrl-C)", args.resume, first, last_line))
            second = sweep(fmu, args.resume, out, extra=["--resume"])
            rows.append(
                row(args.label, "resumed", args.resume, second, second["stdout"].strip().splitlines()[0])
            )
            subprocess.run(["rm", "-rf", str(out)], check=True)
            save(args.label, rows)
        if args.killed:
            out = Path(tmp) / "killed.parquet"
            result = sweep(fmu, args.killed, out, kill_at=0.5)
            pid, at, when = result["killed"][0] if result["killed"] else (0, 0, 0)
            note = (
                f"worker {pid} killed at {at} runs, {when:.1f} s; " + result["stdout"].strip().splitlines()[0]
            )
            rows.append(row(args.label, "a worker killed half-way", args.killed, result, note))
            subprocess.run(["rm", "-rf", str(out)], check=True)
            save(args.label, rows)
    print(f"wrote {save(args.label, rows)}")


if __name__ == "__main__":
    main()
