"""Each check of the elastic ropes against closed forms and MuJoCo, and its largest error.

    python benchmarks/elastic_rope_checks.py

The checks of tests/test_elastic_ropes.py (which hold them to their bounds), measured in both
formulations: a load dropped onto a rope (its meeting time and peak tension), a bounce over
100 snaps (the snaps' times, energy less the books), a taut elastic pendulum's frequencies,
energy less the books through slack and snaps with the winch working, and MuJoCo's tendon in
3D with a moving support and a winch. Prints one line per check and writes
benchmarks/results/elastic_rope_checks.csv.
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
import test_elastic_ropes as checks
from results_csv import write_rows


def main():
    rows = []

    def row(check, formulation, what, value):
        rows.append({"check": check, "formulation": formulation, "what": what, "value": f"{value:.3g}"})
        print(f"{check:24} {formulation:10} {what:36} {value:.3g}", flush=True)

    for formulation in checks.FORMULATIONS:
        for what, value in checks.drop(formulation).items():
            row("drop onto the rope", formulation, what, value)
        for what, value in checks.bounce(formulation).items():
            row("bounce, 100 snaps", formulation, what, value)
        row("taut pendulum", formulation, "frequencies, relative", checks.frequencies(formulation))
        for what, value in checks.against_mujoco(formulation).items():
            row("MuJoCo's tendon, 3D", formulation, what, value)
    row("energy less the books", "auto", "spread over the energy", checks.swinging_books()[1])
    print(write_rows("elastic_rope_checks", rows))


if __name__ == "__main__":
    main()
