"""The native FMU's FMI 3.0 writer: the native FMU's C with fmi3_glue.c instead of fmi2_glue.c.

One FMU with Co-Simulation and Model Exchange, the same model contract (fmu_model.h), the
same variables and value references as the FMI 2.0 native FMU (builder.fmi.variables, backend
"native"), Float64 for Real and Int32 for Integer, and each per-link quantity one array (its
records' `array` and `index`). What FMI 3.0 words differently is here: the model description
(instantiationToken, <Float64>/<Int32>, arrays sized by the model's structural parameter, a
ModelStructure by value reference), fmi3_arrays.h, the binaries' folders (x86_64-linux,
x86_64-windows) and sources/buildDescription.xml instead of a SourceFiles list. builder.packaging.native
packs it (FMI3, a Standard); a model without arrays (the cart) has no structural parameter.
Reading such an FMU's results back is analysis.fmi3_arrays's.
"""

from __future__ import annotations

import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from ...runtime.rules import RULES
from .. import c_literals as c
from .contract import LOG_CATEGORIES, MAX_DERIVATIVE_ORDER, Description, Standard
from .fmi2 import default_experiment, event_indicators
from .units import TIME, attributes, declared, enumerations, unit_definitions
from .variables import Variable, describe, model_structure

TYPES = {"Real": "Float64", "Integer": "Int32"}


@dataclass(frozen=True)
class Fmi3Variable:
    """One variable of the FMI 3.0 FMU: a scalar of the records, or an array of the records of
    one `array` (members, in index order); its value reference is its first member's (the
    model contract's)."""

    name: str
    members: tuple[Variable, ...]
    array: bool

    @property
    def value_reference(self) -> int:
        return self.members[0].value_reference


def layout(records: list[Variable]) -> list[Fmi3Variable]:
    """The FMI 3.0 FMU's variables, in the order of the records' value references (an array
    where its first member is): each record of an array (builder.fmi.variables) in its array,
    the rest scalars."""
    arrays: dict[str, list[Variable]] = {}
    for v in records:
        if v.array is not None:
            arrays.setdefault(v.array, []).append(v)
    result = []
    for v in records:
        if v.array is None:
            result.append(Fmi3Variable(v.name, (v,), False))
        elif v is arrays[v.array][0]:
            result.append(Fmi3Variable(v.array, tuple(sorted(arrays[v.array], key=lambda m: m.index)), True))
    return result


def dimension_size(records: list[Variable]) -> int | None:
    """The size of every array (its elements, one per link), or None without arrays."""
    sizes = {len(v.members) for v in layout(records) if v.array}
    if len(sizes) > 1:
        raise ValueError(f"arrays of sizes {sorted(sizes)}: FMI 3.0's one structural parameter sizes all")
    return sizes.pop() if sizes else None


def arrays_header(described: Description) -> str:
    """fmi3_arrays.h, for fmi3_glue.c and any model: the value reference of time; each array's
    value reference and its members' (the model contract's scalars, in link order), and the
    structural parameter of their dimension, only where there are arrays (C has no empty
    arrays, and the glue asks CP_NARRAY and CP_VR_DIMENSION whether there are)."""
    records, dimension = described.records, described.model.dimension
    arrays = [v for v in layout(records) if v.array]
    hidden = {m.value_reference for v in arrays for m in v.members[1:]}
    size = dimension_size(records)
    n_variables = len(records)
    text = (
        c.fill(
            "fmi3_dimension.h.in",
            name=dimension.name,
            vr_dimension=c.define("CP_VR_DIMENSION", n_variables + 1),
            size=c.define("CP_DIMENSION", size),
            refusal=c.define(
                "CP_DIMENSION_REFUSAL",
                c.string(f"{dimension.name} = %llu: " + dimension.refusal.format(size=size)),
            ),
            array_vrs=c.initializer(v.value_reference for v in arrays),
            members=c.rows(
                [c.initializer(m.value_reference for m in v.members) for v in arrays],
                [v.name for v in arrays],
            ),
        ).rstrip("\n")
        if arrays
        else "/* No arrays: every variable a scalar, no structural parameter. */"
    )
    return c.fill(
        "fmi3_arrays.h.in",
        vr_time=c.define("CP_VR_TIME", n_variables),
        n_array=c.define("CP_NARRAY", len(arrays)),
        dimension=text,
        n_variables=n_variables,
        hidden=c.initializer("1" if k in hidden else "0" for k in range(n_variables)),
        enumeration=c.initializer("1" if RULES[v.rule].items else "0" for v in records),
    )


def _description(variable: Fmi3Variable) -> str:
    first = variable.members[0]
    if not variable.array:
        return first.description
    own = first.description.removeprefix(describe(first.quantity, first.link))  # a load's words
    return describe(first.quantity, every_link=True) + own + " (element [k + 1]: link k)"


def model_description(described: Description) -> bytes:
    """modelDescription.xml (FMI 3.0) for both interfaces of the model: the same variables and
    value references as its FMI 2.0 native FMU; no clocks, no event mode in Co-Simulation, the
    elastic ropes' taut margins Model Exchange's event indicators; the structural parameter
    only where there are arrays (arrays_header)."""
    model, records = described.model, described.records
    root = ET.Element(
        "fmiModelDescription",
        {
            "fmiVersion": "3.0",
            "modelName": model.name,
            "instantiationToken": described.guid,
            "description": described.data["description"],
            "author": "conical-pendulum-fmu",
            "generationTool": "conical_pendulum.builder.fmi.fmi3",
            "generationDateAndTime": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "variableNamingConvention": "structured",
        },
    )
    common = {
        "modelIdentifier": model.name,
        "needsExecutionTool": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false",
        "canGetAndSetFMUState": "true",
        "canSerializeFMUState": "true",
        "providesDirectionalDerivatives": "true",
        "providesAdjointDerivatives": "true",
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
            "maxOutputDerivativeOrder": str(MAX_DERIVATIVE_ORDER),
            "providesIntermediateUpdate": "false",
            "mightReturnEarlyFromDoStep": "true",
            "canReturnEarlyAfterIntermediateUpdate": "false",
            "hasEventMode": "false",
        },
    )
    unit_definitions(root, records, also=(TIME,))
    found = enumerations(records)
    if found:
        table = ET.SubElement(root, "TypeDefinitions")
        for name, items in found.items():
            listed = ET.SubElement(table, "EnumerationType", name=name)
            for value, (item, text) in enumerate(items):
                ET.SubElement(listed, "Item", name=item, value=str(value), description=text)
    categories = ET.SubElement(root, "LogCategories")
    for category, text in LOG_CATEGORIES.items():
        ET.SubElement(categories, "Category", name=category, description=text)
    default_experiment(root, described)
    variables_ = layout(records)
    vr = {m.name: str(v.value_reference) for v in variables_ for m in v.members}  # an element: its array's
    _model_variables(ET.SubElement(root, "ModelVariables"), described, variables_, vr)
    _model_structure(ET.SubElement(root, "ModelStructure"), records, variables_, vr)
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _model_variables(
    variables: ET.Element, described: Description, variables_: list[Fmi3Variable], vr
) -> None:
    """ModelVariables: time, the arrays' structural parameter if there are arrays, then the
    variables (arrays and scalars) by value reference."""
    model, records = described.model, described.records
    n_variables = len(records)
    ET.SubElement(  # FMI 3.0 names the independent variable (fmi3_arrays.h's CP_VR_TIME)
        variables,
        "Float64",
        name="time",
        valueReference=str(n_variables),
        description="simulation time",
        causality="independent",
        variability="continuous",
        quantity=declared(TIME).quantity,
        unit=TIME,
    )
    if any(variable.array for variable in variables_):
        ET.SubElement(  # the arrays' dimension (fmi3_arrays.h's CP_VR_DIMENSION)
            variables,
            "UInt64",
            name=model.dimension.name,
            valueReference=str(n_variables + 1),
            description=model.dimension.description,
            causality="structuralParameter",
            variability="fixed",
            start=str(dimension_size(records)),
        )
    for variable in variables_:
        v = variable.members[0]
        attributes = {
            "name": variable.name,
            "valueReference": str(variable.value_reference),
            "description": _description(variable),
            "causality": v.causality,
            "variability": v.variability,
        }
        if v.initial:
            attributes["initial"] = v.initial
        tag, values = _values(variable)
        attributes |= values
        if v.start is not None:
            attributes["start"] = " ".join(m.start_text() for m in variable.members)
        if v.derivative_of:
            attributes["derivative"] = vr[v.derivative_of]
        element = ET.SubElement(variables, tag, attributes)
        if variable.array:
            ET.SubElement(element, "Dimension", valueReference=str(n_variables + 1))


def _values(variable: Fmi3Variable) -> tuple[str, dict[str, str]]:
    """The variable's type (Float64, Int32, or Enumeration of its declared type) and what
    builder.fmi.units says of its values; an array's elements must say the same (FMI 3.0 has one
    unit, range and nominal per array)."""
    v = variable.members[0]
    rule = RULES[v.rule]
    if rule.items:
        return "Enumeration", {"declaredType": rule.type_name}
    said = {m.name: attributes(m) for m in variable.members}
    if len({tuple(sorted(a.items())) for a in said.values()}) > 1:
        raise ValueError(f"the elements of {variable.name} differ in unit, range or nominal: {said}")
    return TYPES[v.type], said[v.name]


def _model_structure(
    element: ET.Element, records: list[Variable], variables_: list[Fmi3Variable], vr
) -> None:
    """ModelStructure by value reference: builder.fmi.variables.model_structure's unknowns, and
    the event indicators (outputs, with their dependencies)."""
    structure = model_structure(records)
    indicators = {v.name for v in event_indicators(records)}
    # FMI 3.0's order: Output, ContinuousStateDerivative, ClockedState (none), InitialUnknown,
    # EventIndicator, each by value reference; an array is an unknown where its first element
    # is, and depends on what any of its elements does (providesPerElementDependencies is false)
    for tag, unknowns in (
        ("Output", structure.outputs),
        ("ContinuousStateDerivative", structure.derivatives),
        ("InitialUnknown", structure.initial_unknowns),
        ("EventIndicator", [u for u in structure.outputs if u.variable.name in indicators]),
    ):
        listed = {u.variable.name: u for u in unknowns}
        for variable in variables_:
            members = [listed[m.name] for m in variable.members if m.name in listed]
            if not members:
                continue
            known = sorted(
                {vr[k.name]: k.value_reference for u in members for k in u.dependencies}.items(),
                key=lambda item: item[1],
            )
            ET.SubElement(
                element,
                tag,
                valueReference=str(variable.value_reference),
                dependencies=" ".join(reference for reference, _ in known),
            )


def build_description(sources: list[str], model_identifier: str) -> bytes:
    """sources/buildDescription.xml: the C sources a host compiles into the binary."""
    root = ET.Element("fmiBuildDescription", fmiVersion="3.0")
    configuration = ET.SubElement(root, "BuildConfiguration", modelIdentifier=model_identifier)
    files = ET.SubElement(configuration, "SourceFileSet", language="C99")
    for name in sources:
        ET.SubElement(files, "SourceFile", name=name)
    ET.SubElement(configuration, "Library", name="m")
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


# FMI 3.0's platform tuples for builder.packaging.native's platforms (section 2.5.1.1).
PLATFORM_FOLDERS = {"linux64": "x86_64-linux", "win64": "x86_64-windows", "aarch64-linux": "aarch64-linux"}

FMI3 = Standard(
    version=3,
    model_description=model_description,
    platform_folders=PLATFORM_FOLDERS,
    headers=lambda described: {"fmi3_arrays.h": arrays_header(described)},
    files=lambda described: {
        "buildDescription.xml": build_description(described.sources, described.model.name)
    },
)
