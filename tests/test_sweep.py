"""conical_pendulum.analysis.sweep: Dask runs equal to fmpy's one by one, failures kept with their
messages, one Parquet file, the FMU loaded once per worker, and a command that refuses
what it cannot run."""

import logging
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from distributed import Client, LocalCluster

from conical_pendulum.analysis import runner
from conical_pendulum.analysis import sweep as sweep_module
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.analysis.sweep import LoadedFmu, grid, random_samples, sweep

# a start that needs more than 25 internal steps in the communication step from 1.5 s to 2 s
DISCARDED_AT_1_5 = {"alpha0": 1.2, "delta2": 3.0, "max_steps": 25}


@pytest.fixture(scope="module")
def cluster():
    """An existing cluster, as `scheduler=` reaches one; its workers run two tasks at once."""
    with LocalCluster(n_workers=2, threads_per_worker=2, dashboard_address="127.0.0.1:0") as cluster:
        yield cluster


def by_run(results):
    return results.drop_duplicates("run").set_index("run")


def test_runs_equal_fmpy_one_by_one(seed_fmu):
    runs = random_samples(
        {"l0": (5, 15), "m1": (1, 10), "alpha0": (-1, 1), "beta2": (-0.5, 0.5), "delta1": (-2, 2)},
        100,
        seed=7,
    )
    results = sweep(seed_fmu, runs, n_workers=2, progress=False)
    assert (results["status"] == "ok").all() and (results["message"] == "").all()
    inputs = by_run(results)[["l0", "m1", "alpha0_start", "beta2_start", "delta1_start"]]
    assert inputs.rename(columns=lambda name: name.removesuffix("_start")).to_dict("records") == runs
    for index, run in enumerate(runs):
        got = results[results["run"] == index]
        expected = run_fmu(seed_fmu, start_values=run)
        for name in ["time", *results.attrs["outputs"]]:
            assert np.array_equal(got[name].to_numpy(), expected[name]), (index, name)


def test_both_loops_give_the_same_file_on_a_running_cluster(native_seed_fmu, cluster):
    runs = random_samples({"l0": (5, 15), "alpha0": (-1, 1)}, 12, seed=2) + [{"l0": -1.0}, DISCARDED_AT_1_5]
    results = {
        loop: sweep(
            native_seed_fmu,
            runs,
            output_interval=0.5,
            scheduler=cluster.scheduler_address,
            progress=False,
            loop=loop,
        )
        for loop in ("runner", "fmpy")
    }
    # the native FMU's discard ends in fmi2Error at the next step: only the runner keeps rows
    kept = {loop: frame[frame["run"] == 13] for loop, frame in results.items()}
    assert list(kept["runner"]["time"]) == [0.0, 0.5, 1.0, 1.5] and kept["fmpy"]["time"].isna().all()
    assert kept["runner"]["message"].iat[0] == kept["fmpy"]["message"].iat[0]
    pd.testing.assert_frame_equal(*(frame[frame["run"] != 13] for frame in results.values()))
    assert list(by_run(results["runner"])["status"]) == ["ok"] * 12 + ["failed"] * 2


def test_a_worker_without_the_runner_uses_fmpys_loop_and_says_why(seed_fmu, monkeypatch, caplog):
    monkeypatch.setattr(runner, "unavailable", lambda: "no C compiler cc")
    with (
        LocalCluster(n_workers=1, processes=False, dashboard_address="127.0.0.1:0") as in_process,
        caplog.at_level(logging.WARNING, logger="conical_pendulum.analysis.sweep"),
    ):
        results = sweep(
            seed_fmu, [{"l0": 5.0}], stop_time=1.0, scheduler=in_process.scheduler_address, progress=False
        )
    assert (results["status"] == "ok").all()
    assert "runs fmpy's loop, not the compiled runner: no C compiler cc" in caplog.text
    assert "ConicalPendulum: fmpy's loop instead of the compiled runner: no C compiler cc" in caplog.text


def test_a_refused_value_fails_only_its_run(seed_fmu, cluster):
    runs = grid({"l0": [5.0, 10.0], "alpha0": [0.2, 0.4]}) + [{"l0": -1.0}]
    results = sweep(
        seed_fmu,
        runs,
        stop_time=2.0,
        output_interval=0.5,
        scheduler=cluster.scheduler_address,
        progress=False,
    )
    inputs = by_run(results)
    assert list(inputs["status"]) == ["ok"] * 4 + ["failed"]
    assert inputs.loc[4, "alpha0_start"] == math.radians(10)  # left alone: the FMU's start value
    failed = results[results["run"] == 4]
    assert len(failed) == 1 and np.isnan(failed["time"]).all() and np.isnan(failed["energy"]).all()
    assert "l0 = -1.0: a length must be positive" in failed["message"].iat[0]
    ok = results[results["run"] < 4]
    assert ok.groupby("run")["time"].max().eq(2.0).all() and not ok["energy"].isna().any()


@pytest.mark.parametrize("backend", ["pythonfmu", "native"])
def test_a_discarded_step_fails_the_run_with_the_rows_before(backend, seed_fmu, native_seed_fmu, cluster):
    """The native FMU's discard ends in fmi2Error at the next step (fmpy's loop keeps no rows
    then); the compiled runner keeps the rows before it, as pythonfmu's terminated run has."""
    fmu = seed_fmu if backend == "pythonfmu" else native_seed_fmu
    runs = [{"alpha0": 1.2, "delta2": 3.0}, DISCARDED_AT_1_5]
    results = sweep(fmu, runs, output_interval=0.5, scheduler=cluster.scheduler_address, progress=False)
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
        monkeypatch.setattr(sweep_module, "run_fmu", poisoned)
        rows, ok, message = fmu.run({}, 1.0, 0.1, ["energy", "bob2_x"])
        assert not ok and message == "non-finite values in energy"
    finally:
        fmu.close()


def test_the_file_round_trips(seed_fmu, cluster, tmp_path):
    out = tmp_path / "sweep.parquet"
    runs = grid({"l0": [5.0, -1.0], "solver": [1, 2], "beta1": [0.0, 0.3]})
    results = sweep(
        seed_fmu,
        runs,
        stop_time=1.0,
        output_interval=0.25,
        outputs=["energy", "bob2_x"],
        scheduler=cluster.scheduler_address,
        out=out,
        progress=False,
    )
    read = pd.read_parquet(out)
    pd.testing.assert_frame_equal(read, results)
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
    assert read.attrs == {
        "fmu": "ConicalPendulum",
        "fmu_guid": read.attrs["fmu_guid"],
        "stop_time": 1.0,
        "output_interval": 0.25,
        "outputs": ["energy", "bob2_x"],
        "inputs": ["l0", "solver", "beta1_start"],
    }
    inputs = by_run(read)
    assert inputs[["l0", "solver", "beta1_start"]].to_dict("records") == [
        {"l0": run["l0"], "solver": run["solver"], "beta1_start": run["beta1"]} for run in runs
    ]
    assert list(inputs["status"]) == ["ok"] * 4 + ["failed"] * 4
    assert read.groupby("run").size().tolist() == [5] * 4 + [1] * 4


def test_each_worker_loads_the_fmu_once(seed_fmu, cluster):
    with Client(cluster) as client:
        before = client.run(lambda: LoadedFmu.loads)
        results = sweep(
            seed_fmu,
            [{"l0": 5.0 + k} for k in range(40)],
            stop_time=1.0,
            batch=2,
            scheduler=cluster.scheduler_address,
            progress=False,
        )
        after = client.run(lambda: LoadedFmu.loads)
        left = client.run(lambda dask_worker: [name for name in dask_worker.plugins if "sweep" in name])
    assert (results["status"] == "ok").all() and results["run"].nunique() == 40  # in 20 tasks
    assert len(after) == 2 and all(after[worker] - before[worker] == 1 for worker in after)
    assert all(names == [] for names in left.values())  # unregistered: extracted files removed


def test_a_scheduler_without_workers_is_refused(seed_fmu):
    with (
        LocalCluster(n_workers=0, dashboard_address="127.0.0.1:0") as empty,
        pytest.raises(ConnectionError, match="no workers after 1 s"),
    ):
        sweep(seed_fmu, [{"l0": 5.0}], scheduler=empty.scheduler_address, timeout=1, progress=False)


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
        (["--grid", "solver=1.5"], "solver = 1.5: solver is an Integer variable"),
        (["--grid", "l0=5", "--outputs", "energy,bob9_x"], "unknown output(s) bob9_x"),
        (["--grid", "l0=5", "--interval", "0"], "must be positive"),
        (["--grid", "l0=5", "--loop", "python"], "argument --loop: invalid choice: 'python'"),
        (["--grid", "l0=5", "--workers", "0"], "argument --workers: '0': expected a whole number"),
        (["--grid", "l0=5", "--out", "missing/s.parquet"], "out: missing is not a directory"),
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
