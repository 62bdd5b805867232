"""FMUs packed: the native FMU compiled per platform and zipped (native.py), the pythonfmu
FMU's binary (pythonfmu_export.py) and its model description's fixes
(pythonfmu_description.py).

Imports of builder/ only core/, fmi/ and builder.c_literals; builder.fmu drives it.
"""
