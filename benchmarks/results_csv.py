"""Where the benchmark scripts keep their tables: one CSV per script in benchmarks/results."""

import csv
import subprocess
from pathlib import Path

RESULTS = Path(__file__).parent / "results"


def write_rows(name: str, rows: list[dict]) -> Path:
    """rows (dicts with the same keys) as benchmarks/results/<name>.csv."""
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{name}.csv"
    with open(path, "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return path


def checkout_commit() -> str:
    """The short hash of the checkout these scripts lie in: the build the rows of a script run
    in a worktree of a commit were measured on."""
    return subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"],
        cwd=RESULTS.parent,
        capture_output=True,
        text=True,
        check=False,
    ).stdout.strip()


def append_rows(path: Path, rows: list[dict], fields: list[str] | None = None) -> None:
    """rows appended to the CSV at path, its header first where the file is new; fields: its
    columns (the first row's keys unless given; a row may leave some empty)."""
    new = not path.exists()
    with path.open("a", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=fields or list(rows[0]))
        if new:
            writer.writeheader()
        writer.writerows(rows)
