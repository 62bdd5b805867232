"""Scene -> compiled core: the sympy derivation (equations.py, with kane.py, sympy's own
KanesMethod, as its reference), what each output and derivative depends on (dependencies.py),
the generated C (codegen.py) and the Cython core built and cached (compiler.py).

Knows no FMI: imports nothing of the other roles of builder/ but builder.c_literals.
"""
