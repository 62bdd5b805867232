"""One description of the FMU's variables (builder/fmi/variables.py): both FMUs' model
descriptions, model.json and fmu_config.h say what it says, and a new group of variables
is one entry in its list."""

import gc
import json
import re
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from conical_pendulum import Link, Scene
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.builder.compiler import build_core, load_core
from conical_pendulum.builder.fmi import fmi2
from conical_pendulum.builder.fmi import variables as described
from conical_pendulum.builder.fmi.contract import Description
from conical_pendulum.builder.fmi.fmu_config import config_header
from conical_pendulum.builder.fmu import build_fmu, checked_settings, model_data
from conical_pendulum.builder.models.pendulum import PENDULUM
from conical_pendulum.runtime.rules import STATISTICS
from conical_pendulum.scene import Scalar
from fmu_helpers import Instance

SETTINGS = checked_settings(None)
SEED, COUPLED = Scene.uniform(3), Scene.uniform(3, coupling=True)
ONE_LINK = Scene(links=(Link(has_bob=False),))
DOCS = Path(__file__).parents[1] / "docs" / "fmu.md"


@pytest.fixture(scope="module")
def fmus(built_fmu):
    """{(scene name, backend): (scene, FMU)}."""
    return {
        (name, backend): (scene, built_fmu(scene, backend=backend))
        for name, scene in (("seed", SEED), ("coupled", COUPLED), ("one link", ONE_LINK))
        for backend in ("pythonfmu", "native")
    }


def read(fmu):
    with zipfile.ZipFile(fmu) as archive:
        return (
            ET.fromstring(archive.read("modelDescription.xml")),
            json.loads(archive.read("resources/model.json")),
        )


def declared(root):
    """Each ScalarVariable as the description's records give it (start as a number)."""
    rows = []
    for var in root.iter("ScalarVariable"):
        value = var[0]
        start = value.get("start")
        rows.append(
            {
                "name": var.get("name"),
                "value_reference": int(var.get("valueReference")),
                # an enumeration (the solver) is an Integer record whose rule lists its items
                "type": "Integer" if value.tag == "Enumeration" else value.tag,
                "causality": var.get("causality"),
                "variability": var.get("variability"),
                "initial": var.get("initial"),
                "description": var.get("description"),
                "start": None if start is None else (float(start) if value.tag == "Real" else int(start)),
            }
        )
    return rows


FIELDS = ("name", "value_reference", "type", "causality", "variability", "initial", "description", "start")


@pytest.mark.parametrize("name", ["seed", "coupled", "one link"])
@pytest.mark.parametrize("backend", ["pythonfmu", "native"])
def test_both_model_descriptions_and_model_json_say_what_the_description_says(fmus, name, backend):
    scene, fmu = fmus[name, backend]
    records = described.variables(scene, SETTINGS, backend)
    root, model = read(fmu)
    assert model["variables"] == [v.to_dict() for v in records]
    assert declared(root) == [{field: getattr(v, field) for field in FIELDS} for v in records]
    assert [v.value_reference for v in records] == list(range(len(records)))
    # ModelStructure: an unknown's dependencies are those of its depends_on that are knowns of
    # the list (the pythonfmu FMU, Co-Simulation only, has no state among its outputs' knowns);
    # every entry of every list says them, none left to "depends on every known"
    index = {v.name: str(v.value_reference + 1) for v in records}
    inputs = {v.name for v in records if v.causality == "input"}
    states = {v.name for v in records if v.group == "states"} if backend == "native" else set()
    listed = {u.get("index"): u.get("dependencies") for u in root.find("ModelStructure/Outputs")}
    assert list(listed) == [index[v.name] for v in records if v.causality == "output"]
    for v in records:
        if v.causality == "output":
            names = [d for d in v.depends_on if d in inputs | states]
            assert listed[index[v.name]] == " ".join(index[d] for d in names), v.name
    assert all(u.get("dependencies") is not None for u in root.iter("Unknown"))
    derivatives = root.find("ModelStructure/Derivatives")
    assert [u.get("index") for u in (derivatives if derivatives is not None else [])] == [
        index[v.name] for v in records if v.derivative_of
    ]
    # every FMU: parameters, inputs, states, outputs, statistics, settings, (native) der()
    order = [group.name for group in described.groups(backend)]
    assert [v.group for v in records] == sorted((v.group for v in records), key=order.index)


def test_both_backends_give_each_variable_the_same_value_reference():
    for scene in (SEED, COUPLED, ONE_LINK):
        python, native = (
            described.variables(scene, SETTINGS, backend) for backend in ("pythonfmu", "native")
        )
        # the same, every solver included (all in the compiled core), then the derivatives
        assert native[: len(python)] == python
        assert {v.group for v in native[len(python) :]} == {"derivatives"}


def test_the_statistics_slots_of_the_c_are_the_variables_order():
    core = load_core(SEED)  # model.h's CP_STAT_*, which cosim.c fills
    statistics = [v.name for v in described.variables(SEED, SETTINGS) if v.group == "statistics"]
    assert statistics == list(STATISTICS)
    assert {name: k for k, name in enumerate(statistics)} == core.STATISTICS_SLOTS


def test_fmu_config_h_takes_its_value_references_from_the_description():
    data = model_data(COUPLED, build_core(COUPLED), SETTINGS, "native")
    header = config_header(PENDULUM, data, described.records(data), "{guid}")
    records = data["variables"]
    first, seen = {}, 0  # a group's first reference; an empty group's, where the next starts
    for group in described.groups("native"):
        members = [v["value_reference"] for v in records if v["group"] == group.name]
        first[group.name] = members[0] if members else seen
        seen = members[-1] + 1 if members else seen
    for group in described.groups("native"):
        assert f"#define CP_VR_{group.c_name} {first[group.name]}\n" in header
    assert f"#define CP_NREAL {first['integer_settings']}\n" in header
    names = re.search(r"cp_names\[CP_NVARIABLE\] = \{\n(.*?)\n\};", header, re.DOTALL).group(1)
    assert [json.loads(line.strip().rstrip(",")) for line in names.splitlines()] == [
        v["name"] for v in records
    ]


def seed_layout(backend):
    """'parameters 0-18, ...': each group's value references in the seed's FMU."""
    spans = {}
    for v in described.variables(SEED, SETTINGS, backend):
        spans.setdefault(v.group.replace("_", " "), []).append(v.value_reference)
    return ", ".join(f"{group} {refs[0]}-{refs[-1]}" for group, refs in spans.items())


def test_docs_show_the_order_the_description_gives():
    text = DOCS.read_text()
    assert seed_layout("native") in " ".join(text.split())
    section = text.split("## Variables")[1].split("\n## ")[0]
    rows = [line for line in section.splitlines() if line.startswith("| `")]
    first_names = [re.match(r"\| `([^`]+?)(?:\.\.|`|,| )", row).group(1) for row in rows]
    references = {v.name: v.value_reference for v in described.variables(COUPLED, SETTINGS, "native")}
    listed = [references[name] for name in first_names]
    assert listed == sorted(listed), list(zip(first_names, listed))


# --- adding a group of variables: one entry in builder.fmi.variables.GROUPS --------------

EXTRA = described.Group(
    "extra",
    "Real",
    "output",
    "discrete",
    "calculated",
    "EXTRA",
    lambda scene, settings: [
        described.Member(Scalar("n_extra"), None, "an extra count"),
        described.Member(Scalar("n_more"), None, "another one"),
    ],
)
EXTRA_PARAMETER = described.Group(
    "extra_parameter",
    "Real",
    "parameter",
    "fixed",
    None,
    "EXTRA_PARAMETER",
    lambda scene, settings: [described.Member(Scalar("k_extra"), 2.5, "a number")],
)

PLAIN = {v.name: v.value_reference for v in described.variables(SEED, SETTINGS, "native")}


@pytest.fixture
def extra_groups(monkeypatch):
    """GROUPS with a group of two outputs after the statistics and one of a parameter after
    the real settings, and nothing else changed."""
    groups = list(described.GROUPS)
    groups.insert([g.name for g in groups].index("statistics") + 1, EXTRA)
    groups.insert([g.name for g in groups].index("real_settings") + 1, EXTRA_PARAMETER)
    monkeypatch.setattr(described, "GROUPS", groups)


def test_a_new_group_is_one_entry_in_the_list(extra_groups, tmp_path):
    first, later = PLAIN["rtol"], PLAIN["solver"]  # where the new groups go; the rest moves on
    records = {v["name"]: v for v in model_data(SEED, build_core(SEED), SETTINGS, "native")["variables"]}
    new = ("n_extra", "n_more", "k_extra")
    assert [records[name]["value_reference"] for name in new] == [first, first + 1, later + 2]
    assert {name: v["value_reference"] for name, v in records.items() if name not in new} == {
        name: vr + (vr >= first) * 2 + (vr >= later) for name, vr in PLAIN.items()
    }
    data = {"variables": list(records.values()), "settings": SETTINGS, "description": "extra"}
    # fmu_config.h: its value references, the names and how each may be set
    header = config_header(PENDULUM, data, described.records(data), "{guid}")
    for line in (
        f"CP_VR_EXTRA {first}",
        f"CP_VR_SETTINGS {first + 2}",
        f"CP_VR_EXTRA_PARAMETER {later + 2}",
        f"CP_NREAL {later + 3}",
        f"CP_VR_SOLVER {later + 3}",
    ):
        assert f"#define {line}\n" in header
    settable = re.search(r"cp_settable\[CP_NVARIABLE\] = \{(.*)\};", header).group(1).split(", ")
    assert settable[first] == "CP_SET_NEVER" and settable[later + 2] == "CP_SET_BEFORE_INIT"
    # the native model description
    root = ET.fromstring(
        fmi2.model_description(Description(PENDULUM, data, described.records(data), "{guid}", []))
    )
    rows = {row["name"]: row for row in declared(root)}
    assert rows["n_extra"] == {
        "name": "n_extra",
        "value_reference": first,
        "type": "Real",
        "causality": "output",
        "variability": "discrete",
        "initial": "calculated",
        "description": "an extra count",
        "start": None,
    }
    assert rows["k_extra"] == {
        "name": "k_extra",
        "value_reference": later + 2,
        "type": "Real",
        "causality": "parameter",
        "variability": "fixed",
        "initial": None,
        "description": "a number",
        "start": 2.5,
    }
    assert str(first + 1) in {u.get("index") for u in root.find("ModelStructure/Outputs")}
    # both FMUs build with them and run: the slave and the glue read the new layout
    for backend in ("pythonfmu", "native"):
        fmu = build_fmu(SEED, tmp_path / f"{backend}.fmu", backend=backend).path
        root, model = read(fmu)
        rows = {row["name"]: row for row in declared(root)}
        assert [v["name"] for v in model["variables"]] == list(rows) == list(records)[: len(rows)]
        assert rows["n_extra"]["value_reference"] == first
        assert rows["max_steps"]["value_reference"] == PLAIN["max_steps"] + 3
        run = run_fmu(
            fmu, stop_time=0.1, output_interval=0.05, start_values={"max_steps": 1000, "k_extra": 3.0}
        )
        assert np.all(run["n_extra"] == 0) and run["n_rhs"][-1] > 0 and np.isfinite(run["energy"]).all()
        # a calculated output is never set; a parameter is, before initialization only
        for name, initialize, message in (
            ("n_extra", False, "n_extra is a calculated output"),
            ("k_extra", True, "k_extra cannot be set after initialization"),
        ):
            instance = Instance(fmu, start_values={"k_extra": 3.0}, initialize=initialize)
            assert not initialize or instance.get("k_extra") == [3.0]
            with pytest.raises(FMICallException):
                instance.set({name: 1.0})
            assert any(text.startswith(message) for _, text in instance.messages), instance.messages
            instance.close(after_fatal=True)
            gc.collect()  # pythonfmu releases a failed instance twice: the slave makes up for it
