"""A sweep's dataset read: SweepResults."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.dataset as ds
import pyarrow.parquet as pq

from .dataset import SETTINGS_FILE, done_runs


class SweepResults:
    """A sweep's dataset, not read until asked: a folder of Parquet files (`part-*.parquet`)
    and the settings (`_sweep.json`; also in each file's metadata, pandas' `attrs`).

    pandas.read_parquet(path), pyarrow.dataset.dataset(path), dask.dataframe.read_parquet(path)
    and duckdb's read_parquet('<path>/*.parquet') read it; rows of a run are together and
    in time order, runs in the order they finished (sort by run, as to_pandas does)."""

    def __init__(self, path, ran: int | None = None):
        self.path, self.ran = Path(path), ran  # ran: the runs the sweep() that returned it ran
        self.attrs = json.loads((self.path / SETTINGS_FILE).read_text())

    def __repr__(self):
        return f"SweepResults({str(self.path)!r}: {self.attrs['runs']} runs of {self.attrs['fmu']})"

    def dataset(self) -> ds.Dataset:
        return ds.dataset(self.path, format="parquet")

    def to_pandas(self, columns: Sequence[str] | None = None, filter=None) -> pd.DataFrame:
        """The rows (those `filter`, a pyarrow expression, keeps), ordered by run then time, with
        the settings in `attrs`; every column by default, or `columns` (run always)."""
        if columns is not None:
            columns = list(dict.fromkeys(["run", *columns]))
        table = self.dataset().to_table(columns=columns, filter=filter).sort_by("run")  # stable
        frame = table.to_pandas()
        frame.attrs = dict(self.attrs)
        return frame

    def done(self) -> int:
        """How many runs the dataset holds (all of them once the sweep has ended)."""
        return int(done_runs(self.path, self.attrs["runs"]).sum())

    # rows() and failed() read the files one at a time: a scan of the whole dataset keeps
    # every file's footer (its row groups' metadata, ~2 MB a file) until it ends, so the
    # client's peak, after the sweep, grew with the runs (about 4 kB a run).
    def rows(self) -> int:
        return sum(pq.read_metadata(part).num_rows for part in self.dataset().files)

    def failed(self) -> pd.DataFrame:
        """One row per failed run, by run: its inputs and message; only the row groups whose
        statistics of `status` say they hold a failed run are read."""
        columns = ["run", *self.attrs["inputs"], "message"]
        tables, schema = [], None
        for part in self.dataset().files:
            file = pq.ParquetFile(part)
            schema = file.schema_arrow
            status = schema.get_field_index("status")
            groups = []
            for group in range(file.metadata.num_row_groups):
                statistics = file.metadata.row_group(group).column(status).statistics
                if statistics is None or not statistics.has_min_max or statistics.min == "failed":
                    groups.append(group)  # "failed" < "ok": a group with one has it as its least
            if groups:
                table = file.read_row_groups(groups, columns=[*columns, "status"])
                tables.append(table.filter(pc.equal(table["status"], "failed")).select(columns))
            file.close()
        if schema is None:  # no files
            frame = self.to_pandas(columns[1:], filter=ds.field("status") == "failed")
        else:
            table = pa.concat_tables(tables) if tables else schema.empty_table().select(columns)
            frame = table.sort_by("run").to_pandas()  # stable: each run's first row first
            frame.attrs = dict(self.attrs)
        return frame.drop_duplicates("run").set_index("run")
