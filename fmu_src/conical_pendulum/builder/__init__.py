"""Build time: scene -> sympy equations -> generated C -> compiled core -> FMU.

By role, each importing only the roles above it: core/ (the derivation, the generated C, the
cache), fmi/ (what an FMU declares, per FMI version), packaging/ (native binaries,
pythonfmu's export library and model description), models/ (the models behind fmu_model.h);
compiler.py, the compiled core (the scene's numerics and the pendulum's model); fmu.py, the
entry (build_fmu, either backend), uses them all. c_literals.py and templates/,
the C text written one way, serve every role.

Needs sympy, Cython, a C compiler and pythonfmu; nothing here ships inside an FMU.
"""
