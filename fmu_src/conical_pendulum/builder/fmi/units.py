"""The units the FMUs declare, each once: its SI base-unit exponents, the physical quantity of
the variables that carry it, and the unit a tool shows it in (build time: the model
description writers, builder.fmi.fmi2, builder.fmi.fmi3 and
builder.packaging.pythonfmu_description, and the SSP package's connectors read them from the
FMUs they describe).

A variable's record (builder.fmi.variables.Variable) names its unit; everything else written about
the unit comes from here. The names are Modelica's unit syntax ("kg.m2", "N.s/m"), which the
Modelica tools that import FMUs parse; FMI itself reads only the exponents.

FMI 2.0 and 3.0 define a display unit alike: value_display = factor * value_unit + offset
(fmi2Unit.xsd's DisplayUnit; FMI 3.0 section 2.4.3), so degrees are factor 180/pi on radians;
and a unit's base unit: value_SI = factor * value_unit + offset, here always 1 and 0.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

from ...runtime.rules import RULES

BASE_UNITS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")  # FMI's BaseUnit attributes
DEGREES = 180.0 / math.pi  # value_deg = DEGREES * value_rad
TIME = "s"  # the unit of FMI 3.0's independent variable, time


@dataclass(frozen=True)
class DisplayUnit:
    name: str
    factor: float  # value_display = factor * value_unit + offset
    offset: float = 0.0


@dataclass(frozen=True)
class Unit:
    name: str
    base: dict[str, int] = field(default_factory=dict)  # SI exponents; none: dimensionless
    quantity: str | None = None  # FMI's quantity of the variables in this unit
    display: DisplayUnit | None = None  # what a tool shows by default (displayUnit)

    def base_attributes(self) -> dict[str, str]:
        """<BaseUnit>'s attributes (FMI 2.0, 3.0 and SSP 1.0's ssc:BaseUnit alike)."""
        return {name: str(self.base[name]) for name in BASE_UNITS if self.base.get(name)}


UNITS = {
    unit.name: unit
    for unit in (
        Unit("1"),  # dimensionless: a quaternion's components, a count, a relative tolerance
        Unit("s", {"s": 1}, "Time"),
        Unit("m", {"m": 1}, "Length"),
        Unit("m2", {"m": 2}, "Area"),
        Unit("m/s", {"m": 1, "s": -1}, "Velocity"),
        Unit("m/s2", {"m": 1, "s": -2}, "Acceleration"),
        Unit("kg", {"kg": 1}, "Mass"),
        Unit("kg/m3", {"kg": 1, "m": -3}, "Density"),
        Unit("kg.m2", {"kg": 1, "m": 2}, "MomentOfInertia"),
        Unit("N", {"kg": 1, "m": 1, "s": -2}, "Force"),
        Unit("J", {"kg": 1, "m": 2, "s": -2}, "Energy"),
        Unit("J/s", {"kg": 1, "m": 2, "s": -3}, "Power"),  # the energy's books' rates
        Unit("W", {"kg": 1, "m": 2, "s": -3}, "Power"),  # a power put in: a winch's
        Unit("N/m", {"kg": 1, "s": -2}, "TranslationalSpringConstant"),
        Unit("N.s/m", {"kg": 1, "s": -1}, "TranslationalDampingConstant"),
        Unit("N.m.s/rad", {"kg": 1, "m": 2, "s": -1, "rad": -1}, "RotationalDampingConstant"),
        Unit("rad", {"rad": 1}, "Angle", DisplayUnit("deg", DEGREES)),
        Unit("rad/s", {"rad": 1, "s": -1}, "AngularVelocity", DisplayUnit("deg/s", DEGREES)),
        Unit("rad/s2", {"rad": 1, "s": -2}, "AngularAcceleration", DisplayUnit("deg/s2", DEGREES)),
    )
}


def declared(name: str) -> Unit:
    """The declared unit `name` (a record's), or ValueError naming what is declared."""
    try:
        return UNITS[name]
    except KeyError:
        raise ValueError(f"unit {name!r} is not declared in builder.fmi.units: {', '.join(UNITS)}") from None


def used(records, also: tuple[str, ...] = ()) -> list[Unit]:
    """The units the records carry (and `also`), in UNITS's order: a model description's
    UnitDefinitions."""
    names = {v.unit for v in records if v.unit} | set(also)
    for name in names:
        declared(name)
    return [unit for name, unit in UNITS.items() if name in names]


def unit_definitions(parent: ET.Element, records, also: tuple[str, ...] = ()) -> None:
    """<UnitDefinitions> of the units the records carry and `also` (FMI 2.0 and 3.0 write them
    alike)."""
    units = used(records, also)
    if not units:
        return
    table = ET.SubElement(parent, "UnitDefinitions")
    for unit in units:
        element = ET.SubElement(table, "Unit", name=unit.name)
        ET.SubElement(element, "BaseUnit", unit.base_attributes())
        if unit.display:
            shown = unit.display
            ET.SubElement(
                element, "DisplayUnit", name=shown.name, factor=repr(shown.factor), offset=repr(shown.offset)
            )


def attributes(v) -> dict[str, str]:
    """What a model description says of a variable's values (a record's, builder.fmi.variables):
    its quantity, unit and display unit (a Real's), min and max (its rule's: Variable.bounds),
    nominal (a state's); an enumeration's are its type's."""
    found = {}
    if v.unit:
        unit = declared(v.unit)
        found |= {"quantity": unit.quantity} if unit.quantity else {}
        found["unit"] = unit.name
        found |= {"displayUnit": unit.display.name} if unit.display else {}
    found |= v.bounds()
    if v.nominal is not None:
        found["nominal"] = repr(float(v.nominal))
    return found


def enumerations(records) -> dict[str, tuple[tuple[str, str], ...]]:
    """The enumeration types the records use: type name -> items as (name, description), an
    item valued by its place."""
    return {RULES[v.rule].type_name: RULES[v.rule].items for v in records if RULES[v.rule].items}
