"""Scene -> a native FMI 3.0 FMU: the native FMU's C with fmi3_glue.c instead of fmi2_glue.c.

One FMU with Co-Simulation and Model Exchange, the same model contract (fmu_model.h), the
same variables and value references as the FMI 2.0 native FMU (builder.variables, backend
"native"), Float64 for Real and Int32 for Integer. What FMI 3.0 words differently is here:
the model description (instantiationToken, <Float64>/<Int32>, a ModelStructure by value
reference), the binaries' folders (x86_64-linux, x86_64-windows) and sources/
buildDescription.xml instead of a SourceFiles list. builder.native compiles and packs it
(write_native_fmu(..., fmi_version=3)).
"""

from __future__ import annotations

import time
import xml.etree.ElementTree as ET

from ..runtime.files import MODEL_NAME

# FMI 3.0's platform tuples for builder.native's platforms (section 2.5.1.1).
PLATFORM_FOLDERS = {"linux64": "x86_64-linux", "win64": "x86_64-windows"}

TYPES = {"Real": "Float64", "Integer": "Int32"}


def _start(variable: dict) -> str:
    return repr(float(variable["start"])) if variable["type"] == "Real" else str(variable["start"])


def model_description(data: dict, token: str, log_categories: dict[str, str]) -> bytes:
    """modelDescription.xml (FMI 3.0) for both interfaces, from the variables' description
    (builder.variables, in model.json): the same variables and value references as the FMI 2.0
    native FMU; no clocks, no events, no event mode."""
    root = ET.Element(
        "fmiModelDescription",
        {
            "fmiVersion": "3.0",
            "modelName": MODEL_NAME,
            "instantiationToken": token,
            "description": data["description"],
            "author": "conical-pendulum-fmu",
            "generationTool": "conical_pendulum.builder.fmi3",
            "generationDateAndTime": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "variableNamingConvention": "structured",
        },
    )
    common = {
        "modelIdentifier": MODEL_NAME,
        "needsExecutionTool": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false",
        "canGetAndSetFMUState": "true",
        "canSerializeFMUState": "true",
        "providesDirectionalDerivatives": "true",
        "providesAdjointDerivatives": "false",
        "providesPerElementDependencies": "false",
        "providesEvaluateDiscreteStates": "false",
    }
    ET.SubElement(root, "ModelExchange", {**common, "needsCompletedIntegratorStep": "false"})
    ET.SubElement(
        root,
        "CoSimulation",
        {
            **common,
            "canHandleVariableCommunicationStepSize": "true",
            "maxOutputDerivativeOrder": "0",
            "providesIntermediateUpdate": "false",
            "canReturnEarlyAfterIntermediateUpdate": "false",
            "hasEventMode": "false",
        },
    )
    categories = ET.SubElement(root, "LogCategories")
    for name, text in log_categories.items():
        ET.SubElement(categories, "Category", name=name, description=text)
    ET.SubElement(root, "DefaultExperiment", startTime="0.0", stopTime="10.0", stepSize=repr(1.0 / 60.0))
    variables = ET.SubElement(root, "ModelVariables")
    vr = {v["name"]: str(v["value_reference"]) for v in data["variables"]}
    ET.SubElement(  # FMI 3.0 names the independent variable: after every other (fmi3_glue.c's VR_TIME)
        variables,
        "Float64",
        name="time",
        valueReference=str(len(data["variables"])),
        description="simulation time",
        causality="independent",
        variability="continuous",
    )
    for v in data["variables"]:
        attributes = {
            "name": v["name"],
            "valueReference": vr[v["name"]],
            "description": v["description"],
            "causality": v["causality"],
            "variability": v["variability"],
        }
        if v["initial"]:
            attributes["initial"] = v["initial"]
        if v["start"] is not None:
            attributes["start"] = _start(v)
        if v["derivative_of"]:
            attributes["derivative"] = vr[v["derivative_of"]]
        ET.SubElement(variables, TYPES[v["type"]], attributes)

    structure = ET.SubElement(root, "ModelStructure")

    def unknown(tag: str, v: dict, dependencies: bool = True) -> None:
        attributes = {"valueReference": vr[v["name"]]}
        if dependencies:
            attributes["dependencies"] = " ".join(vr[name] for name in v["depends_on"])
        ET.SubElement(structure, tag, attributes)

    # FMI 3.0's order: Output, ContinuousStateDerivative, InitialUnknown, each by value reference
    for v in data["variables"]:
        if v["causality"] == "output":
            unknown("Output", v)
    for v in data["variables"]:
        if v["derivative_of"]:
            unknown("ContinuousStateDerivative", v)
    for v in data["variables"]:  # no dependencies listed: they may depend on every known
        if v["initial"] in ("approx", "calculated") and (v["causality"] == "output" or v["derivative_of"]):
            unknown("InitialUnknown", v, dependencies=False)
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def build_description(sources: list[str]) -> bytes:
    """sources/buildDescription.xml: the C sources a host compiles into the binary."""
    root = ET.Element("fmiBuildDescription", fmiVersion="3.0")
    configuration = ET.SubElement(root, "BuildConfiguration", modelIdentifier=MODEL_NAME)
    files = ET.SubElement(configuration, "SourceFileSet", language="C99")
    for name in sources:
        ET.SubElement(files, "SourceFile", name=name)
    ET.SubElement(configuration, "Library", name="m")
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)
