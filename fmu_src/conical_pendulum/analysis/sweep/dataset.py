"""The dataset: its schema and settings, a batch's rows in long form, the Parquet parts the
client writes, and what an existing dataset holds (to resume it, or refuse it)."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import time
from collections import deque
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

SETTINGS_FILE = "_sweep.json"  # the dataset's settings; a leading _ hides it from Parquet readers
PART_SECONDS, PART_BYTES = 5.0, 256 << 20  # a part file is closed after this long or this much


def schema(md, inputs: pd.DataFrame, outputs: list[str], settings: dict) -> pa.Schema:
    """The dataset's columns, the same in every file whatever its runs did, with the
    settings where pandas reads them into `attrs`."""
    kinds = {v.name: v.type for v in md.modelVariables}
    types = {"Real": pa.float64(), "Integer": pa.int32(), "Enumeration": pa.int32(), "Boolean": pa.bool_()}
    return pa.schema(
        [
            ("run", pa.int64()),
            *((name, pa.from_numpy_dtype(inputs[name].dtype)) for name in inputs.columns),
            ("status", pa.string()),
            ("message", pa.string()),
            ("time", pa.float64()),
            *((name, types[kinds[name]]) for name in outputs),
        ],
        metadata={"PANDAS_ATTRS": json.dumps(settings)},
    )


def batch_table(summary: list, rows: np.ndarray | None, inputs: dict, schema: pa.Schema) -> pa.Table:
    """A batch's rows in long form: each column copied once; a run that kept no rows gets
    one row with no time and no outputs (NaN in pandas)."""
    index, ok, message, kept = zip(*summary)
    kept = np.array(kept)
    lengths = np.maximum(kept, 1)
    run = np.repeat(np.array(index, dtype=np.int64), lengths)
    has_rows = np.repeat(kept > 0, lengths)
    columns = {
        "run": run,
        **{name: values[run] for name, values in inputs.items()},
        "status": np.repeat(np.array(["ok" if good else "failed" for good in ok], dtype=object), lengths),
        "message": np.repeat(np.array(message, dtype=object), lengths),
    }
    arrays = []
    for field in schema:
        if field.name in columns:
            arrays.append(pa.array(columns[field.name], type=field.type))
        elif rows is None:
            arrays.append(pa.nulls(len(run), field.type))
        elif has_rows.all():
            arrays.append(pa.array(np.ascontiguousarray(rows[field.name])).cast(field.type))
        else:
            values = np.zeros(len(run), rows.dtype[field.name])
            values[has_rows] = rows[field.name]
            arrays.append(pa.array(values, mask=~has_rows).cast(field.type))
    return pa.Table.from_arrays(arrays, schema=schema)


class Parts:
    """The dataset's files as the client writes them: batches appended as row groups to a
    hidden file, renamed into the dataset once PART_SECONDS old or PART_BYTES large and when
    the sweep ends or stops, so a dataset holds only whole files and a killed client loses
    at most the open one's runs."""

    def __init__(self, folder: Path, schema: pa.Schema, number: int):
        self.folder, self.schema, self.number, self.writer = folder, schema, number, None
        # repeated values (a run's number, inputs, status, message) as dictionaries; outputs plain
        self.dictionary = [field.name for field in schema if field.name not in ("time", *outputs_of(schema))]

    def write(self, table: pa.Table):
        if self.writer is None:
            self.path = self.folder / f".part-{self.number:05d}.parquet.tmp"
            self.writer = pq.ParquetWriter(self.path, self.schema, use_dictionary=self.dictionary)
            self.opened, self.size = time.monotonic(), 0
        self.writer.write_table(table)
        self.size += table.nbytes
        if self.size >= PART_BYTES or time.monotonic() - self.opened >= PART_SECONDS:
            self.close()

    def close(self):
        if self.writer is not None:
            self.writer.close()
            os.replace(self.path, self.folder / f"part-{self.number:05d}.parquet")
            self.writer, self.number = None, self.number + 1


def outputs_of(schema: pa.Schema) -> list[str]:
    return json.loads(schema.metadata[b"PANDAS_ATTRS"])["outputs"]


def settings_of(md, data: bytes, inputs: pd.DataFrame, stop_time, output_interval, outputs) -> dict:
    """What makes a sweep this sweep: a dataset written with other settings is never resumed."""
    runs = hashlib.sha256()
    for name in inputs.columns:
        values = inputs[name].to_numpy()
        runs.update(f"{name}:{values.dtype}:".encode())
        runs.update(np.ascontiguousarray(values).tobytes())
    return {
        "fmu": md.modelName,
        "fmu_guid": md.guid,
        "fmu_sha256": hashlib.sha256(data).hexdigest(),
        "stop_time": stop_time,
        "output_interval": output_interval,
        "outputs": outputs,
        "inputs": list(inputs.columns),
        "runs": len(inputs),
        "runs_sha256": runs.hexdigest(),
    }


def shown(value) -> str:
    text = ",".join(map(str, value)) if isinstance(value, list) else f"{value}"
    return text if len(text) <= 40 else f"{text[:37]}..."


def differences(found: dict, wanted: dict) -> list[str]:
    """What differs between a dataset's settings and this sweep's, in words."""
    said = []
    if found.get("fmu_sha256") != wanted["fmu_sha256"]:
        said.append(
            f"another FMU ({found.get('fmu')} sha256 {str(found.get('fmu_sha256'))[:12]} there, "
            f"{wanted['fmu']} {wanted['fmu_sha256'][:12]} here)"
        )
    for key, name in [
        ("outputs", "outputs"),
        ("stop_time", "stop time"),
        ("output_interval", "output interval"),
        ("runs", "runs"),
        ("inputs", "variables set"),
    ]:
        if found.get(key) != wanted[key]:
            said.append(f"{name} {shown(found.get(key))} there, {shown(wanted[key])} here")
    if not said and found.get("runs_sha256") != wanted["runs_sha256"]:
        said.append("other values of the runs (another grid, ranges, samples or seed)")
    return said


def done_runs(folder: Path, total: int) -> np.ndarray:
    """Which runs the dataset's files hold, from their footers: the client writes a batch
    of consecutive runs, each whole, as one row group, so each row group's least and
    greatest run bound the runs it holds."""
    done = np.zeros(total, dtype=bool)
    for part in folder.glob("part-*.parquet"):
        metadata = pq.ParquetFile(part).metadata
        column = metadata.schema.names.index("run")
        for group in range(metadata.num_row_groups):
            statistics = metadata.row_group(group).column(column).statistics
            done[statistics.min : statistics.max + 1] = True
    return done


def check_out(out: Path, settings: dict, resume: bool, overwrite: bool) -> tuple[np.ndarray, bool]:
    """(the runs the output holds already, whether to remove it first); refuses an output
    that is not this sweep's to resume or a sweep's to replace, before anything runs."""
    none = np.zeros(settings["runs"], dtype=bool)
    if not out.parent.is_dir():
        raise ValueError(f"out: {out.parent} is not a directory")
    if out.exists() and not out.is_dir():
        raise ValueError(f"out: {out} is a file; a sweep writes a folder: give another name")
    if not out.exists() or not any(out.iterdir()):
        return none, False
    settings_file = out / SETTINGS_FILE
    if not settings_file.is_file():
        raise ValueError(f"out: {out} is a folder that holds no sweep; give another name")
    if overwrite:
        return none, True
    if not resume:
        raise ValueError(
            f"out: {out} holds a sweep already; --resume (resume=True) finishes it, "
            "--overwrite (overwrite=True) replaces it"
        )
    different = differences(json.loads(settings_file.read_text()), settings)
    if different:
        raise ValueError(
            f"out: {out} holds another sweep, not resumed: {'; '.join(different)}; "
            "give another output, or overwrite it"
        )
    return done_runs(out, settings["runs"]), False


def begin(out: Path, settings: dict, replace: bool) -> int:
    """The output folder made ready to write (the last client's open file dropped), and the
    number of its next file."""
    if replace:
        shutil.rmtree(out)
    out.mkdir(exist_ok=True)
    for unfinished in out.glob(".part-*.parquet.tmp"):
        unfinished.unlink()
    if not (out / SETTINGS_FILE).exists():
        written = out / f".{SETTINGS_FILE}.tmp"
        written.write_text(json.dumps(settings, indent=1))
        os.replace(written, out / SETTINGS_FILE)
    taken = [int(part.stem.removeprefix("part-")) for part in out.glob("part-*.parquet")]
    return max(taken, default=-1) + 1


def batches(missing: np.ndarray, size: int) -> deque:
    """The missing runs as (first, last) batches of consecutive runs, at most `size` each."""
    batches = deque()
    starts = np.flatnonzero(np.diff(missing, prepend=-2) != 1)
    for first, last in zip(missing[starts], np.r_[missing[starts[1:] - 1], missing[-1:]]):
        for begin in range(int(first), int(last) + 1, size):
            batches.append((begin, min(begin + size - 1, int(last))))
    return batches
