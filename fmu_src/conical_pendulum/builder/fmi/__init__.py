"""What an FMU declares, written once for both FMI versions: its variables as records
(variables.py), units (units.py), each version's writer (fmi2.py, fmi3.py), the native
FMU's fmu_config.h (fmu_config.py), and the types where models and writers meet
(contract.py: NativeModel, Standard, Description).

Imports of builder/ only core/ (the dependencies the records list) and builder.c_literals.
"""
