"""Derivation, code generation and compile time for n = 1..10 links, cold and cached.

    python benchmarks/build_times.py [--max-links 10]

Cold builds go to a fresh cache directory; the cached figure is a second build_core of
the same scene. Prints a table and writes benchmarks/results/build_times.csv.
"""
import argparse
import tempfile
import time
from pathlib import Path

from conical_pendulum import Scene
from conical_pendulum.builder.compiler import build_core
from results_csv import write_rows



def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--max-links", type=int, default=10)
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as cache:
        print(f"{'n':>3} {'derive s':>9} {'codegen s':>10} {'compile s':>10} {'cold s':>7} {'cached s':>9} {'C lines':>8}")
        for n in range(1, args.max_links + 1):
            scene = Scene.uniform(n)
            start = time.perf_counter()
            build = build_core(scene, Path(cache))
            cold = time.perf_counter() - start
            start = time.perf_counter()
            build_core(scene, Path(cache)).load()
            cached = time.perf_counter() - start
            lines = sum(1 for _ in open(build.directory / "model.c"))
            s = build.seconds
            rows.append({"links": n, "derive_s": s["derive"], "codegen_s": s["codegen"],
                         "compile_s": s["compile"], "cold_s": cold, "cached_s": cached, "c_lines": lines})
            print(f"{n:>3} {s['derive']:>9.2f} {s['codegen']:>10.2f} {s['compile']:>10.2f} "
                  f"{cold:>7.2f} {cached:>9.4f} {lines:>8}")
    write_rows("build_times", rows)


if __name__ == "__main__":
    main()
