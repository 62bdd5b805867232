"""The shapes FMU (shapes_fmu.c): a small FMI 2.0 Co-Simulation FMU of another shape than the
pendulum's, with Integer and Boolean outputs and steps that fail or crash on request, built
for the runner's and the sweep's tests."""

import subprocess
import zipfile
from pathlib import Path

from conical_pendulum.builder.packaging.native import fmi_headers

MODES = {
    "never": 0,
    "discard and terminate": 1,
    "discard": 2,
    "error": 3,
    "segfault": 4,
    "stuck": 5,
}  # parameter mode
SHAPES_VARIABLES = [  # name, value reference, type, causality, start
    ("x", 0, "Real", "output", None),
    ("h", 1, "Real", "output", None),
    ("gain", 2, "Real", "parameter", "1.0"),
    ("fail_at", 3, "Real", "parameter", "1e300"),
    ("nan_at", 4, "Real", "parameter", "1e300"),
    ("count", 0, "Integer", "output", None),
    ("mode", 1, "Integer", "parameter", "0"),
    ("repeats", 2, "Integer", "parameter", "1"),
    ("above", 0, "Boolean", "output", None),
]


def shapes_model_description(variable_steps: bool) -> str:
    variables, outputs = [], []
    for index, (name, vr, kind, causality, start) in enumerate(SHAPES_VARIABLES, start=1):
        if causality == "output":
            variability = "continuous" if kind == "Real" else "discrete"
            attributes, value = f'variability="{variability}" initial="calculated"', f"<{kind}/>"
            outputs.append(f'<Unknown index="{index}"/>')
        else:
            attributes, value = 'variability="fixed" initial="exact"', f'<{kind} start="{start}"/>'
        variables.append(
            f'<ScalarVariable name="{name}" valueReference="{vr}" causality="{causality}" {attributes}>'
            f"{value}</ScalarVariable>"
        )
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="Shapes" guid="{{shapes}}" numberOfEventIndicators="0">
<CoSimulation modelIdentifier="shapes" canHandleVariableCommunicationStepSize="{str(variable_steps).lower()}"/>
<ModelVariables>{"".join(variables)}</ModelVariables>
<ModelStructure><Outputs>{"".join(outputs)}</Outputs></ModelStructure>
</fmiModelDescription>"""


def build_shapes_fmus(folder: Path) -> dict[bool, Path]:
    """The shapes FMU by whether it handles a variable communication step, built in folder."""
    library = folder / "shapes.so"
    source = Path(__file__).with_name("shapes_fmu.c")
    subprocess.run(
        ["cc", "-std=c99", "-O2", "-shared", "-fPIC", f"-I{fmi_headers()}", str(source), "-o", str(library)],
        check=True,
    )
    fmus = {}
    for variable_steps in (True, False):
        path = folder / f"Shapes{'Variable' if variable_steps else 'Fixed'}.fmu"
        with zipfile.ZipFile(path, "w") as archive:
            archive.writestr("modelDescription.xml", shapes_model_description(variable_steps))
            archive.write(library, "binaries/linux64/shapes.so")
        fmus[variable_steps] = path
    return fmus
