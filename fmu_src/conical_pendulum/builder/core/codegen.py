"""Emit the scene's equations as C: mass matrix and forcing, and the requested outputs.

Intermediate definitions are emitted in order, then the final expressions after
common-subexpression elimination. States and parameters are read from the arrays
x and p in the order of Scene.state_names() and Scene.core_parameter_names(); outputs
that need the accelerations u' (the pivot force) read them from dx = x'. After the parameters,
p holds each rope's l'' and each elastic rope's law (Scene.core_extra_names).

Every quantity is a `cp_real` (runtime/csrc/core/real.h): double in the core and the FMU, double
complex where directional.c compiles the same model.c for complex-step derivatives. So the
generated code calls only analytic functions (checked by `_analytic`), which <tgmath.h>
maps to their complex versions there.
"""

from __future__ import annotations

import re

import sympy as sm
from sympy.printing.c import C99CodePrinter

from ...runtime.rules import STATISTICS
from ...scene import APPARENT_MASS, FREE_FORCE, ROPE_EVENTS, WORKS, Scene
from .. import c_literals as c
from .equations import Equations, joint_kinematics
from .equations import needed as _needed

# Functions whose complex version (by <tgmath.h>) continues the real one analytically
# wherever the real one is defined: complex-step differentiation of the generated code is
# exact only through these. Not pow: cpow(z, n) goes through clog, whose imaginary part at
# a negative base is pi, which swallows the step's.
ANALYTIC = {"sin", "cos", "tan", "exp", "log", "sqrt", "sinh", "cosh", "tanh"}


class _Printer(C99CodePrinter):
    """Integer powers as products: pow() is a libm call unless the compiler unrolls it."""

    def _print_Pow(self, expr):
        base, exp = expr.args
        if exp.is_Integer and 1 < abs(exp) <= 4:
            product = "*".join([f"({self._print(base)})"] * int(abs(exp)))
            return f"(1.0/({product}))" if exp < 0 else f"({product})"
        if exp == -1:
            return f"(1.0/({self._print(base)}))"
        return super()._print_Pow(expr)


def _analytic(source: str) -> str:
    """The source, if the functions it calls are all analytic (ANALYTIC)."""
    called = set(re.findall(r"\b([A-Za-z_][A-Za-z_0-9]*)\s*\(", source))
    defined = set(re.findall(r"^void ([A-Za-z_][A-Za-z_0-9]*)\(", source, re.MULTILINE))
    other = called - ANALYTIC - defined
    if other:
        raise ValueError(
            f"the generated C calls {sorted(other)}: not analytic, so the "
            "complex-step derivatives of the native FMU would be wrong"
        )
    return source


def _function(signature, eqs: Equations, targets, prologue=(), epilogue=()):
    """A C function assigning each (lvalue, expr) of targets, between the lines `prologue`
    and `epilogue`."""
    printer = _Printer()
    slot = {name: k for k, name in enumerate(eqs.scene.state_names())}
    rename = {s: sm.Symbol(f"x[{slot[s.name]}]") for s in eqs.states}
    rename.update({s: sm.Symbol(f"p[{k}]") for k, s in enumerate(eqs.params)})
    ndof = len(eqs.rates)
    rename.update({s: sm.Symbol(f"dx[{ndof + k}]") for k, s in enumerate(eqs.rates)})
    exprs = [sm.sympify(e) for _, e in targets]
    lines = [signature, "{", *prologue]
    for symbol, value in _needed(eqs.definitions, exprs):
        lines.append(f"    const cp_real {symbol} = {printer.doprint(value.xreplace(rename))};")
    temps, reduced = sm.cse(exprs, symbols=sm.numbered_symbols("t"), order="none")
    for symbol, value in temps:
        lines.append(f"    const cp_real {symbol} = {printer.doprint(value.xreplace(rename))};")
    for (lvalue, _), value in zip(targets, reduced):
        lines.append(f"    {lvalue} = {printer.doprint(value.xreplace(rename))};")
    lines += [*epilogue, "}"]
    return "\n".join(lines)


WORK_SIGNATURE = "void cp_work_rates(const cp_real *x, const cp_real *p, const cp_real *dx, cp_real *dW)"


def _books(scene: Scene) -> list[str]:
    """model.h's lines for the energy's books, if the scene keeps any (none: no line): their
    number, each one's slot (CP_WORK_DAMPING, ...; -1: not kept), and the expanded
    formulation's function giving their rates."""
    works = scene.work_names()
    if not works:
        return []
    # W_load's and W_rope's slots only where kept (#ifdef CP_WORK_LOAD): scenes without loads
    # or elastic ropes keep their C
    named = [name for name in WORKS if name not in ("W_load", "W_rope") or name in works]
    return [
        c.define("CP_NWORK", len(works)),
        *(c.define(f"CP_WORK_{name.removeprefix('W_').upper()}", _index(works, name)) for name in named),
        *(
            []
            if scene.resolved_formulation() == "recursive"
            else [
                "/* dW: the power of each force of the energy's books, the rates of the states after",
                "   the angles and rates (Scene.work_names); dx: x' (the rates' part read: W_hoist's",
                "   power needs the ropes' tensions). */",
                WORK_SIGNATURE + ";",
            ]
        ),
    ]


def _work_function(eqs: Equations) -> list[str]:
    """model.c's cp_work_rates, if the scene keeps books (none: no function; the recursive
    formulation's is chain.c's)."""
    if not eqs.work_rates:
        return []
    targets = [(f"dW[{k}]", rate) for k, rate in enumerate(eqs.work_rates)]
    reads_rates = set().union(
        *(sm.sympify(e).free_symbols for e in eqs.work_rates),
        *(e.free_symbols for _, e in _needed(eqs.definitions, [sm.sympify(r) for r in eqs.work_rates])),
    ) & set(eqs.rates)
    return [_function(WORK_SIGNATURE, eqs, targets, prologue=[] if reads_rates else ["    (void)dx;"])]


ENERGY_SIGNATURE = "void cp_energy(const cp_real *x, const cp_real *p, cp_real *E)"


def _jumps(scene: Scene) -> list[str]:
    """model.h's lines for the energy's jumps, if a value set at an event can move it (a rope's
    winch speed, a load's mass; none: no line): the energy at (x, p), whose change the book of
    that work takes, and where the loads' masses are in p."""
    if not (scene.ropes() or scene.loads()):
        return []
    loads = scene.loads()
    params = scene.core_parameter_names()
    return [
        "#define CP_ENERGY_JUMPS 1",
        "/* E: the chain's energy at (x, p), kinetic and potential as the output energy's: a value",
        "   set at an event that moves it (a rope's v_hoist, a load's mass) jumps its book by the",
        "   change. */",
        ENERGY_SIGNATURE + ";",
        *(
            [
                c.define("CP_NLOAD", len(loads)),
                "/* Where each load's mass m<i> is in p (Scene.loads' order). */",
                "static const int cp_load_mass[CP_NLOAD] = "
                + c.initializer(params.index(f"m{i}") for i in loads)
                + ";",
            ]
            if loads
            else []
        ),
    ]


def _energy_function(eqs: Equations) -> list[str]:
    """model.c's cp_energy, if the scene's energy can jump (the recursive formulation's is
    chain.c's)."""
    return [_function(ENERGY_SIGNATURE, eqs, [("*E", eqs.energy)])] if _jumps(eqs.scene) else []


def _ropes(scene: Scene) -> list[str]:
    """model.h's lines for the ropes, if the scene has any (none: no line): their number,
    where each one's length is in x and its v_hoist in p, its range, and where the tensions
    are in the outputs."""
    ropes = scene.ropes()
    if not ropes:
        return []
    states, params = scene.state_names(), scene.core_parameter_names()
    outputs = scene.output_names()
    return [
        c.define("CP_NROPE", len(ropes)),
        "/* Each rope's link, where its length l<i> is in x and its v_hoist<i> in p, and the range",
        "   the length must stay in [m] (Scene.ropes' order); its tension T_rope<i> is in the",
        "   outputs from CP_TENSION_OUTPUT on. */",
        "static const int cp_rope_link[CP_NROPE] = " + c.initializer(ropes) + ";",
        "static const int cp_rope_state[CP_NROPE] = "
        + c.initializer(states.index(f"l{i}") for i in ropes)
        + ";",
        "static const int cp_rope_hoist[CP_NROPE] = "
        + c.initializer(params.index(f"v_hoist{i}") for i in ropes)
        + ";",
        "static const double cp_rope_min[CP_NROPE] = "
        + c.initializer(c.double(scene.links[i].rope_min) for i in ropes)
        + ";",
        "static const double cp_rope_max[CP_NROPE] = "
        + c.initializer(c.double(scene.links[i].rope_max) for i in ropes)
        + ";",
        c.define("CP_TENSION_OUTPUT", outputs.index(f"T_rope{ropes[0]}")),
        *_elastic_ropes(scene),
    ]


def _elastic_ropes(scene: Scene) -> list[str]:
    """model.h's lines for the elastic ropes, if the scene has any (none: no line): where each
    one's numbers are, for the rope's law (dynamics.c's cp_rope_law) and the recursive
    formulation."""
    elastic = scene.elastic_ropes()
    if not elastic:
        return []
    states, params = scene.state_names(), scene.core_parameter_names()
    core = params + scene.core_extra_names()
    below = []  # the masses hanging from each elastic rope, its link's and those below, and -1
    for i in elastic:
        names = (f"{mass}{j}" for j in range(i, scene.n) for mass in ("m", "M"))
        below += [params.index(name) for name in names if name in params] + [-1]
    outputs = scene.output_names()
    return [
        c.define("CP_NELASTIC", len(elastic)),
        "/* Each elastic rope's taut margin among the outputs from CP_MARGIN_OUTPUT on; what the",
        "   integration saw of them (ROPE_EVENTS: CP_NELASTIC values each, in this order). */",
        c.define("CP_MARGIN_OUTPUT", outputs.index(f"taut_margin{elastic[0]}")),
        *(c.define(f"CP_ROPE_EVENT_{stem.upper()}", k) for k, stem in enumerate(ROPE_EVENTS)),
        c.define("CP_NROPE_EVENT", len(scene.rope_event_scalars())),
        "/* Each elastic rope (Scene.elastic_ropes' order): its place among the ropes, where its",
        "   reach r<i> and v_r<i> = r<i>' are in x, its EA<i> and zeta_rope<i> in p, and its law's",
        "   T_law<i> (s_taut<i>, margin<i> after it) in the core's p; then the masses hanging from",
        "   each, their places in p, each rope's list ended by -1 (its damping ratio is of their",
        "   stretch). */",
        *(
            f"static const int cp_elastic_{name}[CP_NELASTIC] = {c.initializer(places)};"
            for name, places in (
                ("rope", [scene.ropes().index(i) for i in elastic]),
                ("reach", [states.index(f"r{i}") for i in elastic]),
                ("rate", [states.index(f"v_r{i}") for i in elastic]),
                ("stiffness", [params.index(f"EA{i}") for i in elastic]),
                ("damping", [params.index(f"zeta_rope{i}") for i in elastic]),
                ("law", [core.index(f"T_law{i}") for i in elastic]),
            )
        ),
        "static const int cp_elastic_masses[] = " + c.initializer(below) + ";",
    ]


def _header(scene: Scene, nparam: int, noutput: int, needs_rates: bool, lines: list[str]) -> str:
    """model.h: the sizes and names every formulation shares, then its own lines."""
    ndof = scene.dof()
    return c.fill(
        "model.h.in",
        sizes="\n".join(
            [
                c.define("CP_NDOF", ndof),
                c.define("CP_NSTATE", len(scene.state_names())),
                c.define("CP_NPARAM", nparam),
                c.define("CP_NINPUT", len(scene.input_names())),
                c.define("CP_NOUTPUT", noutput),
                c.define("CP_STATE_NAMES", c.string(" ".join(scene.state_names()))),
                c.define("CP_PARAMETER_NAMES", c.string(" ".join(scene.core_parameter_names()))),
                c.define("CP_OUTPUT_NAMES", c.string(" ".join(scene.output_names()))),
            ]
        ),
        outputs_need_rates=c.define("CP_OUTPUTS_NEED_RATES", int(needs_rates)),
        force_output=c.define("CP_FORCE_OUTPUT", _index(scene.output_names(), "F_pivot_x")),
        statistics="\n".join(
            [
                *(c.define(f"CP_STAT_{name.upper()}", k) for k, name in enumerate(STATISTICS)),
                c.define("CP_NSTAT", len(STATISTICS)),
            ]
        ),
        formulation="\n".join(lines + _books(scene) + _ropes(scene) + _jumps(scene)),
    )


def _places(what: str, noun: str, links: list[int], n: int, order: str) -> list[str]:
    """The recursive header's cp_link_<what>: each of the n links' place among links, the
    links that are a <noun> (no line without any)."""
    if not links:
        return []
    return [
        f"/* Each link's {noun} (its place in {order}). */",
        f"static const int cp_link_{what}[CP_NLINK] = "
        + c.initializer(links.index(i) if i in links else -1 for i in range(n))
        + ";",
    ]


def _index(names: list[str], name: str) -> int:
    return names.index(name) if name in names else -1


def generate_recursive(scene: Scene) -> dict[str, str]:
    """C sources of the recursive formulation: the link table, and one joint's kinematics
    from sympy (the loops over the links are runtime/csrc/core/chain.c)."""
    scalars = scene.core_parameter_scalars()
    names = [scalar.name for scalar in scalars]
    where = {(scalar.quantity, scalar.link): k for k, scalar in enumerate(scalars)}

    def index(quantity, link=None):  # -1: the body is absent
        return where.get((quantity, link), -1)

    links = c.rows(
        [
            c.initializer(index(quantity, i) for quantity in ("l", "m", "M", "Ixx", "Iyy", "Izz"))
            for i in range(scene.n)
        ],
        [f"link {i}" for i in range(scene.n)],
    )
    pivot = index(scene.input_scalars()[0].quantity) if scene.coupling else -1
    ropes, elastic = scene.ropes(), scene.elastic_ropes()
    header = _header(
        scene,
        len(names),
        len(scene.output_names()),
        scene.coupling or bool(ropes),  # the pivot force and the ropes' tensions need u'
        [
            "#define CP_RECURSIVE 1",
            c.define("CP_NLINK", scene.n),
            *_places("rope", "rope", ropes, scene.n, "Scene.ropes' order; -1: its length is fixed"),
            *_places("elastic", "elastic rope", elastic, scene.n, "Scene.elastic_ropes' order; -1: none"),
            c.define("CP_G_INDEX", index("g")),
            c.define("CP_PIVOT_INDEX", pivot),
            *([c.define("CP_DAMPING_INDEX", index("c", 0))] if scene.joint_damping else []),
            *(
                [
                    "#define CP_BOB_FORCES 1",
                    "/* Where each bob's applied force F_bob<i>_x/y/z starts in p (-1: none). */",
                    "static const int cp_bob_force[CP_NLINK] = "
                    + c.initializer(index("F_bob_x", i) for i in range(scene.n))
                    + ";",
                ]
                if scene.forced_bobs()
                else []
            ),
            *(
                [
                    "#define CP_DRAG 1",
                    c.define("CP_RHO_INDEX", index("rho")),
                    c.define("CP_WIND_INDEX", index("wind_x")),
                    c.define("CP_PIVOT_VELOCITY_INDEX", index("v_pivot_x")),
                    "/* Where each bob's drag coefficient C_d<i> and area A<i> are in p (-1: no drag). */",
                    "static const int cp_bob_drag[CP_NLINK] = "
                    + c.initializer(index("C_d", i) for i in range(scene.n))
                    + ";",
                    "static const int cp_bob_area[CP_NLINK] = "
                    + c.initializer(index("A", i) for i in range(scene.n))
                    + ";",
                ]
                if scene.air_drag
                else []
            ),
            *(
                c.define(f"CP_OUTPUT_{group.upper()}", int(group in scene.outputs))
                for group in ("bobs", "poses", "energy")
            ),
            '#include "chain.h"',
            "/* Where each link's parameters are in p (-1: the body is absent). */",
            "static const cp_link_params cp_links[CP_NLINK] = {",
            links,
            "};",
        ],
    )
    a, b, dcm, jac = joint_kinematics()
    printer = _Printer()
    targets = (
        [(f"C[{k}]", v) for k, v in enumerate(dcm)]
        + [(f"J[{k}]", v) for k, v in enumerate(jac)]
        + [(f"Ja[{k}]", v) for k, v in enumerate(jac.diff(a))]
        + [(f"Jb[{k}]", v) for k, v in enumerate(jac.diff(b))]
    )
    temps, reduced = sm.cse([v for _, v in targets], symbols=sm.numbered_symbols("t"))
    body = [f"    const cp_real {t} = {printer.doprint(v)};" for t, v in temps]
    body += [f"    {lvalue} = {printer.doprint(v)};" for (lvalue, _), v in zip(targets, reduced)]
    source = "\n".join(
        [
            "/* Generated by conical_pendulum.builder.core.codegen: do not edit. */",
            "#include <math.h>",
            '#include "model.h"',
            "",
            "void cp_joint(cp_real a, cp_real b, cp_real C[9], cp_real J[6], cp_real Ja[6], cp_real Jb[6])",
            "{",
            *body,
            "}",
            "",
        ]
    )
    return {"model.h": header, "model.c": _analytic(source)}


def generate(eqs: Equations) -> dict[str, str]:
    """C sources of the model: {'model.h': ..., 'model.c': ...}."""
    ndof = eqs.mass_matrix.shape[0]
    needed = _needed(eqs.definitions, eqs.outputs)
    symbols = set().union(
        *(sm.sympify(e).free_symbols for e in eqs.outputs), *(e.free_symbols for _, e in needed)
    )
    needs_rates = bool(symbols & set(eqs.rates))
    momentum_signature = "void cp_momentum(const cp_real *x, const cp_real *p, cp_real *P, cp_real *total)"
    header = _header(
        eqs.scene,
        len(eqs.scene.core_parameter_names()),
        len(eqs.scene.output_names()),
        needs_rates,
        [
            "#define CP_RECURSIVE 0",
            *(
                []
                if eqs.momentum is None
                else [
                    "/* P: the chain's linear momentum per generalized speed, 3 x CP_NDOF row-major, and",
                    "   its total mass: F_pivot = F_free - (total I - P M^-1 P^T) a_pivot. */",
                    momentum_signature + ";",
                ]
            ),
        ],
    )
    upper = [(f"M[{i * ndof + j}]", eqs.mass_matrix[i, j]) for i in range(ndof) for j in range(i, ndof)]
    forcing = [(f"F[{r}]", eqs.forcing[r]) for r in range(ndof)]
    mirror = [f"    M[{j * ndof + i}] = M[{i * ndof + j}];" for i in range(ndof) for j in range(i + 1, ndof)]
    mass = _function(
        "void cp_mass_forcing(const cp_real *x, const cp_real *p, cp_real *M, cp_real *F)",
        eqs,
        upper + forcing,
        epilogue=mirror,
    )
    signature = "void cp_outputs(const cp_real *x, const cp_real *p, const cp_real *dx, cp_real *y)"
    unused = (
        ["    (void)x; (void)p; (void)dx; (void)y;"]
        if not eqs.outputs
        else []
        if needs_rates
        else ["    (void)dx;"]
    )
    # the outputs' slots: F_free and M_app (after F_pivot) are dynamics.c's
    slots = [k for k, name in enumerate(eqs.scene.output_names()) if name not in FREE_FORCE + APPARENT_MASS]
    outputs = _function(signature, eqs, [(f"y[{k}]", e) for k, e in zip(slots, eqs.outputs)], prologue=unused)
    functions = [mass, outputs, *_work_function(eqs), *_energy_function(eqs)]
    if eqs.momentum is not None:
        functions.append(
            _function(
                momentum_signature,
                eqs,
                [
                    *((f"P[{i * ndof + j}]", eqs.momentum[i, j]) for i in range(3) for j in range(ndof)),
                    ("*total", eqs.total_mass),
                ],
            )
        )
    source = (
        "\n\n".join(
            [
                "/* Generated by conical_pendulum.builder.core.codegen: do not edit. */",
                '#include <math.h>\n#include "model.h"',
                *functions,
            ]
        )
        + "\n"
    )
    return {"model.h": header, "model.c": _analytic(source)}
