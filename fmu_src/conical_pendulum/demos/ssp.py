"""The coupled demo as an SSP 1.0 package (System Structure and Parameterization), for system tools.

One .ssp (a zip) holds what demos/coupled.py wires in Python: the two FMUs, their
connectors with units, the connections of each scheme, the cart's parameters and the
default experiment:

    SystemStructure.ssd           the explicit scheme (the default variant)
    ApparentMass.ssd              the apparent-mass scheme (a variant SSD)
    resources/ConicalPendulum.fmu the native pendulum with coupling (instance "p")
    resources/Cart.fmu            the cart (instance "cart")
    resources/explicit.ssv        the cart's parameters for each scheme: m_cart, k_cart,
    resources/apparent-mass.ssv   c_cart, F_x_order; bound to the cart by its variant

Each variant binds one parameter set (so SSP's rule, every binding applies, and the OSP
tools' reading, each binding a named set, agree). The step is written twice, once per
tool family that reads it from the package: the default experiment's annotation
`com.opensimulationplatform` (osp:FixedStepAlgorithm baseStepSize), which libcosim reads,
and the system's annotation `org.openmodelica` (oms:SimulationInformation/oms:FixedStepMaster
stepSize), from which OMSimulator takes its master algorithm and step; ecos takes its
step from its caller, FMPy from its arguments. Each SSD's name is an identifier
(`PendulumOnCart_explicit`): OMSimulator names its model after it and refuses any other.
The connectors' units are those the FMUs declare (their modelDescription.xml's units and
UnitDefinitions: builder.fmi.units), written as SSP 1.0's ssc:Units.

The XML uses the prefixes ssd:, ssc:, ssv:, osp: and oms: throughout: ecos (pugixml),
libcosim (boost property_tree) and OMSimulator (pugixml) match element names with their
prefixes, not namespaces.
"""

from __future__ import annotations

import functools
import shutil
import zipfile
from dataclasses import dataclass
from pathlib import Path

from lxml import etree

from ..builder.fmi.units import BASE_UNITS
from ..errors import UserError
from .coupled import EXCHANGED, SCHEMES, STOP_TIME
from .monolithic import cart_parameters

NS = {
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
    "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations",
    "oms": "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd",
}
VARIANTS = {"explicit": "SystemStructure.ssd", "apparent-mass": "ApparentMass.ssd"}  # scheme -> SSD
FMUS = {"p": "resources/ConicalPendulum.fmu", "cart": "resources/Cart.fmu"}  # instance -> file
SYSTEM = "PendulumOnCart"
STEP = 0.01  # [s] the default experiment's communication step
# OMSimulator's master: fixed steps, algebraic loops between FMUs solved at every step (KINSOL);
# the tolerance of those loops, which its command line replaces with its --tolerance (1e-4 too)
OMS_MASTER = {"description": "oms-ma", "relativeTolerance": "0.0001"}


def parameter_file(scheme: str) -> str:
    return f"resources/{scheme}.ssv"


def _q(prefix: str, tag: str) -> str:
    return f"{{{NS[prefix]}}}{tag}"


def _element(parent, prefix: str, tag: str, **attributes):
    return etree.SubElement(parent, _q(prefix, tag), {k: str(v) for k, v in attributes.items()})


def connectors(scheme: str) -> dict[str, list[str]]:
    """{instance: connector names}: the variables the scheme connects, and the outputs the
    demo records. No input is left unconnected: FMPy's simulate_ssp would connect it to
    the previous input's source (its get_connections keeps that loop's last match)."""
    names = [end for pair in SCHEMES[scheme][0] for end in pair] + EXCHANGED
    wanted: dict[str, list[str]] = {instance: [] for instance in FMUS}
    for name in dict.fromkeys(names):
        instance, variable = name.split("::")
        wanted[instance].append(variable)
    return wanted


@dataclass(frozen=True)
class Declared:
    """A variable as its FMU's model description declares it."""

    causality: str
    type: str  # Real, Integer, or Enumeration
    unit: str | None  # a name of the FMU's UnitDefinitions


def _declared(fmu: Path) -> tuple[dict[str, Declared], dict[str, dict[str, str]]]:
    """The FMU's variables by name, and its units (name -> BaseUnit's attributes), as its
    modelDescription.xml declares them: what an SSP connector says of one."""
    from fmpy import read_model_description

    md = read_model_description(str(fmu))
    units = {}
    for unit in md.unitDefinitions:
        base = unit.baseUnit
        exponents = {name: str(getattr(base, name)) for name in BASE_UNITS if getattr(base, name)}
        scale = {"factor": repr(base.factor)} if base.factor != 1 else {}
        shift = {"offset": repr(base.offset)} if base.offset != 0 else {}
        units[unit.name] = exponents | scale | shift
    variables = {
        v.name: Declared(v.causality, v.type, v.unit or (v.declaredType.unit if v.declaredType else None))
        for v in md.modelVariables
    }
    return variables, units


def _units(root, prefix: str, used: set[str], declared: dict[str, dict[str, str]]) -> None:
    """ssc:Units: each unit the connectors or parameters use, as its FMU declares it."""
    if not used:
        return
    table = _element(root, prefix, "Units")
    for unit in sorted(used):
        _element(_element(table, "ssc", "Unit", name=unit), "ssc", "BaseUnit", **declared[unit])


def model_name(scheme: str) -> str:
    """The name of a scheme's SSD, an identifier: OMSimulator's model (and variant) name."""
    return f"{SYSTEM}_{scheme.replace('-', '_')}"


def _ssd(scheme: str, variables: dict, units: dict, step: float, stop_time: float) -> bytes:
    root = etree.Element(
        _q("ssd", "SystemStructureDescription"),
        {"version": "1.0", "name": model_name(scheme), "generationTool": "conical-pendulum-fmu"},
        nsmap={prefix: NS[prefix] for prefix in ("ssd", "ssc", "osp", "oms")},
    )
    connections, _ = SCHEMES[scheme]
    system = _element(
        root,
        "ssd",
        "System",
        name=SYSTEM,
        description=f"the three-link pendulum hanging from a cart on a spring; the {scheme} exchange",
    )
    elements = _element(system, "ssd", "Elements")
    used = set()
    for instance, names in connectors(scheme).items():
        component = _element(elements, "ssd", "Component", name=instance, source=FMUS[instance])
        table = _element(component, "ssd", "Connectors")
        for name in names:
            variable = variables[instance][name]
            connector = _element(table, "ssd", "Connector", name=name, kind=variable.causality)
            unit = variable.unit
            _element(connector, "ssc", variable.type, **({"unit": unit} if unit else {}))
            used |= {unit} - {None}
        if instance == "cart":
            bindings = _element(component, "ssd", "ParameterBindings")
            _element(bindings, "ssd", "ParameterBinding", source=parameter_file(scheme))
    table = _element(system, "ssd", "Connections")
    for start, end in connections:
        (start_element, start_connector), (end_element, end_connector) = start.split("::"), end.split("::")
        _element(
            table,
            "ssd",
            "Connection",
            startElement=start_element,
            startConnector=start_connector,
            endElement=end_element,
            endConnector=end_connector,
        )
    information = _element(
        _element(
            _element(_element(system, "ssd", "Annotations"), "ssc", "Annotation", type="org.openmodelica"),
            "oms",
            "Annotations",
        ),
        "oms",
        "SimulationInformation",
    )
    _element(information, "oms", "FixedStepMaster", **OMS_MASTER, stepSize=repr(step))
    _units(root, "ssd", used, units)
    experiment = _element(root, "ssd", "DefaultExperiment", startTime=0.0, stopTime=repr(float(stop_time)))
    annotation = _element(
        _element(experiment, "ssd", "Annotations"), "ssc", "Annotation", type="com.opensimulationplatform"
    )
    _element(_element(annotation, "osp", "Algorithm"), "osp", "FixedStepAlgorithm", baseStepSize=repr(step))
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8", pretty_print=True)


def cart_values(scheme: str, cart_mass: float) -> dict:
    """The cart's parameters in a scheme: its mass, spring and damper, and F_x_order."""
    return {**cart_parameters(m_cart=cart_mass), **SCHEMES[scheme][1]}


def _ssv(scheme: str, values: dict, variables: dict, units: dict) -> bytes:
    root = etree.Element(
        _q("ssv", "ParameterSet"),
        {"version": "1.0", "name": scheme},
        nsmap={prefix: NS[prefix] for prefix in ("ssv", "ssc")},
    )
    table = _element(root, "ssv", "Parameters")
    used = set()
    for name, value in values.items():
        variable = variables[name]
        parameter = _element(table, "ssv", "Parameter", name=name)
        if variable.type in ("Integer", "Enumeration"):
            _element(parameter, "ssv", "Integer", value=int(value))
        else:
            unit = variable.unit
            _element(parameter, "ssv", "Real", value=repr(float(value)), **({"unit": unit} if unit else {}))
            used |= {unit} - {None}
    _units(root, "ssv", used, units)
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8", pretty_print=True)


def write_package(
    output: Path,
    pendulum_fmu: Path,
    cart_fmu: Path,
    cart_mass: float = cart_parameters()["m_cart"],
    step: float = STEP,
    stop_time: float = STOP_TIME,
) -> Path:
    """The SSP package at `output` (a .ssp file) with both FMUs, every scheme's variant and
    parameter set, the cart of `cart_mass` [kg], and the default experiment (`step`, `stop_time`)."""
    (pendulum, pendulum_units), (cart, cart_units) = _declared(pendulum_fmu), _declared(cart_fmu)
    variables, units = {"p": pendulum, "cart": cart}, pendulum_units | cart_units
    clash = [
        name for name in pendulum_units.keys() & cart_units.keys() if pendulum_units[name] != cart_units[name]
    ]
    if clash:
        raise ValueError(f"the FMUs declare the units {clash} differently")
    with zipfile.ZipFile(output, "w", zipfile.ZIP_DEFLATED) as package:
        for scheme, ssd in VARIANTS.items():
            package.writestr(ssd, _ssd(scheme, variables, units, step, stop_time))
            package.writestr(
                parameter_file(scheme), _ssv(scheme, cart_values(scheme, cart_mass), cart, cart_units)
            )
        package.write(pendulum_fmu, FMUS["p"])
        package.write(cart_fmu, FMUS["cart"])
    return output


def experiment(package: Path) -> tuple[float, float]:
    """(step, stop time) of the package's default experiment, as SystemStructure.ssd says."""
    with zipfile.ZipFile(package) as archive:
        root = etree.fromstring(archive.read("SystemStructure.ssd"))
    (step,) = root.xpath("ssd:DefaultExperiment//osp:FixedStepAlgorithm/@baseStepSize", namespaces=NS)
    (stop_time,) = root.xpath("ssd:DefaultExperiment/@stopTime", namespaces=NS)
    return float(step), float(stop_time)


@functools.cache  # parsed once, not for every file of every package
def _schema(name: str) -> etree.XMLSchema:
    import fmpy

    return etree.XMLSchema(file=str(Path(fmpy.__file__).parent / "ssp" / "schema" / name))


def validate(package: Path) -> list[str]:
    """What is wrong with the package against the SSP 1.0 schemas FMPy ships (each .ssd and
    .ssv), and each source an SSD names that the package lacks; [] when nothing is."""
    schemas = {".ssd": "SystemStructureDescription.xsd", ".ssv": "SystemStructureParameterValues.xsd"}
    problems = []
    with zipfile.ZipFile(package) as archive:
        names = set(archive.namelist())
        if "SystemStructure.ssd" not in names:
            problems.append("SystemStructure.ssd: missing")
        for name in sorted(names):
            suffix = Path(name).suffix
            if suffix not in schemas:
                continue
            tree = etree.fromstring(archive.read(name))
            schema = _schema(schemas[suffix])
            if not schema.validate(tree):
                problems += [f"{name}:{e.line}: {e.message}" for e in schema.error_log]
            sources = tree.xpath("//ssd:Component/@source | //ssd:ParameterBinding/@source", namespaces=NS)
            problems += [
                f"{name}: names {source}, which the package lacks"
                for source in sources
                if source not in names
            ]
    return problems


def variant(package: Path, scheme: str, folder: Path) -> Path:
    """The package unpacked into `folder` with the scheme's SSD as SystemStructure.ssd: ecos
    and FMPy read that file only (libcosim can be given another .ssd). Returns `folder`."""
    if scheme not in VARIANTS:
        raise UserError(f"unknown scheme {scheme!r}; choose from {', '.join(VARIANTS)}")
    if folder.exists():
        shutil.rmtree(folder)
    with zipfile.ZipFile(package) as archive:
        archive.extractall(folder)
    if VARIANTS[scheme] != "SystemStructure.ssd":
        (folder / VARIANTS[scheme]).replace(folder / "SystemStructure.ssd")
    return folder
