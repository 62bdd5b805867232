"""Scene -> compiled core: the sympy derivation (equations.py, with kane.py, sympy's own
KanesMethod, as its reference), what each output and derivative depends on (dependencies.py),
the generated C (codegen.py) and where the compiled builds are kept (cache.py); the Cython
core itself is built by builder.compiler, above the models it holds.

Knows no FMI: imports nothing of the other roles of builder/ but builder.c_literals.
"""
