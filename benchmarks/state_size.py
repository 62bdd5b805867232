"""What an FMU state holds of the model: the ModelData's size for the build this checkout makes, on
the damped light chain of benchmarks/radau_levers.py at 3, 20 and 100 links.

    python benchmarks/state_size.py [--links 3,20,100] [--out benchmarks/results/state_size.csv]

The size is len(core.Model().data): the bytes of pendulum_model.c's ModelData, which both FMUs'
states copy (the native one adds its machine and a header, the pythonfmu one its mode). Run in a
worktree of a commit to compare builds (docs/fmu.md says which); rows are appended under the
commit's name.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from conical_pendulum.builder.compiler import load_core
from radau_levers import light_chain
from results_csv import RESULTS, append_rows, checkout_commit


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--links", type=lambda s: [int(v) for v in s.split(",")], default=[3, 20, 100])
    parser.add_argument("--out", type=Path, default=RESULTS / "state_size.csv")
    args = parser.parse_args()
    commit = checkout_commit()
    rows = []
    for links in args.links:
        core = load_core(light_chain(links))
        rows.append(
            {
                "commit": commit,
                "links": links,
                "states": len(core.STATE_NAMES),
                "model_data_bytes": len(core.Model().data),
            }
        )
        print(rows[-1], flush=True)
    append_rows(args.out, rows)


if __name__ == "__main__":
    main()
