"""Scene files: a scene from TOML or JSON, its [[link]] tables and scene-wide fields (see
scenes/seed.toml), every unknown field and wrong type named in the message."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

from .links import PARTS, Link, SceneError
from .scene import Scene

DEFAULT_LINK = Link()
SCENE_FIELDS = {
    "link",
    "kinematics",
    "gravity",
    "outputs",
    "coupling",
    "formulation",
    "joint_damping",
    "air_drag",
    "air_density",
}
LINK_FIELDS = {"length", "mass", "radius", "inertia", "damping", *PARTS}


def load_scene(path) -> Scene:
    """A scene from a TOML or JSON file (see scenes/seed.toml for the fields)."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise SceneError(f"scene file {str(path)!r}: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise SceneError(f"scene file {str(path)!r}: not text (UTF-8)") from None
    try:
        if path.suffix == ".toml":
            data = tomllib.loads(text)
        elif path.suffix == ".json":
            data = json.loads(text)
        else:
            raise SceneError(f"scene file {str(path)!r}: expected a .toml or .json file")
    except (tomllib.TOMLDecodeError, json.JSONDecodeError) as exc:
        raise SceneError(f"scene file {str(path)!r}: {exc}") from None
    try:
        return scene_from_dict(data)
    except SceneError as exc:
        raise SceneError(f"scene file {str(path)!r}: {exc}") from None


def scene_from_dict(data: dict) -> Scene:
    """A scene from the structure of a scene file: [[link]] tables and scene-wide fields."""
    _known(data, SCENE_FIELDS, "scene")
    links = data.get("link")
    if not isinstance(links, list) or not links:
        raise SceneError("link: give one [[link]] table per link, top to bottom")
    made = []
    for i, entry in enumerate(links):
        where = f"link[{i}]"
        if not isinstance(entry, dict):
            raise SceneError(f"{where}: expected a table of fields, got {entry!r}")
        _known(entry, LINK_FIELDS, where)
        mass = entry.get("mass", DEFAULT_LINK.mass)
        fields = {
            "has_mass": mass != 0,
            "has_bob": False,
            "mass": mass if mass != 0 else DEFAULT_LINK.mass,
        }
        fields.update({name: entry[name] for name in ("length", "radius", "damping") if name in entry})
        for table, part in PARTS.items():
            if table in entry:
                fields.update(_part(entry[table], part, f"{where}.{table}"))
        if "inertia" in entry:
            fields["moments"] = (
                tuple(entry["inertia"]) if isinstance(entry["inertia"], list) else entry["inertia"]
            )
        try:
            made.append(Link(**fields))
        except TypeError as exc:
            raise SceneError(f"{where}: {exc}") from None
    scene_fields = {"links": tuple(made)}
    for name in SCENE_FIELDS - {"link"}:
        if name in data:
            scene_fields[name] = tuple(data[name]) if name == "outputs" else data[name]
    if "joint_damping" not in data and any("damping" in entry for entry in links):
        scene_fields["joint_damping"] = True  # a link's damping asks for it
    drag_fields = ("drag_coefficient", "area")
    bob_drag = any(name in (entry.get("bob") or {}) for entry in links for name in drag_fields)
    if "air_drag" not in data and ("air_density" in data or bob_drag):
        scene_fields["air_drag"] = True  # the air's density or a bob's drag asks for it
    for name in ("gravity", "air_density"):
        if name in data and (isinstance(data[name], bool) or not isinstance(data[name], (int, float))):
            raise SceneError(f"{name}: expected a number, got {data[name]!r}")
    return Scene(**scene_fields)


def _part(table, part, where: str) -> dict:
    """A link's part from its table: the flag set, each field into its Link field."""
    if not isinstance(table, dict):
        raise SceneError(f"{where}: expected a table {part.shape}, got {table!r}")
    _known(table, set(part.fields), where)
    return {part.flag: True, **{part.link_field(name): value for name, value in table.items()}}


def _known(table: dict, fields: set, where: str) -> None:
    unknown = sorted(set(table) - fields)
    if unknown:
        raise SceneError(f"{where}: unknown field(s) {unknown}; known: {sorted(fields)}")
