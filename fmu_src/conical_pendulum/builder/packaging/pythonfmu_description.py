"""The pythonfmu FMU's model description: what pythonfmu leaves out or gets wrong; the scene's one-line text."""

from __future__ import annotations

import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

from ...scene import Scene
from ..fmi.fmi2 import experiment_tolerance, type_definitions, typed, write_structure
from ..fmi.units import unit_definitions
from ..fmi.variables import Variable, model_structure


def complete(fmu: Path, described: list[Variable], library: Path) -> None:
    """Complete ModelStructure as FMI 2.0 requires; exact start values; the units, ranges and
    the solver's enumeration builder.fmi.fmi2 writes (pythonfmu 0.7 has no Enumeration variable:
    its slave registers solver an Integer, which a host sets with fmi2SetInteger as it sets
    an enumeration, so only the description changes); this platform only,
    its binary `library` (pythonfmu's export library as built here, builder.packaging.pythonfmu_export);
    text compressed, binaries stored (fmpy extracts the FMU at every simulate_fmu).

    `described`: the FMU's variables' records (builder.fmi.variables, in value-reference order);
    pythonfmu's variables must be exactly those (name, value reference, type, causality,
    variability, initial), and the starts and the ModelStructure (builder.fmi.variables.
    model_structure; each output's dependencies on the inputs, its direct feedthrough, so a
    master knows where an algebraic loop can be) are theirs.

    pythonfmu writes no units and lists no InitialUnknowns, writes Real starts with 16 digits (a double
    needs 17 to round-trip), and packs binaries for every platform it has, while the
    compiled core runs only on the platform that built it.
    """
    from pythonfmu.osutil import get_platform

    platform = f"binaries/{get_platform()}/"
    with zipfile.ZipFile(fmu) as archive:
        entries = {
            info.filename: archive.read(info)
            for info in archive.infolist()
            if not info.filename.startswith("binaries/") or info.filename.startswith(platform)
        }
    binaries = [name for name in entries if name.startswith(platform)]
    if len(binaries) != 1:
        raise RuntimeError(f"pythonfmu packed {binaries or 'no binary'} for {platform}, not one library")
    entries[binaries[0]] = library.read_bytes()
    root = ET.fromstring(entries["modelDescription.xml"])
    variables = root.find("ModelVariables").findall("ScalarVariable")
    _check_described(variables, described)
    for var, v in zip(variables, described):  # builder.fmi.fmi2's type element, pythonfmu's start exact
        (written,) = list(var)
        value = {"start": v.start_text()} if written.get("start") is not None else {}
        var.remove(written)
        ET.SubElement(var, *typed(v, value))
    root.find("DefaultExperiment").attrib.update(experiment_tolerance(described))  # as the native FMUs'
    where = [child.tag for child in root].index("CoSimulation") + 1  # FMI 2.0's order of elements
    definitions = ET.Element("definitions")
    unit_definitions(definitions, described)
    type_definitions(definitions, described)
    for offset, element in enumerate(definitions):
        root.insert(where + offset, element)
    element = root.find("ModelStructure")
    for child in list(element):
        element.remove(child)
    index = {v.name: str(v.value_reference + 1) for v in described}  # its place in ModelVariables
    write_structure(element, model_structure(described), index)  # Co-Simulation: no state a known
    ET.indent(root)
    entries["modelDescription.xml"] = ET.tostring(root, encoding="UTF-8", xml_declaration=True)
    with zipfile.ZipFile(fmu, "w") as archive:
        for name, data in entries.items():  # binaries stored: every run extracts them
            stored = name.endswith((".so", ".dll", ".dylib"))
            archive.writestr(name, data, zipfile.ZIP_STORED if stored else zipfile.ZIP_DEFLATED)


def _check_described(variables, described: list[Variable]) -> None:
    """pythonfmu wrote the variables the description gives, in its order (else ValueError)."""

    def attributes(var):
        kind = next(child.tag for child in var)
        return (
            var.get("name"),
            int(var.get("valueReference")),
            kind,
            var.get("causality"),
            var.get("variability"),
            var.get("initial"),
        )

    written = [attributes(var) for var in variables]
    wanted = [(v.name, v.value_reference, v.type, v.causality, v.variability, v.initial) for v in described]
    if written != wanted:
        padded = max(len(written), len(wanted))
        wrong = next((w, d) for w, d in zip(written + [None] * padded, wanted + [None] * padded) if w != d)
        raise ValueError(
            f"pythonfmu's model description disagrees with the variables' "
            f"description: {wrong[0]} where {wrong[1]} was described"
        )


def model_description_text(scene: Scene) -> str:
    """The FMU's one-line description of its scene."""
    links = ", ".join(
        ("cylinder" if link.has_mass else "massless") + ("+bob" if link.has_bob else "")
        for link in scene.links
    )
    kinematics = (
        ""
        if scene.kinematics == "consistent"
        else "; PUBLISHED pydy-example kinematics (does not conserve energy)"
    )
    coupling = (
        "; hangs from a moving support: inputs a_pivot_x/y/z (held over each "
        "communication step, or interpolated from their derivatives), outputs F_pivot_x/y/z = F_free_x/y/z - M_app a_pivot "
        "with the apparent mass M_pivot_xx..zz"
        if scene.coupling
        else ""
    )
    return f"{scene.n}-link conical pendulum ({links}){kinematics}{coupling}"
