"""Derivation, code generation and compile time for n = 1..10 links, in both formulations, cold and cached.

    python benchmarks/build_times.py [--max-links 10] [--formulation both|expanded|recursive]

For each n, the compiled core of Scene.uniform(n) built in the expanded formulation (the
equations derived and generated as C) and in the recursive one (loops over the links,
runtime/csrc/core/chain.c; nothing to derive), each into a fresh cache directory; the cached
figure is a second build_core of the same scene. "auto" (a scene's default) picks the
expanded form below 6 links and the recursive one from 6 (scene.RECURSIVE_FROM). Prints
each build as it ends, then the table docs/performance.md shows (markdown), and writes
benchmarks/results/build_times.csv; `--table` prints that table again from the CSV.
"""

import argparse
import csv
import tempfile
import time
from pathlib import Path

from conical_pendulum import Scene
from conical_pendulum.builder.compiler import build_core
from results_csv import RESULTS, write_rows

FORMULATIONS = ("expanded", "recursive")


def build_row(n: int, formulation: str, cache: Path) -> dict:
    scene = Scene.uniform(n, formulation=formulation)
    start = time.perf_counter()
    build = build_core(scene, cache)
    cold = time.perf_counter() - start
    start = time.perf_counter()
    build_core(scene, cache).load()
    cached = time.perf_counter() - start
    lines = len((build.directory / "model.c").read_text().splitlines())
    s = build.seconds
    return {
        "links": n,
        "formulation": formulation,
        "auto_picks": Scene.uniform(n).resolved_formulation() == formulation,
        "derive_s": s["derive"],
        "codegen_s": s["codegen"],
        "compile_s": s["compile"],
        "cold_s": cold,
        "cached_s": cached,
        "c_lines": lines,
    }


def markdown(rows: list[dict]) -> str:
    """The docs' table: one line per number of links, the expanded build's parts and the
    recursive build's total (it has nothing to derive and generates a fixed 39-line model.c)."""
    by = {(int(r["links"]), r["formulation"]): r for r in rows}
    lines = [
        '| links | "auto" picks | expanded: derive | codegen | compile | cold total | model.c lines '
        "| recursive: cold total |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for n in sorted({n for n, _ in by}):
        e, r = by.get((n, "expanded")), by.get((n, "recursive"))
        cells = [str(n), Scene.uniform(n).resolved_formulation()]
        cells += (
            (
                [f"{float(e[k]):.1f} s" for k in ("derive_s", "codegen_s", "compile_s", "cold_s")]
                + [str(e["c_lines"])]
            )
            if e
            else [""] * 5
        )
        cells.append(f"{float(r['cold_s']):.1f} s" if r else "")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--max-links", type=int, default=10)
    parser.add_argument("--formulation", choices=("both",) + FORMULATIONS, default="both")
    parser.add_argument("--table", action="store_true", help="only print the table of the last run's CSV")
    args = parser.parse_args()
    if args.table:
        with open(RESULTS / "build_times.csv", newline="") as file:
            print(markdown(list(csv.DictReader(file))))
        return
    formulations = FORMULATIONS if args.formulation == "both" else (args.formulation,)
    rows = []
    print(
        f"{'n':>3} {'form':<10} {'auto':>4} {'derive s':>9} {'codegen s':>10} {'compile s':>10} "
        f"{'cold s':>7} {'cached s':>9} {'C lines':>8}"
    )
    for n in range(1, args.max_links + 1):
        for formulation in formulations:
            with tempfile.TemporaryDirectory() as cache:
                row = build_row(n, formulation, Path(cache))
            rows.append(row)
            print(
                f"{n:>3} {formulation:<10} {'*' if row['auto_picks'] else '':>4} {row['derive_s']:>9.2f} "
                f"{row['codegen_s']:>10.2f} {row['compile_s']:>10.2f} {row['cold_s']:>7.2f} "
                f"{row['cached_s']:>9.4f} {row['c_lines']:>8}",
                flush=True,
            )
    write_rows("build_times", rows)
    print(markdown(rows))


if __name__ == "__main__":
    main()
