"""The native FMU's FMI 2.0 writer: its model description (Co-Simulation and Model Exchange,
a SourceFiles list, a complete ModelStructure by index), from the variables' records
(builder.fmi.variables); builder.packaging.native packs it with fmi2_glue.c."""

from __future__ import annotations

import time
import xml.etree.ElementTree as ET

from ...runtime.rules import RULES
from .contract import LOG_CATEGORIES, MAX_DERIVATIVE_ORDER, Description, Standard
from .units import attributes, enumerations, unit_definitions
from .variables import Structure, Variable, model_structure


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
            "generationTool": "conical_pendulum.builder.packaging.native",
            "generationDateAndTime": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "variableNamingConvention": "structured",
            "numberOfEventIndicators": str(len(event_indicators(records))),
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
    unit_definitions(root, records)
    type_definitions(root, records)
    categories = ET.SubElement(root, "LogCategories")
    for name, text in LOG_CATEGORIES.items():
        ET.SubElement(categories, "Category", name=name, description=text)
    default_experiment(root, described)
    index = {v.name: str(v.value_reference + 1) for v in records}  # its place in ModelVariables
    _model_variables(ET.SubElement(root, "ModelVariables"), records, index)
    _model_structure(ET.SubElement(root, "ModelStructure"), records, index)
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def event_indicators(records: list[Variable]) -> list[Variable]:
    """Model Exchange's event indicators, in the order the model gives them
    (model_get_event_indicators): each elastic rope's taut margin, an output."""
    return [v for v in records if v.group == "outputs" and v.quantity == "taut_margin"]


def default_experiment(root: ET.Element, described: Description) -> None:
    """The DefaultExperiment: 10 s at the model's step size, and, where the model has a relative
    tolerance (rtol), its start as the tolerance: what a Model Exchange host integrates with,
    and what a co-simulation master passing it on leaves the FMU's own tolerance at."""
    ET.SubElement(
        root,
        "DefaultExperiment",
        startTime="0.0",
        stopTime="10.0",
        stepSize=repr(described.model.step_size),
        **experiment_tolerance(described.records),
    )


def experiment_tolerance(records: list[Variable]) -> dict[str, str]:
    """The DefaultExperiment's tolerance attribute: rtol's start, where the model has an rtol."""
    rtol = [v.start for v in records if v.name == "rtol"]
    return {"tolerance": repr(float(rtol[0]))} if rtol else {}


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
        ET.SubElement(ET.SubElement(variables, "ScalarVariable", attributes), *typed(v, value))


def typed(v: Variable, value: dict[str, str]) -> tuple[str, dict[str, str]]:
    """A variable's type element (Real, Integer, or Enumeration of its declared type) and its
    attributes: builder.fmi.units's (quantity, unit, range, nominal), then `value`'s (start,
    derivative)."""
    rule = RULES[v.rule]
    if rule.items:
        return "Enumeration", {"declaredType": rule.type_name, **value}
    return v.type, {**attributes(v), **value}


def type_definitions(root: ET.Element, records: list[Variable]) -> None:
    """<TypeDefinitions>: the enumerations the records use (builder.fmi.units.enumerations)."""
    found = enumerations(records)
    if not found:
        return
    table = ET.SubElement(root, "TypeDefinitions")
    for name, items in found.items():
        listed = ET.SubElement(ET.SubElement(table, "SimpleType", name=name), "Enumeration")
        for value, (item, text) in enumerate(items):
            ET.SubElement(listed, "Item", name=item, value=str(value), description=text)


def _model_structure(element: ET.Element, records: list[Variable], index: dict[str, str]) -> None:
    """ModelStructure by index: builder.fmi.variables.model_structure's unknowns, each list in the
    order of ModelVariables and each entry with its dependencies, as FMI 2.0 asks."""
    write_structure(element, model_structure(records), index)


def write_structure(element: ET.Element, structure: Structure, index: dict[str, str]) -> None:
    """The lists of an FMI 2.0 ModelStructure (Derivatives only where there are some), every
    Unknown with its dependencies by index (builder.packaging.pythonfmu_description writes the pythonfmu
    FMU's with this too)."""
    for tag, unknowns in (
        ("Outputs", structure.outputs),
        ("Derivatives", structure.derivatives),
        ("InitialUnknowns", structure.initial_unknowns),
    ):
        if not unknowns:
            continue
        listed = ET.SubElement(element, tag)
        for unknown in unknowns:
            dependencies = " ".join(index[v.name] for v in unknown.dependencies)
            ET.SubElement(listed, "Unknown", index=index[unknown.variable.name], dependencies=dependencies)


FMI2 = Standard(
    version=2,
    model_description=model_description,
    # x86 only: FMI 2.0.4 names other platforms by FMI 3.0's tuples (aarch64-linux), FMPy and
    # OpenModelica load an ARM Linux binary from linux64 (docs/native.md#platforms)
    platform_folders={"linux64": "linux64", "win64": "win64"},
    headers=lambda described: {},
    files=lambda described: {},
)
