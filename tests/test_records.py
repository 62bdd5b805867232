"""The variables' records carry their structure (builder.fmi.variables): quantity, link, unit,
FMI 3.0 array and rule are fields made once, and what is written from them (names,
descriptions, arrays, units, C literals) agrees with them. No FMU is built here."""

import math
import re

import pytest

from conical_pendulum import Link, Scene
from conical_pendulum.builder import c_literals as c
from conical_pendulum.builder.fmi.variables import Variable, describe, model_structure, records, variables
from conical_pendulum.builder.fmu import checked_settings
from conical_pendulum.builder.models import cart
from conical_pendulum.runtime.rules import BadValue, check_rule, rule_of

SETTINGS = checked_settings(None)
MIXED = Scene(links=(Link(), Link(has_bob=False), Link(has_mass=False)), coupling=True)
SCENES = [Scene.uniform(3), Scene.uniform(1), MIXED]


@pytest.mark.parametrize("scene", SCENES, ids=["seed", "one link", "mixed"])
def test_names_are_made_from_quantity_and_link(scene):
    for v in variables(scene, SETTINGS, "native"):
        if v.link is None:
            assert v.name == v.quantity or v.group in ("statistics", "real_settings", "integer_settings")
        else:  # the link's number stands where the quantity's stem ends: bob2_x, der(alpha1)
            assert re.sub(str(v.link), "", v.name, count=1) == v.quantity, v
        assert (v.rule, v.what) == rule_of(v.quantity)


@pytest.mark.parametrize("scene", SCENES, ids=["seed", "one link", "mixed"])
def test_an_array_is_one_quantity_of_every_link(scene):
    found = {}
    for v in variables(scene, SETTINGS, "native"):
        if v.array is not None:
            assert (v.array, v.index, v.type) == (v.quantity, v.link, "Real")
            found.setdefault(v.array, []).append(v.index)
    assert all(indices == list(range(scene.n)) for indices in found.values())
    # a quantity some link lacks stays scalars: the mixed scene's second link has no bob
    if scene is MIXED:
        assert "bob_x" not in found and "m" not in found and "M" not in found and "alpha" in found


def test_units_are_the_ones_the_descriptions_write():
    described = [*variables(MIXED, SETTINGS, "native"), *records(cart.cart_data())]
    for v in described:
        if v.unit not in (None, "1"):  # a dimensionless number's description writes no unit
            assert f"[{v.unit}]" in v.description or v.derivative_of, v
        elif v.type == "Real":
            assert "[" not in v.description or v.name in ("rtol", "atol"), v
    units = {v.name: v.unit for v in described}
    assert (units["l0"], units["omega1"], units["der(omega1)"], units["Ixx0"]) == (
        "m",
        "rad/s",
        "rad/s2",
        "kg.m2",
    )
    assert (units["F_pivot_x"], units["a_pivot_y"], units["g"], units["energy"]) == ("N", "m/s2", "m/s2", "J")
    assert (units["k_cart"], units["c_cart"], units["der(v)"], units["link0_qw"]) == (
        "N/m",
        "N.s/m",
        "m/s2",
        "1",
    )


def test_an_arrays_description_is_made_for_every_link():
    assert describe("bob_x", every_link=True) == "bob k position relative to the pivot, inertial x (Y up) [m]"
    assert (
        describe("omega", 2) == "alpha2' [rad/s]" and describe("omega", every_link=True) == "alpha' [rad/s]"
    )
    assert describe("der(beta)", 0) == "time derivative of beta0"


def test_the_records_go_through_model_json_and_back():
    described = variables(MIXED, SETTINGS, "native")
    assert records({"variables": [v.to_dict() for v in described]}) == described
    assert all(isinstance(v, Variable) for v in described)


def test_a_value_is_checked_by_its_records_rule_not_its_name():
    length = next(v for v in variables(Scene.uniform(2), SETTINGS) if v.name == "l1")
    with pytest.raises(BadValue, match=r"^l1 = -1.0: a length must be positive$"):
        check_rule(length.name, -1.0, length.rule, length.what)
    assert rule_of("l1") == ("finite", "")  # a name is no quantity: nothing stripped off it


def test_model_structure_lists_outputs_derivatives_and_initial_unknowns():
    structure = model_structure(variables(Scene.uniform(2), SETTINGS, "native"))
    outputs = [u.variable for u in structure.outputs]
    assert outputs[0].name == "alpha0" and all(v.causality == "output" for v in outputs)
    assert [u.variable.derivative_of for u in structure.derivatives][:2] == ["alpha0", "alpha1"]
    assert {u.variable.initial for u in structure.initial_unknowns} == {"calculated"}
    # every entry names its knowns: an output the states (Model Exchange's knowns), at
    # initialization the parameters too; an angle's derivative its rate, whatever the list
    names = {u.variable.name: [k.name for k in u.dependencies] for u in structure.initial_unknowns}
    assert names["der(alpha1)"] == ["omega1"]
    assert names["bob0_y"] == ["l0", "alpha0", "beta0"] and names["bob0_x"] == ["l0", "alpha0"]
    assert {u.variable.name: [k.name for k in u.dependencies] for u in structure.outputs}["bob0_y"] == [
        "alpha0",
        "beta0",
    ]
    assert names["n_rhs"] == []  # a count of the solver's work: no function of the knowns


def test_c_literals():
    assert c.double(0.1) == "0.1" and float(c.double(1 / 3)) == 1 / 3
    assert (c.double(math.inf), c.double(-math.inf)) == ("INFINITY", "-INFINITY")
    with pytest.raises(ValueError, match="NaN"):
        c.double(math.nan)
    assert c.string('a "b"\\ c') == r'"a \"b\"\\ c"' and c.string("µ") == r'"\u00b5"'
    assert c.define("CP_X", 3) == "#define CP_X 3" and c.initializer([1, 2]) == "{1, 2}"
    assert c.rows(["{0}", "{1}"], ["a", "b"]) == "    {0},  /* a */\n    {1},  /* b */"
    with pytest.raises(KeyError):  # every hole filled, or no header
        c.fill("model.h.in", sizes="")
