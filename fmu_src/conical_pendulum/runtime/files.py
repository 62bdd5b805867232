"""Names the build and the slaves share: the FMU's model name and its scene's resource file.

No imports, so that the build (builder/fmu.py, builder/packaging/native.py) reads them without
loading a slave, which needs pythonfmu and numpy.
"""

MODEL_NAME = (
    "ConicalPendulum"  # modelName and modelIdentifier: the pythonfmu slave's class, the native binary
)
MODEL_FILE = "model.json"  # in the FMU's resources: the scene's variables, settings and core (builder/fmu.py)
