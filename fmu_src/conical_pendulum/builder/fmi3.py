"""Scene -> a native FMI 3.0 FMU: the native FMU's C with fmi3_glue.c instead of fmi2_glue.c.

One FMU with Co-Simulation and Model Exchange, the same model contract (fmu_model.h), the
same variables and value references as the FMI 2.0 native FMU (builder.variables, backend
"native"), Float64 for Real and Int32 for Integer. What FMI 3.0 words differently is here:
the model description (instantiationToken, <Float64>/<Int32>, a ModelStructure by value
reference), the binaries' folders (x86_64-linux, x86_64-windows) and sources/
buildDescription.xml instead of a SourceFiles list. builder.native compiles and packs it
(write_native_fmu(..., fmi_version=3), or write_model_fmu for any model behind the contract:
a model without links, the coupled demo's cart, has no arrays and no structural parameter).
"""

from __future__ import annotations

import json
import re
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass

# FMI 3.0's platform tuples for builder.native's platforms (section 2.5.1.1).
PLATFORM_FOLDERS = {"linux64": "x86_64-linux", "win64": "x86_64-windows"}

TYPES = {"Real": "Float64", "Integer": "Int32"}

# A per-link scalar's name: l0, bob2_x, link1_qw, der(alpha0) -> the array's name l, bob_x,
# link_qw, der(alpha) and the link (the element's 0-based index).
INDEXED = re.compile(r"^(?P<head>.*?[A-Za-z_(])(?P<link>\d+)(?P<tail>(_[A-Za-z]\w*)?\)?)$")
N_LINKS = "n_links"


@dataclass(frozen=True)
class Fmi3Variable:
    """One variable of the FMI 3.0 FMU: a scalar of the variables' description, or an array of
    one per-link scalar per link (members, in link order); its value reference is its first
    member's (the model contract's)."""

    name: str
    members: tuple[dict, ...]
    array: bool

    @property
    def value_reference(self) -> int:
        return self.members[0]["value_reference"]


def n_links(data: dict) -> int | None:
    """The pendulum's number of links; None for a model without a scene (the cart)."""
    return len(data["scene"]["links"]) if "scene" in data else None


def layout(data: dict) -> list[Fmi3Variable]:
    """The FMI 3.0 FMU's variables, from the variables' description (model.json's records):
    every group of Reals of one quantity per link (l0, l1, ... of one builder.variables group,
    each link present: l0 .. l<n-1>) becomes the array l, the rest stay scalars; in the order
    of the records' value references (an array where its first member is). A model without
    links has scalars only."""
    n, groups = n_links(data), {}
    for v in data["variables"] if n is not None else ():
        match = INDEXED.match(v["name"])
        if match and v["type"] == "Real":
            key = (match["head"] + match["tail"], v["group"])
            groups.setdefault(key, {})[int(match["link"])] = v
    arrays = {
        members[0]["name"]: (name, tuple(members[k] for k in range(n)))
        for (name, _), members in groups.items()
        if sorted(members) == list(range(n))
    }
    in_arrays = {m["name"] for _, members in arrays.values() for m in members}
    result = []
    for v in data["variables"]:
        if v["name"] in arrays:
            name, members = arrays[v["name"]]
            result.append(Fmi3Variable(name, members, True))
        elif v["name"] not in in_arrays:
            result.append(Fmi3Variable(v["name"], (v,), False))
    return result


def element_names(data: dict) -> dict[str, tuple[str, int]]:
    """Each per-link scalar's name -> (its array's name, its 0-based index): alpha0 -> (alpha, 0),
    which FMI 3.0's structured naming writes alpha[1]."""
    return {
        m["name"]: (variable.name, k)
        for variable in layout(data)
        if variable.array
        for k, m in enumerate(variable.members)
    }


def arrays_header(data: dict) -> str:
    """fmi3_arrays.h, for fmi3_glue.c and any model: the value reference of time; each array's
    value reference and its members' (the model contract's scalars, in link order), and the
    structural parameter n_links of their dimension, only where there are arrays (C has no
    empty arrays, and the glue asks CP_NARRAY and CP_VR_DIMENSION whether there are)."""
    arrays = [v for v in layout(data) if v.array]
    hidden = {m["value_reference"] for v in arrays for m in v.members[1:]}
    n_variables = len(data["variables"])
    dimension = [
        "/* FMI 3.0's arrays: the array of value reference cp_array_vr[a] holds the model",
        " * contract's Reals cp_array_members[a][0 .. CP_DIMENSION - 1], link by link. A member",
        " * other than the first is no FMI 3.0 variable (cp_array_hidden). Their dimension is the",
        f" * structural parameter {N_LINKS}, fixed by the build: its value reference, its value and",
        " * the refusal of another value (a format of that value, %llu). */",
        f"#define CP_VR_DIMENSION {n_variables + 1}",
        f"#define CP_DIMENSION {n_links(data)}",
        "#define CP_DIMENSION_REFUSAL "
        + json.dumps(
            f"{N_LINKS} = %llu: the number of links is fixed when the FMU is built ({n_links(data)}); "
            "build the FMU of another scene"
        ),
        "static const unsigned cp_array_vr[CP_NARRAY] = {"
        + ", ".join(str(v.value_reference) for v in arrays)
        + "};",
        "static const unsigned cp_array_members[CP_NARRAY][CP_DIMENSION] = {",
        *(
            "    {" + ", ".join(str(m["value_reference"]) for m in v.members) + f"}},  /* {v.name} */"
            for v in arrays
        ),
        "};",
    ]
    return "\n".join(
        [
            "/* Generated by conical_pendulum.builder.fmi3: do not edit. */",
            "#ifndef CP_FMI3_ARRAYS_H",
            "#define CP_FMI3_ARRAYS_H",
            "",
            "/* FMI 3.0's independent variable, after every variable of the model contract. */",
            f"#define CP_VR_TIME {n_variables}",
            f"#define CP_NARRAY {len(arrays)}",
            *(
                dimension
                if arrays
                else ["/* No arrays: every variable a scalar, no structural parameter. */"]
            ),
            f"static const unsigned char cp_array_hidden[{n_variables}] = {{"
            + ", ".join("1" if k in hidden else "0" for k in range(n_variables))
            + "};",
            "#endif",
            "",
        ]
    )


def _description(variable: Fmi3Variable) -> str:
    first = variable.members[0]["description"]
    if not variable.array:
        return first
    return re.sub(r"\b0\b", "k", first) + " (element [k + 1]: link k)"


def _start(variable: dict) -> str:
    return repr(float(variable["start"])) if variable["type"] == "Real" else str(variable["start"])


def model_description(
    data: dict, token: str, log_categories: dict[str, str], name: str, step_size: float
) -> bytes:
    """modelDescription.xml (FMI 3.0) for both interfaces of the model `name` (its
    modelIdentifier; step_size the default experiment's), from the variables' description
    (builder.variables, in model.json): the same variables and value references as its FMI 2.0
    native FMU; no clocks, no events, no event mode; the structural parameter n_links only where
    there are arrays (arrays_header)."""
    root = ET.Element(
        "fmiModelDescription",
        {
            "fmiVersion": "3.0",
            "modelName": name,
            "instantiationToken": token,
            "description": data["description"],
            "author": "conical-pendulum-fmu",
            "generationTool": "conical_pendulum.builder.fmi3",
            "generationDateAndTime": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "variableNamingConvention": "structured",
        },
    )
    common = {
        "modelIdentifier": name,
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
            "maxOutputDerivativeOrder": "0",
            "providesIntermediateUpdate": "false",
            "mightReturnEarlyFromDoStep": "true",
            "canReturnEarlyAfterIntermediateUpdate": "false",
            "hasEventMode": "false",
        },
    )
    categories = ET.SubElement(root, "LogCategories")
    for category, text in log_categories.items():
        ET.SubElement(categories, "Category", name=category, description=text)
    ET.SubElement(root, "DefaultExperiment", startTime="0.0", stopTime="10.0", stepSize=repr(step_size))
    variables = ET.SubElement(root, "ModelVariables")
    variables_ = layout(data)
    vr = {m["name"]: str(v.value_reference) for v in variables_ for m in v.members}  # an element: its array's
    n_variables = len(data["variables"])
    ET.SubElement(  # FMI 3.0 names the independent variable (fmi3_arrays.h's CP_VR_TIME)
        variables,
        "Float64",
        name="time",
        valueReference=str(n_variables),
        description="simulation time",
        causality="independent",
        variability="continuous",
    )
    if any(variable.array for variable in variables_):
        ET.SubElement(  # the arrays' dimension (fmi3_arrays.h's CP_VR_DIMENSION)
            variables,
            "UInt64",
            name=N_LINKS,
            valueReference=str(n_variables + 1),
            description="number of links: the size of every per-link array",
            causality="structuralParameter",
            variability="fixed",
            start=str(n_links(data)),
        )
    for variable in variables_:
        v = variable.members[0]
        attributes = {
            "name": variable.name,
            "valueReference": str(variable.value_reference),
            "description": _description(variable),
            "causality": v["causality"],
            "variability": v["variability"],
        }
        if v["initial"]:
            attributes["initial"] = v["initial"]
        if v["start"] is not None:
            attributes["start"] = " ".join(_start(m) for m in variable.members)
        if v["derivative_of"]:
            attributes["derivative"] = vr[v["derivative_of"]]
        element = ET.SubElement(variables, TYPES[v["type"]], attributes)
        if variable.array:
            ET.SubElement(element, "Dimension", valueReference=str(n_variables + 1))

    structure = ET.SubElement(root, "ModelStructure")

    def unknown(tag: str, variable: Fmi3Variable, dependencies: bool = True) -> None:
        attributes = {"valueReference": str(variable.value_reference)}
        if dependencies:
            names = [name for m in variable.members for name in m["depends_on"]]
            attributes["dependencies"] = " ".join(dict.fromkeys(vr[name] for name in names))
        ET.SubElement(structure, tag, attributes)

    # FMI 3.0's order: Output, ContinuousStateDerivative, InitialUnknown, each by value reference
    for variable in variables_:
        if variable.members[0]["causality"] == "output":
            unknown("Output", variable)
    for variable in variables_:
        if variable.members[0]["derivative_of"]:
            unknown("ContinuousStateDerivative", variable)
    for variable in variables_:  # no dependencies listed: they may depend on every known
        v = variable.members[0]
        if v["initial"] in ("approx", "calculated") and (v["causality"] == "output" or v["derivative_of"]):
            unknown("InitialUnknown", variable, dependencies=False)
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


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


def fmu_data(path) -> dict | None:
    """model.json of an FMI 3.0 FMU of this package (a .fmu or its unzipped folder), or None for
    any other FMU."""
    import json
    import zipfile
    from pathlib import Path

    from ..runtime.files import MODEL_FILE

    path = Path(path)
    names = ("modelDescription.xml", f"resources/{MODEL_FILE}")
    try:
        if path.is_dir():
            description, model = ((path / name).read_bytes() for name in names)
        else:
            with zipfile.ZipFile(path) as archive:
                description, model = (archive.read(name) for name in names)
    except (KeyError, OSError, zipfile.BadZipFile):
        return None
    if ET.fromstring(description).get("fmiVersion") != "3.0":
        return None
    return json.loads(model)


def array_start_values(data: dict, values: dict) -> dict:
    """Start values by the FMI 2.0 FMU's names (alpha0, l1, ...) -> the FMI 3.0 FMU's: an array
    whole, its other elements at their start values."""
    elements, records = element_names(data), {v["name"]: v for v in data["variables"]}
    members = {v.name: [m["name"] for m in v.members] for v in layout(data) if v.array}
    starts = {}
    for name, value in values.items():
        if name in elements:
            array, k = elements[name]
            starts.setdefault(array, [records[m]["start"] for m in members[array]])[k] = value
        else:
            starts[name] = value
    return starts


def scalar_columns(data: dict, result):
    """An fmpy result of the FMI 3.0 FMU with each array column (shape (n,)) split into the FMI
    2.0 FMU's scalar columns (alpha -> alpha0, alpha1, ...), so what reads the FMI 2.0 FMU's
    results reads it."""
    import numpy as np

    members = {v.name: [m["name"] for m in v.members] for v in layout(data) if v.array}
    columns = []
    for name in result.dtype.names:
        if name in members and result[name].ndim == 2:
            columns += [(member, result[name][:, k]) for k, member in enumerate(members[name])]
        else:
            columns.append((name, result[name]))
    flat = np.empty(len(result), dtype=[(name, "f8") for name, _ in columns])
    for name, values in columns:
        flat[name] = values
    return flat
