"""An FMI 3.0 FMU of this package read from the host with the FMI 2.0 FMU's scalar names:
its arrays (alpha, l, bob_x, ...) set whole from per-link start values, and split into
per-link columns in results. The arrays are its records' (model.json: each variable's
`array` and `index`, builder.fmi.variables), never parsed from names."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

from ..builder.fmi.variables import Variable, records
from ..runtime.files import MODEL_FILE


def fmu_data(path) -> dict | None:
    """model.json of an FMI 3.0 FMU of this package (a .fmu or its unzipped folder), or None for
    any other FMU."""
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


def arrays(data: dict) -> dict[str, list[Variable]]:
    """Each FMI 3.0 array's records by its name, element by element."""
    found: dict[str, list[Variable]] = {}
    for v in sorted((v for v in records(data) if v.array is not None), key=lambda v: v.index):
        found.setdefault(v.array, []).append(v)
    return found


def element_names(data: dict) -> dict[str, tuple[str, int]]:
    """Each per-link scalar's name -> (its array's name, its 0-based index): alpha0 -> (alpha, 0),
    which FMI 3.0's structured naming writes alpha[1]."""
    return {v.name: (v.array, v.index) for v in records(data) if v.array is not None}


def array_start_values(data: dict, values: dict) -> dict:
    """Start values by the FMI 2.0 FMU's names (alpha0, l1, ...) -> the FMI 3.0 FMU's: an array
    whole, its other elements at their start values."""
    elements, members = element_names(data), arrays(data)
    starts = {}
    for name, value in values.items():
        if name in elements:
            array, k = elements[name]
            starts.setdefault(array, [m.start for m in members[array]])[k] = value
        else:
            starts[name] = value
    return starts


def scalar_columns(data: dict, result):
    """An fmpy result of the FMI 3.0 FMU with each array column (shape (n,)) split into the FMI
    2.0 FMU's scalar columns (alpha -> alpha0, alpha1, ...), so what reads the FMI 2.0 FMU's
    results reads it."""
    import numpy as np

    members = {name: [m.name for m in elements] for name, elements in arrays(data).items()}
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
