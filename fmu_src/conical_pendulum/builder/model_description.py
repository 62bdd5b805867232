"""The FMU's model description: what pythonfmu leaves out or gets wrong, and the variables' descriptions."""

from __future__ import annotations

import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

from ..scene import Scene


def complete(fmu: Path, described: list[dict], library: Path) -> None:
    """Complete ModelStructure as FMI 2.0 requires; exact start values; this platform only,
    its binary `library` (pythonfmu's export library as built here, builder.pythonfmu_export);
    text compressed, binaries stored (fmpy extracts the FMU at every simulate_fmu).

    `described`: the FMU's variables as builder.variables describes them (as dicts, in
    value-reference order); pythonfmu's variables must be exactly those (name, value
    reference, type, causality, variability, initial), and the starts and each output's
    dependencies on the inputs (its direct feedthrough, so a master knows where an algebraic
    loop can be) are theirs.

    pythonfmu lists no InitialUnknowns, writes Real starts with 16 digits (a double
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
    structure = root.find("ModelStructure")
    for child in list(structure):
        structure.remove(child)
    outputs = ET.SubElement(structure, "Outputs")
    initial = ET.SubElement(structure, "InitialUnknowns")
    _check_described(variables, described)
    starts = {v["name"]: v["start"] for v in described if v["start"] is not None}
    index_of = {v["name"]: str(index) for index, v in enumerate(described, start=1)}
    inputs_of = {v["name"]: v["causality"] == "input" for v in described}
    # Co-Simulation only: an output depends on the inputs it names (the state is not a known)
    depends = {
        v["name"]: " ".join(index_of[name] for name in v["depends_on"] if inputs_of[name]) for v in described
    }
    for index, var in enumerate(variables, start=1):
        real = var.find("Real")
        if real is not None and real.get("start") is not None:
            real.set("start", repr(float(starts[var.get("name")])))
        if var.get("causality") == "output":
            direct = depends[var.get("name")]
            ET.SubElement(
                outputs,
                "Unknown",
                index=str(index),
                dependencies=direct,
                **({"dependenciesKind": " ".join(["dependent"] * len(direct.split()))} if direct else {}),
            )
            if var.get("initial") in ("calculated", "approx"):
                ET.SubElement(initial, "Unknown", index=str(index))
    if not len(initial):
        structure.remove(initial)
    ET.indent(root)
    entries["modelDescription.xml"] = ET.tostring(root, encoding="UTF-8", xml_declaration=True)
    with zipfile.ZipFile(fmu, "w") as archive:
        for name, data in entries.items():  # binaries stored: every run extracts them
            stored = name.endswith((".so", ".dll", ".dylib"))
            archive.writestr(name, data, zipfile.ZIP_STORED if stored else zipfile.ZIP_DEFLATED)


def _check_described(variables, described: list[dict]) -> None:
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
    wanted = [
        (v["name"], v["value_reference"], v["type"], v["causality"], v["variability"], v["initial"])
        for v in described
    ]
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
        "; hangs from a moving support: inputs a_pivot_x/y/z (held constant over each "
        "communication step), outputs F_pivot_x/y/z = F_free_x/y/z - M_app a_pivot "
        "with the apparent mass M_pivot_xx..zz"
        if scene.coupling
        else ""
    )
    return f"{scene.n}-link conical pendulum ({links}){kinematics}{coupling}"


_INDEXED = {
    "l": "length of link {i} [m]",
    "m": "mass of bob {i} [kg]",
    "M": "mass of link {i} [kg]",
    "Ixx": "central inertia of link {i} about its x axis [kg m2]",
    "Iyy": "central inertia of link {i} about its own (y) axis [kg m2]",
    "Izz": "central inertia of link {i} about its z axis [kg m2]",
    "alpha": "angle of joint {i} about the parent's z axis [rad]",
    "beta": "angle of joint {i} about the parent's x axis [rad]",
    "omega": "alpha{i}' [rad/s]",
    "delta": "beta{i}' [rad/s]",
}
_NAMED = {
    "g": "gravitational acceleration along -Y [m/s2]",
    "energy": "total mechanical energy relative to the pivot (kinetic + potential, zero at Y = 0) [J]",
}


def describe(name: str) -> str:
    """The description of one of the scene's variables (parameters, inputs, state, outputs),
    from its name; the solver settings and statistics describe themselves (runtime.rules)."""
    if name in _NAMED:
        return _NAMED[name]
    if name.startswith("a_pivot_"):
        return (
            f"acceleration of the pivot (the support), inertial {name[-1]} (Y up) [m/s2]; "
            "held constant over each communication step"
        )
    if name.startswith("M_pivot_"):
        return (
            f"apparent mass of the chain at the pivot, entry {name[-2:]} of the symmetric "
            "M_app in F_pivot = F_free - M_app a_pivot [kg]; depends on the state only"
        )
    if name.startswith("F_free_"):
        return (
            f"force the pendulum would exert on a support at rest (a_pivot = 0), inertial "
            f"{name[-1]} (Y up) [N]: F_pivot = F_free - M_app a_pivot; depends on the state only"
        )
    if name.startswith("F_pivot_"):
        return (
            f"force the pendulum exerts on its support, inertial {name[-1]} (Y up) [N]; "
            "depends at once on the a_pivot inputs"
        )
    if name.startswith("bob"):
        return f"bob {name[3:].split('_')[0]} position relative to the pivot, inertial {name[-1]} (Y up) [m]"
    if name.startswith("link"):
        index, part = name[4:].split("_")
        if part.startswith("q"):
            return f"link {index} orientation quaternion, {part[1]} component"
        return f"link {index} mass-centre position relative to the pivot, inertial {part} [m]"
    kind = name.rstrip("0123456789")
    return _INDEXED[kind].format(i=name[len(kind) :])
