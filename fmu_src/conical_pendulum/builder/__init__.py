"""Build time: scene -> sympy equations -> generated C -> compiled core -> FMU.

Needs sympy, Cython, a C compiler and pythonfmu; nothing here ships inside an FMU.
"""
