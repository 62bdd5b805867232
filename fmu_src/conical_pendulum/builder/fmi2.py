"""The native FMU's FMI 2.0 writer: its model description (Co-Simulation and Model Exchange,
a SourceFiles list, a complete ModelStructure by index), from the variables' records
(builder.variables); builder.native packs it with fmi2_glue.c."""

from __future__ import annotations

import time
import xml.etree.ElementTree as ET

from .native_model import LOG_CATEGORIES, MAX_DERIVATIVE_ORDER, Description, Standard
from .variables import Variable, model_structure


def model_description(described: Description) -> bytes:
    """modelDescription.xml (FMI 2.0) for both interfaces of the model."""
    model, records = described.model, described.records
    root = ET.Element(
        "fmiModelDescription",
        {
            "fmiVersion": "2.0",
            "modelName": model.name,
            "guid": described.guid,
            "description": described.data["description"],
            "author": "conical-pendulum-fmu",
            "generationTool": "conical_pendulum.builder.native",
            "generationDateAndTime": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "variableNamingConvention": "structured",
            "numberOfEventIndicators": "0",
        },
    )
    common = {
        "modelIdentifier": model.name,
        "needsExecutionTool": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false",
        "canGetAndSetFMUstate": "true",
        "canSerializeFMUstate": "true",
        "providesDirectionalDerivative": "true",
    }
    for kind, extra in (
        ("ModelExchange", {"completedIntegratorStepNotNeeded": "true"}),
        (
            "CoSimulation",
            {
                "canHandleVariableCommunicationStepSize": "true",
                "canInterpolateInputs": "true",
                "maxOutputDerivativeOrder": str(MAX_DERIVATIVE_ORDER),
            },
        ),
    ):
        interface = ET.SubElement(root, kind, {**common, **extra})
        files = ET.SubElement(interface, "SourceFiles")
        for name in described.sources:
            ET.SubElement(files, "File", name=name)
    categories = ET.SubElement(root, "LogCategories")
    for name, text in LOG_CATEGORIES.items():
        ET.SubElement(categories, "Category", name=name, description=text)
    ET.SubElement(root, "DefaultExperiment", startTime="0.0", stopTime="10.0", stepSize=repr(model.step_size))
    index = {v.name: str(v.value_reference + 1) for v in records}  # its place in ModelVariables
    _model_variables(ET.SubElement(root, "ModelVariables"), records, index)
    _model_structure(ET.SubElement(root, "ModelStructure"), records, index)
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _model_variables(variables: ET.Element, records: list[Variable], index: dict[str, str]) -> None:
    """ModelVariables: one ScalarVariable per record, in value-reference order."""
    for v in records:
        attributes = {
            "name": v.name,
            "valueReference": str(v.value_reference),
            "description": v.description,
            "causality": v.causality,
            "variability": v.variability,
        }
        if v.initial:
            attributes["initial"] = v.initial
        value = {}
        if v.start is not None:
            value["start"] = v.start_text()
        if v.derivative_of:
            value["derivative"] = index[v.derivative_of]
        ET.SubElement(ET.SubElement(variables, "ScalarVariable", attributes), v.type, value)


def _model_structure(element: ET.Element, records: list[Variable], index: dict[str, str]) -> None:
    """ModelStructure by index: builder.variables.model_structure's unknowns, each list in the
    order of ModelVariables, as FMI 2.0 asks."""
    structure = model_structure(records)
    for tag, unknowns in (("Outputs", structure.outputs), ("Derivatives", structure.derivatives)):
        listed = ET.SubElement(element, tag)
        for v in unknowns:
            dependencies = " ".join(index[name] for name in v.depends_on)
            ET.SubElement(listed, "Unknown", index=index[v.name], dependencies=dependencies)
    initial = ET.SubElement(element, "InitialUnknowns")
    for v in structure.initial_unknowns:
        ET.SubElement(initial, "Unknown", index=index[v.name])


FMI2 = Standard(
    version=2,
    model_description=model_description,
    platform_folders={"linux64": "linux64", "win64": "win64"},
    headers=lambda described: {},
    files=lambda described: {},
)
