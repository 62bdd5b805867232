"""What a rope (a link whose length its winch drives) costs a right-hand side, against the
same chain with that link's length fixed.

    python benchmarks/hoist_cost.py

Chains of massless links with bobs (the crane's: a rope, then slings): 1 and 3 links in the
expanded equations, 10 in the recursive formulation, each with the top link fixed and with it
a rope (its length a state, the input
v_hoist, the Coriolis term of its sliding end and the winch's acceleration l'', and the book W_hoist, whose power -T v_hoist
needs the rope's tension, so the accelerations); with and without a moving support (coupling).
The right-hand side (x', the books' rates included) is timed in a C loop
(core.seconds_per_call), medians of 15 repeats taken in turn, at a state off equilibrium with
nonzero inputs. Prints the table docs/model.md shows and writes
benchmarks/results/hoist_cost.csv.
"""

from conical_pendulum import Link, Scene
from results_csv import write_rows
from rhs_rounds import prepared, rhs_medians

CHAINS = {
    "1 link, expanded": (1, "expanded"),
    "3 links, expanded": (3, "expanded"),
    "10 links, recursive": (10, "recursive"),
}
COUPLING = {"fixed support": False, "moving support": True}
REPEATS, CALLS = 15, 200_000


def scene(n: int, formulation: str, rope: bool, coupling: bool) -> Scene:
    top = Link(
        has_mass=False,
        length=10.0,
        rope=rope,
        rope_min=1.0 if rope else None,
        rope_max=30.0 if rope else None,
    )
    return Scene(
        links=(top,) + (Link(has_mass=False, length=3.0),) * (n - 1),
        coupling=coupling,
        formulation=formulation,
    )


def main():
    rows = []
    for chain, (n, formulation) in CHAINS.items():
        for support, coupling in COUPLING.items():
            cases = {
                label: prepared(scene(n, formulation, rope, coupling), (-0.5, 1.0))
                for label, rope in (("fixed", False), ("rope", True))
            }
            medians = rhs_medians(cases, CALLS // n, REPEATS)
            base = medians["fixed"]
            for label, (_, _, _, n_state) in cases.items():
                rhs = medians[label]
                rows.append(
                    {
                        "chain": chain,
                        "support": support,
                        "top link": label,
                        "states": n_state,
                        "rhs_us": round(rhs * 1e6, 3),
                        "over_fixed": round(rhs / base, 2),
                    }
                )
                print(
                    f"{chain:<20} {support:<15} {label:<6} {n_state:3d} states {rhs * 1e6:8.3f} us  x{rhs / base:.2f}"
                )
    write_rows("hoist_cost", rows)


if __name__ == "__main__":
    main()
