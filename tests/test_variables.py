"""One description of the FMU's variables (builder/variables.py): both FMUs' model
descriptions, model.json and fmu_config.h say what it says, and a new group of variables
is one entry in its list."""
import json
import re
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest

from conical_pendulum import Link, Scene
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.builder import variables as described
from conical_pendulum.builder.compiler import build_core, load_core
from conical_pendulum.builder.fmu import build_fmu, checked_settings, model_data
from conical_pendulum.builder.native import config_header, model_description
from conical_pendulum.runtime.rules import STATISTICS

SETTINGS = checked_settings(None)
SEED, COUPLED = Scene.uniform(3), Scene.uniform(3, coupling=True)
ONE_LINK = Scene(links=(Link(has_bob=False),))
DOCS = Path(__file__).parents[1] / "docs" / "fmu.md"


@pytest.fixture(scope="module")
def fmus(seed_fmu, native_seed_fmu, coupled_fmu, fmu_dir):
    """{(scene name, backend): FMU}: the session's where there is one, the others built here."""
    built = {("seed", "pythonfmu"): (SEED, seed_fmu), ("seed", "native"): (SEED, native_seed_fmu),
             ("coupled", "pythonfmu"): (COUPLED, coupled_fmu)}
    for name, scene, backend in (("coupled", COUPLED, "native"), ("one link", ONE_LINK, "pythonfmu"),
                                 ("one link", ONE_LINK, "native")):
        path = fmu_dir / f"variables_{name.replace(' ', '_')}_{backend}.fmu"
        built[name, backend] = (scene, build_fmu(scene, path, backend=backend).path)
    return built


def read(fmu):
    with zipfile.ZipFile(fmu) as archive:
        return (ET.fromstring(archive.read("modelDescription.xml")),
                json.loads(archive.read("resources/model.json")))


def declared(root):
    """Each ScalarVariable as the description's records give it (start as a number)."""
    rows = []
    for var in root.iter("ScalarVariable"):
        value = var[0]
        start = value.get("start")
        rows.append({"name": var.get("name"), "value_reference": int(var.get("valueReference")),
                     "type": value.tag, "causality": var.get("causality"),
                     "variability": var.get("variability"), "initial": var.get("initial"),
                     "description": var.get("description"),
                     "start": None if start is None else (float(start) if value.tag == "Real" else int(start))})
    return rows


FIELDS = ("name", "value_reference", "type", "causality", "variability", "initial", "description",
          "start")


@pytest.mark.parametrize("name", ["seed", "coupled", "one link"])
@pytest.mark.parametrize("backend", ["pythonfmu", "native"])
def test_both_model_descriptions_and_model_json_say_what_the_description_says(fmus, name, backend):
    scene, fmu = fmus[name, backend]
    records = described.variables(scene, SETTINGS, backend)
    root, model = read(fmu)
    assert model["variables"] == [v.to_dict() for v in records]
    assert declared(root) == [{field: getattr(v, field) for field in FIELDS} for v in records]
    assert [v.value_reference for v in records] == list(range(len(records)))
    # ModelStructure: an unknown's dependencies are its depends_on (the pythonfmu FMU,
    # Co-Simulation only, lists the inputs among them: the state is no known there)
    index = {v.name: str(v.value_reference + 1) for v in records}
    inputs = {v.name for v in records if v.causality == "input"}
    listed = {u.get("index"): u.get("dependencies") for u in root.find("ModelStructure/Outputs")}
    assert list(listed) == [index[v.name] for v in records if v.causality == "output"]
    for v in records:
        if v.causality == "output":
            names = v.depends_on if backend == "native" else [d for d in v.depends_on if d in inputs]
            assert listed[index[v.name]] == " ".join(index[d] for d in names), v.name
    derivatives = root.find("ModelStructure/Derivatives")
    assert [u.get("index") for u in (derivatives if derivatives is not None else [])] == [
        index[v.name] for v in records if v.derivative_of]
    # every FMU: parameters, inputs, states, outputs, statistics, settings, (native) der()
    order = [group.name for group in described.groups(backend)]
    assert [v.group for v in records] == sorted((v.group for v in records), key=order.index)


def test_both_backends_give_each_variable_the_same_value_reference():
    for scene in (SEED, COUPLED, ONE_LINK):
        python, native = (described.variables(scene, SETTINGS, backend)
                          for backend in ("pythonfmu", "native"))
        assert native[:len(python)] == python
        assert {v.group for v in native[len(python):]} == {"derivatives"}


def test_the_statistics_slots_of_the_c_are_the_variables_order():
    core = load_core(SEED)  # model.h's CP_STAT_*, which cosim.c fills
    statistics = [v.name for v in described.variables(SEED, SETTINGS) if v.group == "statistics"]
    assert statistics == list(STATISTICS)
    assert core.STATISTICS_SLOTS == {name: k for k, name in enumerate(statistics)}


def test_fmu_config_h_takes_its_value_references_from_the_description():
    data = model_data(COUPLED, build_core(COUPLED), SETTINGS, "native")
    header = config_header(data, "{guid}")
    records = data["variables"]
    first = {v["group"]: v["value_reference"] for v in reversed(records)}
    for group in described.groups("native"):
        assert f"#define CP_VR_{group.c_name} {first[group.name]}\n" in header
    assert f"#define CP_NREAL {first['integer_settings']}\n" in header
    names = re.search(r"cp_names\[\] = \{\n(.*?)\n\};", header, re.DOTALL).group(1)
    assert [json.loads(line.strip().rstrip(",")) for line in names.splitlines()] == [
        v["name"] for v in records]


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


# --- adding a group of variables: one entry in builder.variables.GROUPS --------------

EXTRA = described.Group("extra", "Real", "output", "discrete", "calculated", "EXTRA",
                        lambda scene, settings: [described.Member("n_extra", None, "an extra count"),
                                                 described.Member("n_more", None, "another one")])


PLAIN = {v.name: v.value_reference for v in described.variables(SEED, SETTINGS, "native")}


@pytest.fixture
def extra_group(monkeypatch):
    """GROUPS with a group of two outputs after the statistics, and nothing else changed."""
    groups = list(described.GROUPS)
    groups.insert([g.name for g in groups].index("statistics") + 1, EXTRA)
    monkeypatch.setattr(described, "GROUPS", groups)


def test_a_new_group_is_one_entry_in_the_list(extra_group, tmp_path):
    plain = PLAIN
    first = plain["rtol"]  # the new group takes the real settings' place; they and the rest move on
    records = {v["name"]: v for v in model_data(SEED, build_core(SEED), SETTINGS, "native")["variables"]}
    assert [records[name]["value_reference"] for name in ("n_extra", "n_more")] == [first, first + 1]
    assert {name: v["value_reference"] for name, v in records.items() if name not in ("n_extra", "n_more")} == {
        name: vr + (2 if vr >= first else 0) for name, vr in plain.items()}
    data = {"variables": list(records.values()), "settings": SETTINGS, "description": "extra"}
    # fmu_config.h: its value references and the names by value reference
    header = config_header(data, "{guid}")
    assert f"#define CP_VR_EXTRA {first}\n" in header and f"#define CP_VR_SETTINGS {first + 2}\n" in header
    assert f"#define CP_NREAL {plain['solver'] + 2}\n" in header
    # the native model description
    root = ET.fromstring(model_description(data, "{guid}"))
    rows = {row["name"]: row for row in declared(root)}
    assert rows["n_extra"] == {"name": "n_extra", "value_reference": first, "type": "Real",
                               "causality": "output", "variability": "discrete",
                               "initial": "calculated", "description": "an extra count", "start": None}
    assert str(first + 1) in {u.get("index") for u in root.find("ModelStructure/Outputs")}
    # both FMUs build with it and run: the slave and the glue read the new layout
    for backend in ("pythonfmu", "native"):
        fmu = build_fmu(SEED, tmp_path / f"{backend}.fmu", backend=backend).path
        root, model = read(fmu)
        rows = {row["name"]: row for row in declared(root)}
        assert [v["name"] for v in model["variables"]] == list(rows) == list(records)[:len(rows)]
        assert rows["n_extra"]["value_reference"] == first
        assert rows["max_steps"]["value_reference"] == plain["max_steps"] + 2
        run = run_fmu(fmu, stop_time=0.1, output_interval=0.05, start_values={"max_steps": 1000})
        assert np.all(run["n_extra"] == 0) and run["n_rhs"][-1] > 0 and np.isfinite(run["energy"]).all()
