"""The `conical-pendulum` command: its help, check, page, and one-line refusals of bad options."""
import json
import signal
import subprocess
import sys
import urllib.request
from pathlib import Path

import pytest

from conical_pendulum.cli import COMMANDS, main

COMMAND = str(Path(sys.executable).with_name("conical-pendulum"))  # the installed console script
NAMES = ["build", "check", "show", "page", "sweep", "demo"]


def cli(*args, cwd=None, timeout=300):
    return subprocess.run([COMMAND, *map(str, args)], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout)


def test_help_lists_every_command_with_a_summary_and_an_example():
    run = cli("--help")
    assert run.returncode == 0, run.stderr
    assert list(COMMANDS) == NAMES
    lines = run.stdout.splitlines()
    for name in NAMES:
        row = next(i for i, line in enumerate(lines) if line.split()[:1] == [name])
        assert lines[row].split(None, 1)[1] == COMMANDS[name].summary  # the one-line summary
        assert lines[row + 1].strip().startswith(f"$ conical-pendulum {name} ")  # and an example
    assert "conical-pendulum COMMAND --help" in run.stdout


def test_python_m_runs_the_same_command():
    run = subprocess.run([sys.executable, "-m", "conical_pendulum", "--help"], capture_output=True,
                         text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith("usage: python -m conical_pendulum ")
    assert all(f"\n    {name} " in run.stdout for name in NAMES)


@pytest.mark.parametrize("name, options", [
    ("build", ["--links", "--scene", "--output", "--no-check", "--coupling", "--native"]),
    ("check", ["FMU", "--stop-time", "--interval", "--rtol"]),
    ("show", ["--plot", "--gif", "--fps"]),
    ("page", ["FMU", "--out", "--stop-time", "--start NAME=VALUE", "--serve", "--port"]),
    ("sweep", ["--grid", "--random", "--samples", "--workers", "--scheduler", "--out"]),
    ("demo", ["--out", "--steps", "--stop-time", "--cart-mass"]),
])
def test_each_command_explains_its_options(name, options):
    run = cli(name, "--help")
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith(f"usage: conical-pendulum {name} ")
    assert all(option in run.stdout for option in options), run.stdout
    assert "Traceback" not in run.stderr


@pytest.mark.slow
def test_build_checks_and_draws_the_run(tmp_path):
    """Without --no-check: the fmpy run against the native reference, then results.csv,
    pendulum.png and pendulum.gif next to the FMU (about 25 s, most of it the GIF)."""
    run = cli("build", "--links", "1", "--output", tmp_path / "One.fmu", timeout=600)
    assert run.returncode == 0, run.stderr
    assert f"built {tmp_path / 'One.fmu'}" in run.stdout and "1 links" in run.stdout
    assert "angles agree to" in run.stdout and run.stdout.count(": OK") == 1
    assert f"wrote {tmp_path / 'results.csv'}, {tmp_path / 'pendulum.png'} and {tmp_path / 'pendulum.gif'}" \
        in run.stdout
    assert all((tmp_path / name).stat().st_size > 10_000 for name in ("results.csv", "pendulum.png", "pendulum.gif"))


def test_check_passes_on_the_seed_fmu(seed_fmu):
    run = cli("check", seed_fmu, "--stop-time", "2")
    assert run.returncode == 0, run.stderr
    assert "fmpy.simulate_fmu, 2 s at 60 outputs/s, DOP853 rtol = atol = 1e-12" in run.stdout
    assert "energy" in run.stdout  # every output's difference
    agree = run.stdout.strip().splitlines()[-1]
    assert agree.startswith("angles agree to ") and agree.endswith(" rad: OK")
    assert float(agree.split()[3]) < 1e-10


def test_check_fails_when_the_fmu_is_run_loosely(seed_fmu):
    """rtol 1e-3 with an output a second: the angles are off by far more than 1e-8."""
    run = cli("check", seed_fmu, "--rtol", "1e-3", "--interval", "1")
    assert run.returncode == 1, run.stderr
    assert run.stdout.strip().endswith("rad: FAILED")


def test_page_writes_the_pydy_page(seed_fmu, tmp_path):
    run = cli("page", seed_fmu, "--out", tmp_path, "--stop-time", "1", "--start", "alpha0=0.5",
              "--start", "l0=8")
    assert run.returncode == 0, run.stderr
    folder = tmp_path / "pydy-resources"
    assert f"into {folder}" in run.stdout
    assert "http://127.0.0.1:8000/index.html?load=conical_pendulum_scene_desc.json" in run.stdout
    assert (folder / "index.html").exists()
    scene = json.loads((folder / "conical_pendulum_scene_desc.json").read_text())
    assert {o["name"] for o in scene["objects"].values()} == {
        "link0", "link1", "link2", "bob0", "bob1", "bob2"}
    data = json.loads((folder / "conical_pendulum_simulation_data.json").read_text())
    assert len(next(iter(data.values()))) == 61  # 1 s at 60 outputs/s, both ends


def test_page_serves_until_interrupted(seed_fmu, tmp_path):
    server = subprocess.Popen([COMMAND, "page", str(seed_fmu), "--out", str(tmp_path), "--stop-time", "0.5",
                               "--serve", "--port", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True)
    try:
        lines = []
        while not lines or not lines[-1].startswith("Ctrl-C"):
            line = server.stdout.readline()
            assert line, server.stderr.read()
            lines.append(line.strip())
        address = next(line for line in lines if line.startswith("http://127.0.0.1:"))
        with urllib.request.urlopen(address, timeout=10) as page:
            assert page.status == 200 and b"<html" in page.read().lower()
        root = address.split("index.html")[0]
        with urllib.request.urlopen(root + "conical_pendulum_scene_desc.json", timeout=10) as desc:
            assert json.load(desc)["source"] == "PyDy"
    finally:
        server.send_signal(signal.SIGINT)
        out, err = server.communicate(timeout=30)
    assert server.returncode == 0, err
    assert "stopped" in out and "Traceback" not in err


@pytest.mark.parametrize("args, message", [
    (["frobnicate"], "conical-pendulum: argument COMMAND: invalid choice: 'frobnicate'"),
    ([], "conical-pendulum: the following arguments are required: COMMAND"),
    (["check", "missing.fmu"], "conical-pendulum check: missing.fmu: not an FMU built by conical_pendulum"),
    (["check", "FMU", "--stop-time", "-1"], "conical-pendulum check: --stop-time: must be a positive number, got -1"),
    (["check", "FMU", "--rtol", "x"], "conical-pendulum check: argument --rtol: invalid float value: 'x'"),
    (["check", "FMU", "--frobnicate", "3"], "conical-pendulum check: unrecognized arguments: --frobnicate 3"),
    (["page", "FMU", "--out", "page", "--start", "length=3"],
     "conical-pendulum page: --start length=3: the FMU has no variable 'length'"),
    (["page", "FMU", "--out", "page", "--start", "energy=3"], "--start energy=3: energy is calculated"),
    (["page", "FMU", "--out", "page", "--start", "alpha0"],
     "conical-pendulum page: argument --start: 'alpha0': expected NAME=NUMBER"),
    (["page", "FMU", "--out", "page", "--start", "solver=0.5"], "--start solver=0.5: solver is an Integer"),
    (["page", "FMU"], "conical-pendulum page: the following arguments are required: --out"),
    (["page", "FMU", "--out", "page", "--port", "70000"], "--port: 70000 is not a port number"),
    (["show", "RESULTS"], "conical-pendulum show: give --plot and/or --gif"),
    (["show", "RESULTS", "--plot", "p.png", "--fps", "0"], "conical-pendulum show: --fps: must be positive, got 0"),
    (["sweep", "FMU", "--grid", "l0=5,x"], "conical-pendulum sweep: argument --grid: 'x' is not a number"),
    (["sweep", "FMU"], "conical-pendulum sweep: one of the arguments --grid --random is required"),
    (["demo", "--steps", "0.1,x"], "conical-pendulum demo: argument --steps: expected numbers"),
    (["build", "--links", "0"], "conical-pendulum build: links: 0 is out of range"),
])
def test_bad_options_are_one_line_and_exit_2(seed_fmu, tmp_path, args, message):
    results = tmp_path / "results.csv"
    results.write_text("time,alpha0\n0,0\n")
    run = cli(*[{"FMU": seed_fmu, "RESULTS": results}.get(a, a) for a in args], cwd=tmp_path)
    assert run.returncode == 2, run.stdout
    assert message in run.stderr
    assert run.stderr.count("\n") == 1  # one line, not the usage block
    assert "Traceback" not in run.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.csv"]  # nothing written


def test_in_process_a_bad_option_is_returned_not_raised(capsys):
    assert main(["check", "--interval", "0", "missing.fmu"]) == 2
    assert capsys.readouterr().err == "conical-pendulum check: --interval: must be a positive number, got 0\n"
