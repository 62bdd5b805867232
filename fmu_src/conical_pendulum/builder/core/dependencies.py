"""What each computed variable of the pendulum depends on, read from the model (build time only).

ModelStructure names, for every output and state derivative, the knowns it depends on; FMI
2.0 reads a missing list as "depends on every known", OMSimulator as "on nothing", so every
list is written out (builder.fmi.variables puts these sets into the records' depends_on).

The expanded equations (builder.core.equations.derive) give them exactly: an expression's free
symbols, followed through the named intermediate definitions; u' = M^-1 F depends on every
entry of M and F in its block of M (structurally, M^-1 is full within a block). The
recursive formulation (runtime/csrc/core/chain.c) has no expressions: its loops go down the
chain, so a link's kinematics depend on its own and its ancestors' joints and lengths, and the
dynamics on everything; tests/test_dependencies.py holds the two to each other where both exist
and both to the FMUs' directional derivatives.
"""

from __future__ import annotations

import functools

from ...scene import APPARENT_MASS, FREE_FORCE, PIVOT_INPUTS, PIVOT_OUTPUTS, PIVOT_VELOCITY, WIND, Scene

Dependencies = dict[str, frozenset[str]]  # computed variable -> the knowns it depends on


@functools.cache
def dependencies(scene: Scene) -> Dependencies:
    """Each output's (Scene.output_names) and state derivative's (der(alpha0), ...) knowns:
    states, parameters and inputs, by name."""
    if scene.resolved_formulation() == "recursive":
        return _chain(scene)
    from .equations import derive  # sympy: build time only

    return _symbolic(scene, derive(scene))


def _symbolic(scene: Scene, eqs) -> Dependencies:
    core = scene.core_parameter_names() + scene.core_extra_names()  # _law resolves the latter
    knowns = {s: s.name for s in eqs.states} | dict(zip(eqs.params, core))
    rates = set(eqs.rates)
    closure: dict = {}  # symbol -> the knowns (and rates u') it depends on

    def of(expr) -> frozenset:
        found = set()
        for symbol in getattr(expr, "free_symbols", ()):
            if symbol in closure:
                found |= closure[symbol]
            elif symbol in knowns:
                found.add(knowns[symbol])
            elif symbol in rates:
                found.add(symbol)
        return frozenset(found)

    for symbol, expr in eqs.definitions:
        closure[symbol] = of(expr)
    mass, forcing = eqs.mass_matrix, eqs.forcing
    dim = mass.shape[0]
    blocks = _blocks(dim, lambda i, j: mass[i, j] != 0)
    rate_of = {}
    for block in blocks:
        used = frozenset().union(
            *(of(mass[i, j]) for i in block for j in block), *(of(forcing[i]) for i in block)
        )
        rate_of.update({eqs.rates[i]: used for i in block})

    def resolved(expr) -> frozenset[str]:  # u' replaced by what it depends on
        found = of(expr)
        return frozenset(name for item in found for name in (rate_of[item] if item in rates else {item}))

    names = scene.state_names()
    computed = [name for name in scene.output_names() if name not in FREE_FORCE + APPARENT_MASS]
    result = {name: resolved(expr) for name, expr in zip(computed, eqs.outputs)}  # F_free, M_app below
    result |= {f"der({names[k]})": frozenset({names[k + dim]}) for k in range(dim)}  # q' = u
    result |= {f"der({names[dim + k]})": rate_of[eqs.rates[k]] for k in range(dim)}
    result |= {f"der({name})": resolved(rate) for name, rate in zip(scene.work_names(), eqs.work_rates)}
    result |= {f"der(l{i})": resolved(rate) for i, rate in zip(scene.ropes(), eqs.rope_rates)}  # v_hoist
    if scene.coupling:
        everything = frozenset().union(*rate_of.values())
        momentum = frozenset().union(*(of(entry) for entry in eqs.momentum), of(eqs.total_mass))
        whole_mass = frozenset().union(*(of(mass[i, j]) for i in range(dim) for j in range(dim)))
        result |= dict.fromkeys(FREE_FORCE, everything - set(PIVOT_INPUTS))  # F_pivot at a_pivot = 0
        result |= dict.fromkeys(APPARENT_MASS, momentum | whole_mass)  # m I - P M^-1 P^T
    return {
        name: frozenset(k for item in found for k in _law(scene).get(item, {item}))
        for name, found in result.items()
    }


def _law(scene: Scene) -> Dependencies:
    """What the core's p holds beyond the variables, by what it depends on: each rope's l''
    (the rate of an input: nothing a variable holds), and each elastic rope's law (T_law,
    s_taut, margin: dynamics.c's cp_rope_law), from its length, reach and their rates, its EA and
    damping, and the masses hanging from it."""
    law = {f"a_hoist{i}": frozenset() for i in scene.ropes()}
    parameters = set(scene.parameter_names())
    for i in scene.elastic_ropes():
        masses = {f"{mass}{j}" for j in range(i, scene.n) for mass in ("m", "M")} & parameters
        rope = {f"l{i}", f"r{i}", f"v_r{i}", f"v_hoist{i}", f"EA{i}", f"zeta_rope{i}"}
        law[f"T_law{i}"] = frozenset(rope | masses)
        law[f"s_taut{i}"] = frozenset({f"l{i}", f"r{i}"})
        law[f"margin{i}"] = law[f"T_law{i}"]
    return law


def _blocks(dim: int, linked) -> list[list[int]]:
    """The indices 0..dim-1 in the connected blocks of the symmetric relation linked(i, j)."""
    root = list(range(dim))

    def find(i):
        while root[i] != i:
            root[i] = root[root[i]]
            i = root[i]
        return i

    for i in range(dim):
        for j in range(i + 1, dim):
            if linked(i, j):
                root[find(i)] = find(j)
    blocks: dict[int, list[int]] = {}
    for i in range(dim):
        blocks.setdefault(find(i), []).append(i)
    return list(blocks.values())


def _chain(scene: Scene) -> Dependencies:
    """The recursive formulation's dependencies: down the chain from the pivot."""
    n, parameters = scene.n, set(scene.parameter_names())
    angles = [frozenset({f"alpha{i}", f"beta{i}"}) for i in range(n)]
    above = [frozenset().union(*angles[: i + 1]) for i in range(n)]  # orientation of link i
    elastic = scene.elastic_ropes()
    # the distances down to link i's lower end: the links' lengths, the elastic ropes' reaches
    lengths = [frozenset(f"r{k}" if k in elastic else f"l{k}" for k in range(i + 1)) for i in range(n)]
    # the winches' speeds that move link i's bob: of the (inextensible) ropes at or above it
    hoists = [
        frozenset(f"v_hoist{k}" for k in scene.ropes() if k <= i and k not in elastic) for i in range(n)
    ]
    inputs, works = set(scene.input_names()), set(scene.work_names())
    # the forces' coefficients, which move nothing but the chain's dynamics (and the books)
    coefficients = {
        s.name for s in scene.parameter_scalars() if s.quantity in ("c", "C_d", "A", "rho", "zeta_rope")
    }
    everything = frozenset(scene.state_names()) | parameters | inputs
    motion = everything - works  # the chain's motion; the energy's books follow it
    result = {}
    for scalar in scene.output_scalars():
        i = scalar.link
        if scalar.stem == "bob" or scalar.quantity in ("link_x", "link_y", "link_z"):
            # the first joint turns last about the pivot's x axis (equations.py's 'Space' 'ZXY'),
            # which moves no point along x
            turns = above[i] - ({"beta0"} if scalar.suffix == "_x" else set())
            result[scalar.name] = turns | lengths[i]
        elif scalar.stem == "link":  # the orientation quaternion
            result[scalar.name] = above[i]
        elif scalar.name == "energy":  # the velocities: the winches' speeds among the inputs
            result[scalar.name] = motion - (inputs - hoists[n - 1]) - coefficients
        elif scalar.name in PIVOT_OUTPUTS:
            result[scalar.name] = motion
        elif scalar.name in FREE_FORCE:
            result[scalar.name] = motion - set(PIVOT_INPUTS)
        elif scalar.name in APPARENT_MASS:
            stiffnesses = {f"EA{i}" for i in elastic}  # the ropes' pull is no inertia
            result[scalar.name] = (
                above[n - 1] | (parameters - {"g"} - coefficients - stiffnesses) | lengths[n - 1]
            )
        elif scalar.stem in ("T_rope", "P_hoist") and i in elastic:  # the rope's law
            result[scalar.name] = _law(scene)[f"T_law{i}"]
        elif scalar.stem in ("T_rope", "P_hoist"):  # Newton's law for what hangs from the rope
            result[scalar.name] = motion
        elif scalar.stem == "stretch":
            result[scalar.name] = frozenset({f"r{i}", f"l{i}"})
        elif scalar.stem == "taut_margin":
            result[scalar.name] = _law(scene)[f"margin{i}"]
    names = scene.state_names()
    dim = scene.dof()
    result |= {f"der({names[k]})": frozenset({names[k + dim]}) for k in range(dim)}
    result |= {f"der({names[dim + k]})": motion for k in range(dim)}
    result |= _work_rates(scene, above, lengths, hoists)
    result |= {f"der(l{i})": frozenset({f"v_hoist{i}"}) for i in scene.ropes()}
    return result


def _work_rates(scene: Scene, above, lengths, hoists) -> Dependencies:
    """The energy's books' rates: each force's power, its size times the velocity of where
    it acts (a point of link i moves with the joints, lengths and winches down to i); the
    winches' power, their speeds times the ropes' tensions, with everything."""
    n, elastic = scene.n, scene.elastic_ropes()
    rates = [
        frozenset({f"omega{i}", f"delta{i}"} | ({f"v_r{i}"} if i in elastic else set())) for i in range(n)
    ]
    moving = [above[i] | frozenset().union(*rates[: i + 1]) | lengths[i] | hoists[i] for i in range(n)]

    def of_kind(*quantities):
        return {s.name for s in scene.parameter_scalars() if s.quantity in quantities}

    powers = {
        "W_damping": of_kind("c")
        | {f"{rate}{i}" for rate in ("omega", "delta") for i in range(n)},  # c w_rel^2
        "W_drag": frozenset().union(  # the drag times the bob's velocity
            *(moving[i] | of_kind("rho") | {f"C_d{i}", f"A{i}"} for i in scene.dragged_bobs())
        )
        | (set(scene.input_names()) & {*WIND, *PIVOT_VELOCITY}),  # the air's velocity
        "W_external": frozenset().union(
            *(moving[i] | {f"F_bob{i}_{c}" for c in "xyz"} for i in scene.forced_bobs())
        ),
        "W_pivot": moving[n - 1] | of_kind("m", "M") | set(PIVOT_INPUTS),  # -m a_pivot . v
        # an inextensible rope's tension is Newton's law for all below it, an elastic one's its law
        "W_hoist": frozenset().union(*(_law(scene)[f"T_law{i}"] for i in elastic))
        | (
            frozenset(scene.state_names()) - set(scene.work_names())
            | set(scene.parameter_names())
            | set(scene.input_names())
            if set(scene.ropes()) - set(elastic)
            else frozenset()
        ),
        "W_load": frozenset(),  # it jumps at a load's change, and stays between
        "W_rope": frozenset().union(*(_law(scene)[f"T_law{i}"] for i in scene.elastic_ropes())),
    }
    return {f"der({name})": frozenset(powers[name]) for name in scene.work_names()}
