"""conical_pendulum.analysis.sweep: Dask runs equal to fmpy's one by one, failures kept with their
messages, a Parquet dataset that pandas, pyarrow, dask and duckdb read, the FMU loaded once
per worker, a run that crashes its worker costing one row, interrupted sweeps resumed to
the same dataset, and a command that refuses what it cannot run."""

import contextlib
import hashlib
import logging
import math
import os
import signal
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path

import dask
import numpy as np
import pandas as pd
import pyarrow.dataset as ds
import pytest
from distributed import Client, LocalCluster

from conical_pendulum.analysis import runner
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.analysis.sweep import (
    LoadedFmu,
    SweepResults,
    dataset,
    grid,
    random_samples,
    sweep,
    worker,
)
from conical_pendulum.analysis.sweep import cluster as clusters
from conical_pendulum.analysis.sweep import loop as client_loop
from conical_pendulum.analysis.sweep import runs as run_tables
from shapes import MODES, build_shapes_fmus

pytestmark = pytest.mark.cluster  # Dask clusters, local ones or the command's own

# a start that needs more than 25 internal steps in the communication step from 1.5 s to 2 s,
# with the solver settings it was found with (the defaults before DOP853 at 1e-11 across points)
OLD_SOLVER = {"solver": 1, "rtol": 1e-8, "atol": 1e-8, "across_points": 0}
DISCARDED_AT_1_5 = {"alpha0": 1.2, "delta2": 3.0, "max_steps": 25, **OLD_SOLVER}


@pytest.fixture
def tmp_path(tmp_path):
    """pytest's folder for the test under a short name, a symlink in /tmp removed after: the
    sweeps' processes take TMPDIR inside it, where multiprocessing's forkserver binds its Unix
    socket (pymp-*/listener-*, at most 107 bytes), and pytest's own path outgrows that once
    its run counter has three digits (/tmp/pytest-of-root/pytest-124/popen-gw0/test_every_run_
    crashing_finish0/tmp/...: 108). What the processes write still lands in pytest's folder."""
    alias = Path("/tmp") / f"cp-sweep-{os.getpid()}-{uuid.uuid4().hex[:8]}"
    alias.symlink_to(tmp_path, target_is_directory=True)
    yield alias
    alias.unlink()


@pytest.fixture(scope="module", autouse=True)
def dask_scratch(tmp_path_factory):
    """The tests' own clusters keep Dask's scratch space in pytest's folder, not in TMPDIR,
    where Dask would leave its dask-scratch-space (a sweep's cluster makes and removes its own)."""
    with dask.config.set({"temporary-directory": str(tmp_path_factory.mktemp("dask-scratch"))}):
        yield


@pytest.fixture(scope="module")
def cluster():
    """An existing cluster, as `scheduler=` reaches one; its workers run two tasks at once."""
    with LocalCluster(n_workers=2, threads_per_worker=2, dashboard_address="127.0.0.1:0") as cluster:
        yield cluster


def by_run(results):
    return results.drop_duplicates("run").set_index("run")


def test_runs_equal_fmpy_one_by_one(seed_fmu, tmp_path):
    runs = random_samples(
        {"l0": (5, 15), "m1": (1, 10), "alpha0": (-1, 1), "beta2": (-0.5, 0.5), "delta1": (-2, 2)},
        100,
        seed=7,
    )
    results = sweep(seed_fmu, runs, n_workers=2, progress=False, out=tmp_path / "s.parquet").to_pandas()
    assert (results["status"] == "ok").all() and (results["message"] == "").all()
    inputs = by_run(results)[["l0", "m1", "alpha0_start", "beta2_start", "delta1_start"]]
    assert inputs.rename(columns=lambda name: name.removesuffix("_start")).to_dict("records") == runs
    for index, run in enumerate(runs):
        got = results[results["run"] == index]
        expected = run_fmu(seed_fmu, start_values=run)
        for name in ["time", *results.attrs["outputs"]]:
            assert np.array_equal(got[name].to_numpy(), expected[name]), (index, name)


def test_both_loops_give_the_same_file_on_a_running_cluster(native_seed_fmu, cluster, tmp_path):
    runs = random_samples({"l0": (5, 15), "alpha0": (-1, 1)}, 12, seed=2) + [{"l0": -1.0}, DISCARDED_AT_1_5]
    results = {
        loop: sweep(
            native_seed_fmu,
            runs,
            output_interval=0.5,
            scheduler=cluster.scheduler_address,
            progress=False,
            loop=loop,
            out=tmp_path / loop,
        ).to_pandas()
        for loop in ("runner", "fmpy")
    }
    # the native FMU's discard ends in fmi2Error at the next step: only the runner keeps rows
    kept = {loop: frame[frame["run"] == 13] for loop, frame in results.items()}
    assert list(kept["runner"]["time"]) == [0.0, 0.5, 1.0, 1.5] and kept["fmpy"]["time"].isna().all()
    assert kept["runner"]["message"].iat[0] == kept["fmpy"]["message"].iat[0]
    pd.testing.assert_frame_equal(*(frame[frame["run"] != 13] for frame in results.values()))
    assert list(by_run(results["runner"])["status"]) == ["ok"] * 12 + ["failed"] * 2


def test_a_worker_without_the_runner_uses_fmpys_loop_and_says_why(seed_fmu, monkeypatch, caplog, tmp_path):
    monkeypatch.setattr(runner, "unavailable", lambda: "no C compiler cc")
    with (
        LocalCluster(n_workers=1, processes=False, dashboard_address="127.0.0.1:0") as in_process,
        caplog.at_level(logging.WARNING, logger="conical_pendulum.analysis.sweep"),
    ):
        results = sweep(
            seed_fmu,
            [{"l0": 5.0}],
            stop_time=1.0,
            scheduler=in_process.scheduler_address,
            progress=False,
            out=tmp_path / "s.parquet",
        ).to_pandas()
    assert (results["status"] == "ok").all()
    assert "runs fmpy's loop, not the compiled runner: no C compiler cc" in caplog.text
    assert "ConicalPendulum: fmpy's loop instead of the compiled runner: no C compiler cc" in caplog.text


def test_a_refused_value_fails_only_its_run(seed_fmu, cluster, tmp_path):
    runs = grid({"l0": [5.0, 10.0], "alpha0": [0.2, 0.4]}) + [{"l0": -1.0}]
    results = sweep(
        seed_fmu,
        runs,
        stop_time=2.0,
        output_interval=0.5,
        scheduler=cluster.scheduler_address,
        progress=False,
        out=tmp_path / "s.parquet",
    ).to_pandas()
    inputs = by_run(results)
    assert list(inputs["status"]) == ["ok"] * 4 + ["failed"]
    assert inputs.loc[4, "alpha0_start"] == math.radians(10)  # left alone: the FMU's start value
    failed = results[results["run"] == 4]
    assert len(failed) == 1 and np.isnan(failed["time"]).all() and np.isnan(failed["energy"]).all()
    assert "l0 = -1.0: a length must be positive" in failed["message"].iat[0]
    ok = results[results["run"] < 4]
    assert ok.groupby("run")["time"].max().eq(2.0).all() and not ok["energy"].isna().any()


@pytest.mark.parametrize("backend", ["pythonfmu", "native"])
def test_a_discarded_step_fails_the_run_with_the_rows_before(
    backend, seed_fmu, native_seed_fmu, cluster, tmp_path
):
    """The native FMU's discard ends in fmi2Error at the next step (fmpy's loop keeps no rows
    then); the compiled runner keeps the rows before it, as pythonfmu's terminated run has."""
    fmu = seed_fmu if backend == "pythonfmu" else native_seed_fmu
    runs = [{"alpha0": 1.2, "delta2": 3.0, **OLD_SOLVER}, DISCARDED_AT_1_5]
    results = sweep(
        fmu,
        runs,
        output_interval=0.5,
        scheduler=cluster.scheduler_address,
        progress=False,
        out=tmp_path / "s",
    ).to_pandas()
    assert list(by_run(results)["status"]) == ["ok", "failed"]
    failed = results[results["run"] == 1]
    assert list(failed["time"]) == [0.0, 0.5, 1.0, 1.5]  # fmpy's repeat of the last good point dropped
    assert "more than max_steps = 25 internal steps" in failed["message"].iat[0]
    assert "The state is kept at t = 1.5 s" in failed["message"].iat[0]
    first = results[results["run"] == 0]
    assert first["time"].iat[-1] == 10.0
    assert np.array_equal(failed["alpha0"], first["alpha0"][:4])


def test_non_finite_outputs_fail_the_run(seed_fmu, monkeypatch):
    def poisoned(*args, **kwargs):
        rows = run_fmu(*args, **kwargs)
        rows["energy"][3] = np.nan
        return rows

    fmu = LoadedFmu(seed_fmu.read_bytes(), loop="fmpy")
    try:
        rows, ok, message = fmu.run({}, 1.0, 0.1, ["energy", "bob2_x"])
        assert ok and message == "" and rows["time"][-1] == 1.0
        monkeypatch.setattr(worker, "run_fmu", poisoned)
        rows, ok, message = fmu.run({}, 1.0, 0.1, ["energy", "bob2_x"])
        assert not ok and message == "non-finite values in energy"
    finally:
        fmu.close()


def test_the_dataset_round_trips(seed_fmu, cluster, tmp_path, monkeypatch):
    monkeypatch.setattr(dataset, "PART_SECONDS", 0.0)  # a file per batch: a dataset of several
    out = tmp_path / "sweep.parquet"
    runs = grid({"l0": [5.0, -1.0], "solver": [1, 2], "beta1": [0.0, 0.3]})
    handle = sweep(
        seed_fmu,
        runs,
        stop_time=1.0,
        output_interval=0.25,
        outputs=["energy", "bob2_x"],
        scheduler=cluster.scheduler_address,
        out=out,
        batch=3,
        progress=False,
    )
    assert len(list(out.glob("part-*.parquet"))) == 3 and handle.done() == 8 and handle.rows() == 24
    results = handle.to_pandas()
    read = pd.read_parquet(out)  # runs in the order they finished
    pd.testing.assert_frame_equal(read.sort_values("run", kind="stable", ignore_index=True), results)
    assert list(read.columns) == [
        "run",
        "l0",
        "solver",
        "beta1_start",
        "status",
        "message",
        "time",
        "energy",
        "bob2_x",
    ]
    assert (
        read.attrs
        == results.attrs
        == {
            "fmu": "ConicalPendulum",
            "fmu_guid": read.attrs["fmu_guid"],
            "fmu_sha256": hashlib.sha256(seed_fmu.read_bytes()).hexdigest(),
            "stop_time": 1.0,
            "output_interval": 0.25,
            "outputs": ["energy", "bob2_x"],
            "inputs": ["l0", "solver", "beta1_start"],
            "runs": 8,
            "runs_sha256": read.attrs["runs_sha256"],
        }
    )
    inputs = by_run(results)
    assert inputs[["l0", "solver", "beta1_start"]].to_dict("records") == [
        {"l0": run["l0"], "solver": run["solver"], "beta1_start": run["beta1"]} for run in runs
    ]
    assert list(inputs["status"]) == ["ok"] * 4 + ["failed"] * 4
    assert results.groupby("run").size().tolist() == [5] * 4 + [1] * 4
    failed = handle.failed()
    assert list(failed.index) == [4, 5, 6, 7] and list(failed.columns) == [
        "l0",
        "solver",
        "beta1_start",
        "message",
    ]
    assert failed["message"].str.startswith("l0 = -1.0: a length must be positive").all()


def test_pyarrow_dask_and_duckdb_read_the_dataset(seed_fmu, cluster, tmp_path, monkeypatch):
    duckdb = pytest.importorskip("duckdb")
    dd = pytest.importorskip("dask.dataframe")
    monkeypatch.setattr(dataset, "PART_SECONDS", 0.0)
    out = tmp_path / "sweep.parquet"
    handle = sweep(
        seed_fmu,
        random_samples({"l0": (5, 15)}, 9, seed=1) + [{"l0": -1.0}],
        stop_time=1.0,
        output_interval=0.5,
        outputs=["energy"],
        scheduler=cluster.scheduler_address,
        out=out,
        batch=4,
        progress=False,
    )
    expected = handle.to_pandas().drop(columns="message")
    by_pyarrow = ds.dataset(out).to_table().to_pandas()
    by_dask = dd.read_parquet(out).compute()
    by_duckdb = duckdb.sql(f"select * from read_parquet('{out}/*.parquet') order by run, time").df()
    for frame in (by_pyarrow, by_dask, by_duckdb):
        frame = frame.sort_values(["run", "time"], ignore_index=True)  # duckdb's order is its threads'
        assert list(frame["run"]) == list(expected["run"]) == [k for k in range(9) for _ in range(3)] + [9]
        for name in ["l0", "time", "energy"]:
            assert np.array_equal(frame[name].to_numpy(float), expected[name].to_numpy(float), equal_nan=True)
        assert list(frame["status"]) == ["ok"] * 27 + ["failed"]


def test_each_worker_loads_the_fmu_once(seed_fmu, cluster, tmp_path):
    with Client(cluster) as client:
        before = client.run(lambda: LoadedFmu.loads)
        results = sweep(
            seed_fmu,
            [{"l0": 5.0 + k} for k in range(40)],
            stop_time=1.0,
            batch=2,
            scheduler=cluster.scheduler_address,
            progress=False,
            out=tmp_path / "s.parquet",
        ).to_pandas()
        after = client.run(lambda: LoadedFmu.loads)
        left = client.run(lambda dask_worker: [name for name in dask_worker.plugins if "sweep" in name])
    assert (results["status"] == "ok").all() and results["run"].nunique() == 40  # in 20 tasks
    assert len(after) == 2 and all(after[worker] - before[worker] == 1 for worker in after)
    assert all(names == [] for names in left.values())  # unregistered: extracted files removed


def test_a_scheduler_without_workers_is_refused(seed_fmu, tmp_path):
    with (
        LocalCluster(n_workers=0, dashboard_address="127.0.0.1:0") as empty,
        pytest.raises(ConnectionError, match="no workers after 1 s"),
    ):
        sweep(
            seed_fmu,
            [{"l0": 5.0}],
            scheduler=empty.scheduler_address,
            timeout=1,
            progress=False,
            out=tmp_path / "s.parquet",
        )
    assert not list(tmp_path.iterdir())  # nothing written


def test_runs_are_made_reproducibly():
    assert grid({"l0": [5, 10], "alpha0": [0.1, 0.2]}) == [
        {"l0": 5, "alpha0": 0.1},
        {"l0": 5, "alpha0": 0.2},
        {"l0": 10, "alpha0": 0.1},
        {"l0": 10, "alpha0": 0.2},
    ]
    samples = random_samples({"l0": (5, 15), "g": (9, 10)}, 50, seed=3)
    assert samples == random_samples({"l0": (5, 15), "g": (9, 10)}, 50, seed=3)
    assert samples != random_samples({"l0": (5, 15), "g": (9, 10)}, 50, seed=4)
    assert all(5 <= run["l0"] < 15 and 9 <= run["g"] < 10 for run in samples)


def test_runs_are_held_as_columns(seed_fmu):
    """A million runs cost the client 8 bytes a value, as dicts or as columns, with the same
    table; what is not a number or not whole for an Integer is refused naming its run."""
    from fmpy import read_model_description

    md = read_model_description(str(seed_fmu))
    samples = random_samples({"l0": (5, 15), "alpha0": (0, 0.5)}, 10**6, seed=1)
    table = run_tables.run_table(md, samples)
    assert table.memory_usage(index=False).sum() == 2 * 8 * 10**6
    assert sum(values.nbytes for values in samples.columns.values()) == 2 * 8 * 10**6
    as_dicts = run_tables.run_table(md, list(samples[:1000]) + [{"l0": 7.0}])
    start = float(next(v.start for v in md.modelVariables if v.name == "alpha0"))
    assert as_dicts.iloc[:1000].equals(table.iloc[:1000])
    assert as_dicts.iloc[1000].to_dict() == {"l0": 7.0, "alpha0": start}  # left alone: its start
    solvers = run_tables.run_table(md, grid({"solver": [1, 2], "l0": [5.0]}))
    assert solvers["solver"].dtype == np.int64 and list(solvers["solver"]) == [1, 2]
    for runs, message in [
        ([{"l0": 5.0}, {"l0": "x"}], "run 1: l0 = 'x' is not a number"),
        ([{"l0": 5.0}, (("l0", 5.0),)], "run 1: .* is not a mapping"),
        (grid({"solver": [1.0, 1.5]}), "run 1: solver = 1.5: solver is an Enumeration variable"),
        (run_tables.Runs({"l0": np.array(["5"])}), "runs: l0 holds <U1 values, not numbers"),
        ([], "no runs to do"),
    ]:
        with pytest.raises(ValueError, match=message):
            run_tables.run_table(md, runs)


def test_dask_keeps_no_history_of_the_runs(seed_fmu, cluster, tmp_path, monkeypatch):
    """Dask keeps the last messages of each stream for debugging, 1000 by default: the
    batches' runs and rows, which grew the client up to 25,000 runs. The sweep's client and
    its local scheduler keep LOW_LEVEL_LOG, on a local cluster and on a running one."""
    kept = []
    made = clusters.connect

    @contextlib.contextmanager
    def watched(*args, **kwargs):
        with made(*args, **kwargs) as client:
            yield client
            logs = [client.scheduler_comm.recent_message_log]
            if client.cluster is not None:  # the local cluster's scheduler, in this process
                scheduler = client.cluster.scheduler
                streams = [*scheduler.stream_comms.values(), *scheduler.client_comms.values()]
                logs += [stream.recent_message_log for stream in streams]
                logs += [scheduler.transition_log]
            kept.append([log.maxlen for log in logs])

    monkeypatch.setattr(client_loop, "connect", watched)
    runs = grid({"l0": [5.0, 6.0, 7.0]})
    sweep(seed_fmu, runs, out=tmp_path / "local.parquet", stop_time=0.1, progress=False)
    sweep(
        seed_fmu,
        runs,
        out=tmp_path / "running.parquet",
        stop_time=0.1,
        progress=False,
        scheduler=cluster.scheduler_address,
    )
    assert len(kept[0]) > 2 and len(kept[1]) == 1
    assert all(maxlen == clusters.LOW_LEVEL_LOG for logs in kept for maxlen in logs)


def command(*args, cwd):
    """`conical-pendulum sweep ...`, the installed command."""
    return subprocess.run(
        [str(Path(sys.executable).with_name("conical-pendulum")), "sweep", *map(str, args)],
        cwd=cwd,
        check=False,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_command_writes_the_sweep(seed_fmu, tmp_path):
    out = tmp_path / "s.parquet"
    run = command(
        seed_fmu,
        "--grid",
        "l0=5,-1",
        "--grid",
        "alpha0=0.1,0.2",
        "--stop-time",
        "1",
        "--interval",
        "0.1",
        "--outputs",
        "energy,bob2_x",
        "--workers",
        "1",
        "--loop",
        "fmpy",
        "--out",
        out,
        cwd=tmp_path,
    )
    assert run.returncode == 1, run.stderr  # some runs failed
    assert f"wrote {out}: 4 runs (2 failed), 24 rows" in run.stdout
    assert "run 2 (l0 = -1, alpha0_start = 0.1) failed: l0 = -1.0: a length must be positive" in run.stdout
    assert "4/4 runs, 2 failed" in run.stderr
    assert list(pd.read_parquet(out).columns) == [
        "run",
        "l0",
        "alpha0_start",
        "status",
        "message",
        "time",
        "energy",
        "bob2_x",
    ]


@pytest.mark.parametrize(
    "args, message",
    [
        (["--grid", "l0=5,x"], "argument --grid: 'x' is not a number"),
        (["--grid", "l0"], "argument --grid: 'l0': expected NAME=V1,V2,..."),
        (["--random", "l0=5"], "argument --random: 'l0=5': expected NAME=LOW:HIGH"),
        (["--random", "l0=5:15"], "--random needs --samples"),
        (["--random", "l0=15:5", "--samples", "3"], "l0 range 15.0:5.0 must be finite with low <= high"),
        (["--grid", "l0=5", "--random", "l1=1:2"], "not allowed with argument"),
        (["--grid", "l0=5", "--grid", "l0=6"], "a variable is given twice"),
        (["--grid", "length=5"], "unknown variable(s) length: ConicalPendulum has no such variable"),
        (["--grid", "energy=1"], "energy cannot be set"),
        (["--grid", "solver=1.5"], "solver = 1.5: solver is an Enumeration variable"),
        (["--grid", "l0=5", "--outputs", "energy,bob9_x"], "unknown output(s) bob9_x"),
        (["--grid", "l0=5", "--interval", "0"], "must be positive"),
        (["--grid", "l0=5", "--loop", "python"], "argument --loop: invalid choice: 'python'"),
        (["--grid", "l0=5", "--workers", "0"], "argument --workers: '0': expected a whole number"),
        (["--grid", "l0=5", "--out", "missing/s.parquet"], "out: missing is not a directory"),
        (
            ["--grid", "l0=5", "--resume", "--overwrite"],
            "argument --overwrite: not allowed with argument --resume",
        ),
        (
            ["--grid", "l0=5", "--scheduler", "tcp://127.0.0.1:1", "--workers", "2"],
            "--workers is for the local",
        ),
        (["--grid", "l0=5", "--scheduler", "127.0.0.1"], "scheduler '127.0.0.1': cannot connect"),
        (
            ["--grid", "l0=5", "--scheduler", "tcp://127.0.0.1:1", "--connect-timeout", "1"],
            "scheduler 'tcp://127.0.0.1:1': cannot connect (Timed out",
        ),
    ],
)
def test_command_refuses_what_it_cannot_run(seed_fmu, tmp_path, args, message):
    run = command(seed_fmu, *args, cwd=tmp_path)
    assert run.returncode == 2
    assert message in run.stderr
    assert run.stderr.startswith("conical-pendulum sweep: ") and run.stderr.count("\n") == 1  # one line
    assert "Traceback" not in run.stderr
    assert not list(tmp_path.iterdir())


def test_command_refuses_a_missing_fmu(tmp_path):
    run = command("Missing.fmu", "--grid", "l0=5", cwd=tmp_path)
    assert run.returncode == 2
    assert run.stderr.count("\n") == 1
    assert "Missing.fmu: cannot read the FMU (No such file or directory)" in run.stderr
    assert "Traceback" not in run.stderr


@pytest.fixture(scope="module")
def crashing_fmu(tmp_path_factory):
    """The shapes FMU (tests/shapes_fmu.c): with mode = 4 its step past fail_at segfaults."""
    return build_shapes_fmus(tmp_path_factory.mktemp("shapes"))[True]


def test_a_run_that_kills_its_worker_costs_one_row(crashing_fmu, tmp_path):
    """Runs 3 and 6 segfault their worker: each kills it twice (in its batch, then alone), is
    failed with the signal, and every other run of their batches completes."""
    runs = [
        {"gain": 1.0 + k, "mode": MODES["segfault"] if k in (3, 6) else 0, "fail_at": 0.5} for k in range(10)
    ]
    start = time.perf_counter()
    handle = sweep(
        crashing_fmu, runs, stop_time=1.0, output_interval=0.25, batch=4, progress=False, out=tmp_path / "s"
    )
    seconds = time.perf_counter() - start
    results = handle.to_pandas()
    runs_done = by_run(results)
    assert list(runs_done.index) == list(range(10))
    assert [k for k in range(10) if runs_done.loc[k, "status"] == "failed"] == [3, 6]
    for k in (3, 6):
        crashed = results[results["run"] == k]
        assert len(crashed) == 1 and crashed["time"].isna().all() and crashed["x"].isna().all()
        assert crashed["message"].iat[0] == (
            "the worker process died running this run, twice (SIGSEGV, segmentation fault)"
        )
    ok = results[~results["run"].isin([3, 6])]
    assert ok.groupby("run")["time"].apply(list).eq([[0.0, 0.25, 0.5, 0.75, 1.0]] * 8).all()
    # x = gain * sum of h (1 + t) over the steps: the runs' own values, none mixed up
    expected = {k: (1.0 + k) * 0.25 * sum(1 + 0.25 * step for step in range(4)) for k in range(10)}
    last = ok.groupby("run")["x"].last()
    assert all(math.isclose(last[k], expected[k]) for k in last.index)
    print(f"10 runs, 2 segfaulting, on 2 workers: {seconds:.1f} s")


def test_the_command_reports_a_crashing_run_and_exits_1(crashing_fmu, tmp_path):
    run = command(
        crashing_fmu,
        "--grid",
        "mode=0,4",
        "--grid",
        "fail_at=0.5",
        "--grid",
        "gain=1,2",
        "--stop-time",
        "1",
        "--interval",
        "0.5",
        "--out",
        tmp_path / "s.parquet",
        cwd=tmp_path,
    )
    assert run.returncode == 1, run.stderr
    assert "4 runs (2 failed), 8 rows" in run.stdout
    assert (
        "run 2 (mode = 4, fail_at = 0.5, gain = 1) failed: the worker process died running this run, "
        "twice (SIGSEGV, segmentation fault)" in run.stdout
    )
    assert "Traceback" not in run.stderr and "KilledWorker" not in run.stderr


def interrupted_after(batches: int, monkeypatch):
    """Ctrl-C, as the client's main thread gets it, once that many batches are written."""
    add = client_loop.Progress.add
    calls = []

    def interrupting(self, runs, failed):
        add(self, runs, failed)
        calls.append(runs)
        if len(calls) == batches:
            raise KeyboardInterrupt

    monkeypatch.setattr(client_loop.Progress, "add", interrupting)


def test_an_interrupted_sweep_resumes_to_the_same_dataset(seed_fmu, cluster, tmp_path, monkeypatch):
    runs = random_samples({"l0": (5, 15), "alpha0": (-1, 1)}, 30, seed=5) + [{"l0": -1.0}]
    settings = {
        "stop_time": 1.0,
        "output_interval": 0.1,
        "batch": 2,
        "scheduler": cluster.scheduler_address,
        "progress": False,
    }
    whole = sweep(seed_fmu, runs, out=tmp_path / "whole", **settings).to_pandas()
    out = tmp_path / "resumed"
    monkeypatch.setattr(dataset, "PART_SECONDS", 0.0)
    with monkeypatch.context() as interrupt:
        interrupted_after(5, interrupt)
        with pytest.raises(KeyboardInterrupt):
            sweep(seed_fmu, runs, out=out, **settings)
    first = SweepResults(out)
    assert 10 <= first.done() < 31 and not list(out.glob(".*.tmp"))
    with pytest.raises(ValueError, match=r"holds a sweep already; --resume \(resume=True\) finishes it"):
        sweep(seed_fmu, runs, out=out, **settings)
    resumed = sweep(seed_fmu, runs, out=out, resume=True, **settings)
    assert resumed.done() == 31 and resumed.rows() == len(whole)
    pd.testing.assert_frame_equal(resumed.to_pandas(), whole)  # nothing twice, nothing missing
    again = sweep(seed_fmu, runs, out=out, resume=True, **settings)  # nothing left: nothing run
    pd.testing.assert_frame_equal(again.to_pandas(), whole)


def test_a_killed_command_resumes_to_the_same_dataset(seed_fmu, cluster, tmp_path):
    """The client killed (SIGKILL) with files written: the same command with --resume ends it."""
    args = ["--grid", "l0=5,6,7,8,9,10,11,12", "--grid", "alpha0=0.1,0.2,0.3,0.4", "--stop-time", "2"]
    args += ["--interval", "0.1", "--outputs", "energy,bob2_x", "--batch", "1", "--workers", "1"]
    out = tmp_path / "s.parquet"
    script = (
        "import sys; from conical_pendulum.analysis.sweep import dataset; dataset.PART_SECONDS = 0.0; "
        "from conical_pendulum.cli import main; sys.exit(main(sys.argv[1:]))"
    )
    killed_scratch = tmp_path / "tmp"  # what a client killed outright cannot remove: not in /tmp
    killed_scratch.mkdir()
    client = subprocess.Popen(
        [sys.executable, "-c", script, "sweep", seed_fmu, *args, "--out", out, "--no-progress"],
        cwd=tmp_path,
        env={**os.environ, "TMPDIR": str(killed_scratch)},
    )
    deadline = time.monotonic() + 240
    while len(list(out.glob("part-*.parquet"))) < 3 and client.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    os.kill(client.pid, signal.SIGKILL)
    client.wait()
    kept = SweepResults(out).done()
    assert 3 <= kept < 32, kept
    run = command(seed_fmu, *args, "--out", out, "--resume", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert f"wrote {out}: 32 runs (0 failed), 672 rows" in run.stdout
    runs = grid({"l0": [5, 6, 7, 8, 9, 10, 11, 12], "alpha0": [0.1, 0.2, 0.3, 0.4]})
    whole = sweep(
        seed_fmu,
        [{name: float(value) for name, value in one.items()} for one in runs],
        stop_time=2.0,
        output_interval=0.1,
        outputs=["energy", "bob2_x"],
        scheduler=cluster.scheduler_address,
        progress=False,
        out=tmp_path / "whole",
    )
    pd.testing.assert_frame_equal(SweepResults(out).to_pandas(), whole.to_pandas())


def test_a_sweep_with_other_arguments_is_not_resumed(seed_fmu, native_seed_fmu, cluster, tmp_path):
    out = tmp_path / "s.parquet"
    runs = grid({"l0": [5.0, 6.0]})
    settings = {
        "stop_time": 0.5,
        "output_interval": 0.25,
        "outputs": ["energy"],
        "progress": False,
        "resume": True,
    }
    sweep(seed_fmu, runs, out=out, scheduler=cluster.scheduler_address, **settings)
    before = sorted(path.name for path in out.iterdir())
    for fmu, other_runs, changed, message in [
        (
            native_seed_fmu,
            runs,
            {},
            r"another FMU \(ConicalPendulum sha256 \w{12} there, ConicalPendulum \w{12} here\)",
        ),
        (seed_fmu, runs, {"stop_time": 1.0}, "stop time 0.5 there, 1.0 here"),
        (seed_fmu, runs, {"outputs": ["energy", "bob2_x"]}, "outputs energy there, energy,bob2_x here"),
        (
            seed_fmu,
            grid({"l0": [5.0, 7.0]}),
            {},
            r"other values of the runs \(another grid, ranges, samples or seed\)",
        ),
        (seed_fmu, grid({"l0": [5.0, 6.0, 7.0]}), {}, "runs 2 there, 3 here"),
        (seed_fmu, grid({"g": [9.0, 9.5]}), {}, "variables set l0 there, g here"),
    ]:
        with pytest.raises(ValueError, match=f"out: {out} holds another sweep, not resumed: {message}"):
            sweep(fmu, other_runs, out=out, **{**settings, **changed})
    assert sorted(path.name for path in out.iterdir()) == before  # never mixed, nothing removed
    overwritten = sweep(
        seed_fmu,
        runs,
        out=out,
        scheduler=cluster.scheduler_address,
        **{**settings, "resume": False, "overwrite": True, "stop_time": 1.0},
    )
    assert overwritten.attrs["stop_time"] == 1.0 and overwritten.rows() == 10


def test_the_command_refuses_an_existing_sweep_and_says_how_to_go_on(seed_fmu, tmp_path):
    (tmp_path / "s.parquet").mkdir()
    (tmp_path / "s.parquet" / "_sweep.json").write_text("{}")
    run = command(seed_fmu, "--grid", "l0=5", "--out", "s.parquet", cwd=tmp_path)
    assert run.returncode == 2 and run.stderr.count("\n") == 1
    assert (
        "out: s.parquet holds a sweep already; --resume (resume=True) finishes it, --overwrite" in run.stderr
    )
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("mine")
    run = command(seed_fmu, "--grid", "l0=5", "--out", "other", "--overwrite", cwd=tmp_path)
    assert (
        run.returncode == 2 and "out: other is a folder that holds no sweep; give another name" in run.stderr
    )
    assert (tmp_path / "other" / "notes.txt").read_text() == "mine"


# Sweeps that never hang (issue 39): before, a local cluster lost every worker when runs
# crashed every few seconds (SpecCluster's lost-worker timer closed nannies that were
# restarting them), and the client waited forever: 15 all-crashing runs on one worker hung
# in 4 of 4 tries. Each case runs the command with a time limit, in a temporary directory
# of its own (TMPDIR, the workers' too) that must be empty afterwards.
CRASH_LIMIT = 600  # seconds: a hang fails the test, a loaded machine does not
SEGFAULTED = "the worker process died running this run, twice (SIGSEGV, segmentation fault)"


def isolated_command(fmu, *args, tmp_path, env=None):
    """`conical-pendulum sweep FMU ARGS --out s.parquet` with TMPDIR a fresh folder."""
    temporary = tmp_path / "tmp"
    temporary.mkdir(exist_ok=True)
    out = tmp_path / "s.parquet"
    run = subprocess.run(
        [str(Path(sys.executable).with_name("conical-pendulum")), "sweep", str(fmu), *map(str, args)]
        + ["--out", str(out), "--no-progress", "--overwrite"],
        cwd=tmp_path,
        env={**os.environ, "TMPDIR": str(temporary), **(env or {})},
        stdin=subprocess.DEVNULL,
        check=False,
        capture_output=True,
        text=True,
        timeout=CRASH_LIMIT,
    )
    return run, SweepResults(out) if (out / "_sweep.json").exists() else None, temporary


def crashing_runs(samples: int, crash_below: float, seed: int = 2) -> list:
    """The shapes FMU as the issue's Crash.fmu, a parameter above a threshold crashing it:
    each run segfaults past t = fail_at, drawn from 0 to `crash_below`, and stops at 1 s:
    below 1, every run crashes; with 10, about a tenth."""
    return ["--random", "mode=4:4", "--random", f"fail_at=0:{crash_below}", "--random", "gain=0:1"] + [
        "--samples",
        samples,
        "--seed",
        seed,
        "--stop-time",
        "1",
        "--interval",
        "0.01",
    ]


def check_crashing_sweep(run, results, temporary, samples: int):
    """Exit status 1, every run once, each crashing run failed naming SIGSEGV, nothing left."""
    assert run.returncode == 1, run.stderr
    assert f"{samples} runs (" in run.stdout and "Traceback" not in run.stderr
    frame = results.to_pandas(["status", "message", "fail_at", "time"])
    assert results.done() == samples and sorted(frame["run"].unique()) == list(range(samples))
    first = frame.drop_duplicates("run").set_index("run")
    crashing = first["fail_at"] < 1  # a step, the last ending at 1 s, reaches past fail_at
    assert (first.loc[crashing, "message"] == SEGFAULTED).all()
    assert (first.loc[~crashing, "status"] == "ok").all()
    assert (frame[frame["run"].isin(first.index[crashing])].groupby("run").size() == 1).all()
    assert (frame[frame["run"].isin(first.index[~crashing])].groupby("run").size() == 101).all()
    assert sorted(path.name for path in temporary.iterdir()) == []  # no FMU, note nor scratch left
    return int(crashing.sum())


@pytest.mark.parametrize(
    "samples, workers",
    [
        (15, 1),
        (30, 2),
        pytest.param(15, 2, marks=pytest.mark.slow),
        pytest.param(30, 1, marks=pytest.mark.slow),
    ],
)
def test_every_run_crashing_finishes(crashing_fmu, tmp_path, samples, workers):
    """Each crashing run costs about two worker restarts (some 2 to 4 s here): 15 runs on
    one worker about 2 minutes on the loaded machine; the other pairs are long checks."""
    run, results, temporary = isolated_command(
        crashing_fmu, *crashing_runs(samples, 0.9), "--workers", workers, tmp_path=tmp_path
    )
    assert check_crashing_sweep(run, results, temporary, samples) == samples
    assert f"{samples} runs ({samples} failed)" in run.stdout


def test_three_hundred_runs_a_tenth_crashing_finish(crashing_fmu, tmp_path):
    run, results, temporary = isolated_command(crashing_fmu, *crashing_runs(300, 10.0), tmp_path=tmp_path)
    crashed = check_crashing_sweep(run, results, temporary, 300)
    assert 15 <= crashed <= 45  # about a tenth, seed 2


@pytest.mark.slow
@pytest.mark.parametrize("seed", [3, 4, 5])
@pytest.mark.parametrize("samples, workers, crash_below", [(15, 1, 0.9), (30, 2, 0.9), (300, 2, 10.0)])
def test_crashing_sweeps_finish_every_time(crashing_fmu, tmp_path, samples, workers, crash_below, seed):
    """The race struck 4 of 4 tries: the cases again, with other runs."""
    run, results, temporary = isolated_command(
        crashing_fmu, *crashing_runs(samples, crash_below, seed), "--workers", workers, tmp_path=tmp_path
    )
    check_crashing_sweep(run, results, temporary, samples)


@pytest.fixture
def running_cluster(tmp_path):
    """A cluster as a user starts one: `dask scheduler` and `dask worker --nanny` (two
    workers of one thread) processes, with TMPDIR a fresh folder; stopped after."""
    dask = str(Path(sys.executable).with_name("dask"))
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    address_file = tmp_path / "scheduler.json"
    # the scheduler tells the client of a task whose worker died at once, as a local cluster does
    env = {**os.environ, "TMPDIR": str(temporary), "DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES": "0"}
    started = [
        subprocess.Popen(
            [dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard"]
            + ["--scheduler-file", str(address_file)],
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    ]
    try:
        deadline = time.monotonic() + 120
        while not address_file.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        started.append(
            subprocess.Popen(
                [dask, "worker", "--nanny", "--nworkers", "2", "--nthreads", "1", "--no-dashboard"]
                + ["--scheduler-file", str(address_file)],
                env=env,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
        )
        with Client(scheduler_file=str(address_file), timeout=120) as client:
            client.wait_for_workers(2, timeout=120)
            yield client.scheduler.address, temporary
    finally:
        for process in reversed(started):
            process.terminate()
            try:
                process.wait(timeout=60)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()


def test_crashing_runs_on_a_running_cluster(crashing_fmu, running_cluster, tmp_path):
    address, temporary = running_cluster
    client = tmp_path / "client"
    client.mkdir()
    run, results, client_temporary = isolated_command(
        crashing_fmu, *crashing_runs(20, 2.0), "--scheduler", address, tmp_path=client
    )
    check_crashing_sweep(run, results, client_temporary, 20)
    # the workers' host: their notes and extracted FMUs removed; Dask's own scratch space stays
    assert [path.name for path in temporary.iterdir() if path.name != "dask-scratch-space"] == []


def test_a_stuck_run_is_ended_after_the_run_timeout(crashing_fmu, tmp_path):
    """A doStep that never returns (mode 5): its worker process ended after --run-timeout,
    the run failed saying so, at the cost of one timeout, and the other runs done."""
    args = ["--grid", "mode=0,5,0,0,0,0", "--grid", "fail_at=0.5", "--stop-time", "1", "--interval", "0.25"]
    start = time.monotonic()
    run, results, temporary = isolated_command(
        crashing_fmu, *args, "--run-timeout", "5", "--batch", "3", "--workers", "2", tmp_path=tmp_path
    )
    seconds = time.monotonic() - start
    assert run.returncode == 1, run.stderr
    failed = results.failed()
    assert list(failed.index) == [1]
    assert failed.loc[1, "message"] == "exceeded 5 s: its worker process was ended (SIGKILL)"
    assert "6 runs (1 failed), 26 rows" in run.stdout  # five runs of 5 rows, one row for the stuck one
    assert sorted(path.name for path in temporary.iterdir()) == []
    print(f"6 runs, one stuck, --run-timeout 5, 2 workers: {seconds:.1f} s")


def test_a_run_timeout_needs_nannies(crashing_fmu, tmp_path):
    with (
        LocalCluster(n_workers=1, processes=False, dashboard_address="127.0.0.1:0") as in_process,
        pytest.raises(ValueError, match=r"run timeout 5 s: the cluster's workers have no nanny"),
    ):
        sweep(
            crashing_fmu,
            [{"gain": 1.0}],
            scheduler=in_process.scheduler_address,
            run_timeout=5,
            progress=False,
            out=tmp_path / "s",
        )


def test_a_cluster_without_workers_stops_the_sweep_resumably(crashing_fmu, tmp_path):
    """The workers gone for good (scaled to none, while a run is stuck): the sweep stops once
    no worker has been alive for no_workers_timeout s, saying how to finish it."""
    runs = [{"gain": 1.0, "mode": 0}, {"gain": 2.0, "mode": MODES["stuck"], "fail_at": 0.5}]
    with LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address="127.0.0.1:0") as doomed:
        stopping = threading.Timer(10, doomed.scale, [0])  # long after the first run
        stopping.start()
        start = time.monotonic()
        try:
            with pytest.raises(ConnectionError) as stopped:
                sweep(
                    crashing_fmu,
                    runs,
                    stop_time=1.0,
                    output_interval=0.5,
                    batch=1,
                    scheduler=doomed.scheduler_address,
                    no_workers_timeout=3,
                    progress=False,
                    out=tmp_path / "s",
                )
        finally:
            stopping.cancel()
    assert str(stopped.value) == (
        f"no worker alive for 3 s; the runs done are kept in {tmp_path / 's'}: "
        "run again with --resume (resume=True) to finish"
    )
    assert time.monotonic() - start < 120
    assert SweepResults(tmp_path / "s").done() == 1


def test_a_local_cluster_replaces_a_nanny_that_closed():
    """A nanny the cluster closed (as SpecCluster's lost-worker timer did) is started anew
    while the client watches the workers."""
    with clusters.connect(None, 1, 10) as client:
        (nanny,) = client.cluster.workers.values()
        client.cluster.sync(nanny.close)
        assert not client.nthreads()
        watch = clusters.Workers(client, patience=300)
        deadline = time.monotonic() + 120
        while not client.nthreads() and time.monotonic() < deadline:
            watch.check(every=0)
            time.sleep(0.5)
        assert client.nthreads() and nanny not in client.cluster.workers.values()


WORKER_KILLED_LAST = """
import os, signal
from distributed.scheduler import KilledWorker
from conical_pendulum.analysis.sweep import cluster

def crash():
    os.kill(os.getpid(), signal.SIGSEGV)

if __name__ == "__main__":
    with cluster.connect(None, 1, 10) as client:
        for _ in range(2):  # as a run that killed its worker twice, the sweep's last
            try:
                client.submit(crash, pure=False).result()
            except KilledWorker:
                pass
"""


def test_a_cluster_closes_clean_after_its_last_task_killed_the_worker(tmp_path):
    """The sweep's end just after a run killed its worker, while the nanny starts the next:
    closing then stopped that worker half-started, and its process printed Dask's
    "ConnectionPool is closed" traceback in about 1 of 3 tries (6 of 19 here), 0 of 30 since
    connect() waits for the restart (at most cluster.SETTLE_SECONDS)."""
    script = tmp_path / "last_task_killed.py"
    script.write_text(WORKER_KILLED_LAST)
    for _ in range(8):
        run = subprocess.run(
            [sys.executable, str(script)],
            cwd=tmp_path,
            env={**os.environ, "TMPDIR": str(tmp_path)},
            stdin=subprocess.DEVNULL,
            capture_output=True,
            text=True,
            timeout=CRASH_LIMIT,
            check=False,
        )
        assert run.returncode == 0 and "Traceback" not in run.stderr, run.stderr
