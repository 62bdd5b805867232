"""What ships inside an FMU: the pythonfmu slave and its entry, the value rules, the names
the build and the slave share, and the C (csrc/: the core's numerics, the FMI layers, the
models behind the contract) with pythonfmu's export library sources.

Imports nothing from build time and nothing outside the standard library, numpy and
pythonfmu, because it runs in the host's process
under a package name unique to its FMU.
"""
