"""What ships inside an FMU: the pythonfmu slaves, the value rules, and the C core and solvers.

Imports nothing from build time and nothing outside the standard library, numpy and
pythonfmu (scipy only for the Radau fallback and the demo's cart), because it runs in
the host's process under a package name unique to its FMU.
"""
