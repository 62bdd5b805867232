"""What each force a scene adds costs a right-hand side, against the same chain without it.

    python benchmarks/force_cost.py

The seed chain (3 links, expanded equations) and a 10-link chain (recursive formulation),
each without options, with joint damping (joint_damping: the torques and W_damping), with
the air's drag on every bob (air_drag: the inputs wind and v_pivot, the drag and W_drag),
with forces on every bob (bob_force: the inputs F_bob<i>, their generalized forces and
W_external), with damping and forces, and with all three; all with a moving support
(coupling), so that the pivot's work W_pivot is in the books of every variant with a force. The right-hand side (x', the books'
rates included) is timed in a C loop (core.seconds_per_call), medians of 7 repeats taken in
turn, at a state off equilibrium with nonzero inputs. Prints the table docs/model.md shows
and writes benchmarks/results/force_cost.csv.
"""

from conical_pendulum import Link, Scene
from results_csv import write_rows
from rhs_rounds import prepared, rhs_medians

CHAINS = {"3 links, expanded": (3, "expanded"), "10 links, recursive": (10, "recursive")}
OPTIONS = {  # a link's fields, and air_drag for the scene
    "none": {},
    "joint damping": {"damping": 2.0},
    "air drag": {"air_drag": True},
    "bob forces": {"bob_force": True},
    "damping + bob forces": {"damping": 2.0, "bob_force": True},
    "all three": {"damping": 2.0, "bob_force": True, "air_drag": True},
}
REPEATS, CALLS = 7, 100_000


def scene(n: int, formulation: str, option: dict) -> Scene:
    link = {name: value for name, value in option.items() if name != "air_drag"}
    return Scene(
        links=(Link(**link),) * n,
        joint_damping="damping" in option,
        air_drag=option.get("air_drag", False),
        coupling=True,
        formulation=formulation,
    )


def main():
    rows = []
    for chain, (n, formulation) in CHAINS.items():
        cases = {
            label: prepared(scene(n, formulation, option), (1.0, 5.0)) for label, option in OPTIONS.items()
        }
        medians = rhs_medians(cases, CALLS // n, REPEATS)
        base = medians["none"]
        for label, (_, _, _, n_state) in cases.items():
            rhs = medians[label]
            rows.append(
                {
                    "chain": chain,
                    "options": label,
                    "states": n_state,
                    "rhs_us": round(rhs * 1e6, 3),
                    "over_none": round(rhs / base, 2),
                }
            )
            print(f"{chain:<20} {label:<22} {n_state:4d} states {rhs * 1e6:8.3f} us  x{rhs / base:.2f}")
    write_rows("force_cost", rows)


if __name__ == "__main__":
    main()
