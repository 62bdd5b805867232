"""The `conical-pendulum` command: its help, check, page, and one-line refusals of bad options."""

import importlib
import importlib.util
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import urllib.request
import zipfile
from pathlib import Path

import pytest

from conical_pendulum import errors
from conical_pendulum.cli import COMMANDS, main, run_command
from conical_pendulum.errors import install_command

COMMAND = str(Path(sys.executable).with_name("conical-pendulum"))  # the installed console script
NAMES = ["build", "check", "linearize", "show", "page", "sweep", "demo", "system"]


def cli(*args, cwd=None, timeout=300):
    return subprocess.run(
        [COMMAND, *map(str, args)], cwd=cwd, check=False, capture_output=True, text=True, timeout=timeout
    )


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
    run = subprocess.run(
        [sys.executable, "-m", "conical_pendulum", "--help"],
        check=False,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith("usage: python -m conical_pendulum ")
    assert all(f"\n    {name} " in run.stdout for name in NAMES)


@pytest.mark.parametrize(
    "name, options",
    [
        ("build", ["--links", "--scene", "--output", "--no-check", "--coupling", "--native"]),
        ("check", ["FMU", "--stop-time", "--interval", "--rtol"]),
        ("linearize", ["FMU", "--state NAME=VALUE", "--input", "--parameter", "--method", "--out", "--plot"]),
        ("show", ["--plot", "--gif", "--fps"]),
        ("page", ["FMU", "--out", "--stop-time", "--start NAME=VALUE", "--serve", "--port"]),
        ("sweep", ["--grid", "--random", "--samples", "--workers", "--scheduler", "--out"]),
        ("demo", ["--out", "--steps", "--stop-time", "--cart-mass"]),
        ("system", ["--out", "--cart-mass", "--step", "--stop-time", "--run", "SystemStructure.ssd"]),
    ],
)
def test_each_command_explains_its_options(name, options):
    run = cli(name, "--help")
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith(f"usage: conical-pendulum {name} ")
    assert all(option in run.stdout for option in options), run.stdout
    assert "Traceback" not in run.stderr


# what the extras (sweep, cosim, linear, test's pydy) add to the base install
EXTRAS_PACKAGES = ("dask", "distributed", "pandas", "pyarrow", "ecospy", "libcosimpy", "control", "pydy")


@pytest.mark.parametrize("name", NAMES)
def test_each_commands_help_works_with_the_base_install(name):
    """A user deciding whether to install an extra can read what the command does: --help
    lists its options without the extras, and a command that needs one says which."""
    hidden = "; ".join(f"sys.modules[{package!r}] = None" for package in EXTRAS_PACKAGES)
    run = subprocess.run(
        [
            sys.executable,
            "-c",
            f"import sys; {hidden}; from conical_pendulum.cli import main; sys.exit(main([{name!r}, '--help']))",
        ],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0 and run.stdout.startswith(f"usage: conical-pendulum {name} "), run.stderr
    assert "Traceback" not in run.stderr
    if name == "sweep":
        assert "--grid" in run.stdout and f"needs dask: {install_command('sweep')}" in run.stdout


@pytest.mark.slow
def test_build_checks_and_draws_the_run(tmp_path):
    """Without --no-check: the fmpy run against the native reference, then its CSV, plot and
    animation named after the FMU (25 s quiet, 105 s on a loaded machine, most of it the GIF)."""
    run = cli("build", "--links", "1", "--output", tmp_path / "One.fmu", timeout=600)
    assert run.returncode == 0, run.stderr
    assert f"built {tmp_path / 'One.fmu'}" in run.stdout and "1 links" in run.stdout
    assert "angles agree to" in run.stdout and run.stdout.count(": OK") == 1
    assert f"wrote {tmp_path / 'One.csv'}, {tmp_path / 'One.png'} and {tmp_path / 'One.gif'}" in run.stdout
    assert all((tmp_path / name).stat().st_size > 10_000 for name in ("One.csv", "One.png", "One.gif"))


def test_check_passes_on_the_seed_fmu(seed_fmu):
    run = cli("check", seed_fmu, "--stop-time", "2")
    assert run.returncode == 0, run.stderr
    assert "fmpy.simulate_fmu, 2 s at 60 outputs/s, DOP853 rtol = atol = 1e-12" in run.stdout
    assert "energy" in run.stdout  # every output's difference
    agree = run.stdout.strip().splitlines()[-1]
    assert agree.startswith("angles agree to ") and agree.endswith(" rad: OK")
    assert float(agree.split()[3]) < 1e-10


def test_check_fails_an_fmu_that_runs_another_parameter_value(seed_fmu, tmp_path):
    """The seed FMU with its scene's first link 1e-9 longer (relatively) than the FMU runs
    (its compiled variable table): 6e-10 rad off, which a fixed 1e-8 rad let through; the
    measured bound does not."""
    wrong = tmp_path / "Wrong.fmu"
    with zipfile.ZipFile(seed_fmu) as source, zipfile.ZipFile(wrong, "w") as target:
        for item in source.infolist():
            data = source.read(item)
            if item.filename == "resources/model.json":
                model = json.loads(data)
                model["scene"]["links"][0]["length"] *= 1 + 1e-9
                data = json.dumps(model)
            target.writestr(item, data)
    run = cli("check", wrong)
    assert run.returncode == 1, run.stderr
    lines = run.stdout.strip().splitlines()
    assert lines[-2].startswith("the bound: ") and "DOP853's error at the FMU's rtol 1e-12" in lines[-2]
    assert lines[-1].startswith("angles agree to ") and lines[-1].endswith(" rad: FAILED")
    assert float(lines[-1].split()[3]) > 10 * float(lines[-1].split()[-3])


def test_page_writes_the_pydy_page(seed_fmu, tmp_path):
    run = cli(
        "page", seed_fmu, "--out", tmp_path, "--stop-time", "1", "--start", "alpha0=0.5", "--start", "l0=8"
    )
    assert run.returncode == 0, run.stderr
    folder = tmp_path / "pydy-resources"
    assert f"into {folder}" in run.stdout
    assert "http://127.0.0.1:8000/index.html?load=conical_pendulum_scene_desc.json" in run.stdout
    assert (folder / "index.html").exists()
    scene = json.loads((folder / "conical_pendulum_scene_desc.json").read_text())
    assert {o["name"] for o in scene["objects"].values()} == {
        "link0",
        "link1",
        "link2",
        "bob0",
        "bob1",
        "bob2",
    }
    data = json.loads((folder / "conical_pendulum_simulation_data.json").read_text())
    assert len(next(iter(data.values()))) == 61  # 1 s at 60 outputs/s, both ends


def ignore_sigint():
    """In the child: SIGINT ignored, as a background job (`cmd &`) inherits it."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.mark.parametrize(
    "stop, started",
    [(signal.SIGINT, None), (signal.SIGINT, ignore_sigint), (signal.SIGTERM, ignore_sigint)],
    ids=["ctrl-c", "ctrl-c-in-background", "sigterm-in-background"],
)
def test_page_serves_until_interrupted(seed_fmu, tmp_path, stop, started):
    server = subprocess.Popen(
        [
            COMMAND,
            "page",
            str(seed_fmu),
            "--out",
            str(tmp_path),
            "--stop-time",
            "0.5",
            "--serve",
            "--port",
            "0",
        ],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=started,
    )
    bound = threading.Timer(240, server.kill)  # the reads below end, whatever the server does
    bound.daemon = True
    bound.start()
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
        server.send_signal(stop)
        try:
            out, err = server.communicate(timeout=30)
        finally:  # a server that did not stop fails the test, and is ended
            bound.cancel()
            server.kill()
    assert server.returncode == 0, err
    assert "stopped" in out and "Traceback" not in err


@pytest.mark.parametrize(
    "args, message",
    [
        (["frobnicate"], "conical-pendulum: argument COMMAND: invalid choice: 'frobnicate'"),
        ([], "conical-pendulum: the following arguments are required: COMMAND"),
        (
            ["check", "missing.fmu"],
            "conical-pendulum check: missing.fmu: No such file or directory",
        ),
        (
            ["check", "FMU", "--stop-time", "-1"],
            "conical-pendulum check: --stop-time: must be a positive number, got -1",
        ),
        (
            ["check", "FMU", "--rtol", "x"],
            "conical-pendulum check: argument --rtol: invalid float value: 'x'",
        ),
        (
            ["check", "FMU", "--frobnicate", "3"],
            "conical-pendulum check: unrecognized arguments: --frobnicate 3",
        ),
        (
            ["page", "FMU", "--out", "page", "--start", "length=3"],
            "conical-pendulum page: --start length=3: the FMU has no variable 'length'",
        ),
        (["page", "FMU", "--out", "page", "--start", "energy=3"], "--start energy=3: energy is calculated"),
        (
            ["page", "FMU", "--out", "page", "--start", "alpha0"],
            "conical-pendulum page: argument --start: 'alpha0': expected NAME=NUMBER",
        ),
        (
            ["page", "FMU", "--out", "page", "--start", "solver=0.5"],
            "--start solver=0.5: solver is an Enumeration",
        ),
        (["page", "FMU"], "conical-pendulum page: the following arguments are required: --out"),
        (["page", "FMU", "--out", "page", "--port", "70000"], "--port: 70000 is not a port number"),
        (["show", "RESULTS"], "conical-pendulum show: give --plot, --gif and/or --books"),
        (
            ["show", "RESULTS", "--plot", "p.png", "--fps", "0"],
            "conical-pendulum show: --fps: must be positive, got 0",
        ),
        (
            ["sweep", "FMU", "--grid", "l0=5,x"],
            "conical-pendulum sweep: argument --grid: 'x' is not a number",
        ),
        (["sweep", "FMU"], "conical-pendulum sweep: one of the arguments --grid --random is required"),
        (["demo", "--steps", "0.1,x"], "conical-pendulum demo: argument --steps: expected numbers"),
        # the rule a step breaks, not every rule
        (
            ["demo", "--steps", "0.3"],
            "conical-pendulum demo: --steps: 0.3 does not divide --stop-time 10 (10 / 0.3",
        ),
        (["demo", "--steps", "0.1,0.25"], "--steps: 0.25 is not a multiple of the smallest step 0.1"),
        (["demo", "--steps", "0,0.1"], "conical-pendulum demo: --steps: 0 must be a positive number"),
        (["check", "."], "conical-pendulum check: .: Is a directory"),
        (["check", "RESULTS"], "results.csv: not an FMU built by conical_pendulum"),
        (
            ["system", "--run", "ecos,openmodelica"],
            "conical-pendulum system: argument --run: unknown tool(s) 'openmodelica'; "
            "choose from ecospy, ecos, libcosim, fmpy, omsimulator or all",
        ),
        (
            ["system", "--step", "0.3", "--stop-time", "1"],
            "conical-pendulum system: --step: 0.3 does not divide --stop-time 1 (1 / 0.3 = 3.333)",
        ),
        (
            ["system", "--cart-mass", "5,-1"],
            "conical-pendulum system: --cart-mass: must be a positive number",
        ),
        (["build", "--links", "0"], "conical-pendulum build: links: 0 is out of range"),
    ],
)
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


# ---- every command's error paths, in process: one line on stderr and an exit status, never a traceback


def run_main(capsys, *argv):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def one_line(err: str, name: str) -> str:
    """The message of stderr's one line `conical-pendulum <name>: <message>`."""
    assert err.startswith(f"conical-pendulum {name}: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    return err.removeprefix(f"conical-pendulum {name}: ").rstrip("\n")


def hide(monkeypatch, *packages):
    """Imports of these packages fail from now on, as if they were not installed."""
    for package in packages:
        monkeypatch.setitem(sys.modules, package, None)


@pytest.mark.parametrize(
    "name, args, hidden, message",
    [
        ("page", ["FMU", "--out", "OUT"], "pydy", "needs pydy: INSTALL test (or pip install pydy)"),
        ("sweep", ["FMU", "--grid", "l0=5,6", "--out", "OUT/s.parquet"], "dask", "needs dask: INSTALL sweep"),
        ("demo", ["--out", "OUT"], "ecospy", "needs ecospy: INSTALL cosim"),
    ],
)
def test_a_missing_optional_package_is_one_line_saying_what_to_install(
    monkeypatch, capsys, tmp_path, seed_fmu, name, args, hidden, message
):
    hide(monkeypatch, hidden)
    # a module an earlier test imported would not import its package again: drop them
    # (and from their packages: `from ..analysis import sweep` takes the package's attribute)
    dropped = ("conical_pendulum.analysis.sweep", "conical_pendulum.commands.sweep")
    for module in [name for name in sys.modules if name.startswith(dropped)]:  # and the package's modules
        monkeypatch.delitem(sys.modules, module, raising=False)
        package, _, attribute = module.rpartition(".")
        if package in sys.modules:
            monkeypatch.delattr(sys.modules[package], attribute, raising=False)
    status, out, err = run_main(
        capsys, name, *[{"FMU": seed_fmu}.get(a, a.replace("OUT", str(tmp_path / "out"))) for a in args]
    )
    extra = message.split("INSTALL ")[1].split()[0]
    assert status == 2 and one_line(err, name) == message.replace(f"INSTALL {extra}", install_command(extra))
    assert not out and not list(tmp_path.iterdir())  # found before any work


class Installed:
    """importlib.metadata's distribution, as pip leaves it: `direct_url` is PEP 610's record
    (None for a wheel from an index)."""

    def __init__(self, direct_url):
        self.direct_url = direct_url

    def read_text(self, name):
        return None if self.direct_url is None else json.dumps(self.direct_url)


@pytest.mark.parametrize(
    "direct_url, inside, hint",
    [
        (None, False, 'pip install "conical-pendulum-fmu[sweep]"'),  # from PyPI
        (
            {"url": "SOURCE", "dir_info": {}},
            False,
            'pip install "conical-pendulum-fmu[sweep]"',
        ),  # pip install .
        ({"url": "SOURCE", "dir_info": {"editable": True}}, True, 'pip install -e ".[sweep]"'),
        ({"url": "SOURCE", "dir_info": {"editable": True}}, False, 'pip install -e "SOURCE[sweep]"'),
    ],
    ids=["wheel", "from-a-folder", "editable-here", "editable-elsewhere"],
)
def test_the_install_hint_fits_how_the_package_was_installed(monkeypatch, tmp_path, direct_url, inside, hint):
    source = tmp_path / "checkout"
    source.mkdir()
    if direct_url is not None:
        direct_url = {**direct_url, "url": source.as_uri()}
    monkeypatch.setattr(errors, "distribution", lambda name: Installed(direct_url))
    monkeypatch.chdir(source if inside else tmp_path)
    assert install_command("sweep") == hint.replace("SOURCE", str(source))


def test_a_missing_extra_of_an_installed_wheel_names_the_package(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(errors, "distribution", lambda name: Installed(None))
    hide(monkeypatch, "ecospy")
    status, out, err = run_main(capsys, "demo", "--out", tmp_path / "out")
    assert status == 2 and one_line(err, "demo") == 'needs ecospy: pip install "conical-pendulum-fmu[cosim]"'
    assert not out and not list(tmp_path.iterdir())


def test_system_says_what_its_runs_leave_and_where(tmp_path):
    from conical_pendulum.commands.system import scratch_note

    work = tmp_path / "work" / "p_100kg_0.01s"
    work.mkdir(parents=True)
    (work / "ecos-explicit.csv").write_bytes(b"x" * 3_000_000)
    assert scratch_note(tmp_path / "work") == (
        "left 3 MB of the tools' scratch files (each one's unpacked packages, outputs and logs) "
        f"in {tmp_path / 'work'}: delete the folder when done"
    )


def test_demo_without_tbb_says_what_to_install(monkeypatch, capsys, tmp_path):
    from conical_pendulum.demos import ecospy_run

    find_spec = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util,
        "find_spec",  # ecospy itself is there
        lambda name, *a: object() if name == "ecospy" else find_spec(name, *a),
    )
    monkeypatch.setattr(ecospy_run, "TBB", str(tmp_path / "libtbb.so.12"))
    status, _, err = run_main(capsys, "demo", "--out", tmp_path / "out")
    assert status == 2 and one_line(err, "demo") == f"needs tbb: {install_command('cosim')}"
    assert not list(tmp_path.iterdir())


def test_system_without_libcosimpy_says_what_to_install_before_building(monkeypatch, capsys, tmp_path):
    from conical_pendulum.demos import libcosim_run

    monkeypatch.setattr(libcosim_run, "missing", lambda: "libcosimpy")
    status, _, err = run_main(capsys, "system", "--out", tmp_path / "out", "--run", "ecos,libcosim")
    assert (
        status == 2
        and one_line(err, "system") == f"--run libcosim: needs libcosimpy: {install_command('cosim')}"
    )
    assert not list(tmp_path.iterdir())


def test_build_without_mingw_says_what_to_install(monkeypatch, capsys, tmp_path):
    which = shutil.which
    monkeypatch.setattr(shutil, "which", lambda cmd, *a, **k: None if "mingw" in cmd else which(cmd, *a, **k))
    status, _, err = run_main(
        capsys, "build", "--native", "--win64", "--no-check", "--output", tmp_path / "W.fmu"
    )
    assert status == 2
    assert one_line(err, "build") == (
        "the win64 binary needs the compiler x86_64-w64-mingw32-gcc "
        "(Debian: apt-get install gcc-mingw-w64-x86-64)"
    )
    assert not (tmp_path / "W.fmu").exists()


def test_build_without_a_c_compiler_says_what_to_install(monkeypatch, capsys, tmp_path):
    monkeypatch.setenv("CONICAL_PENDULUM_CACHE", str(tmp_path / "cache"))  # nothing compiled yet
    monkeypatch.setenv("CC", "no-such-cc")
    status, _, err = run_main(capsys, "build", "--links", "1", "--no-check", "--output", tmp_path / "P.fmu")
    assert status == 2
    assert one_line(err, "build") == (
        "the compiled core needs the C compiler no-such-cc, which is "
        "not on PATH (Debian: apt-get install gcc; or set CC)"
    )
    assert not (tmp_path / "P.fmu").exists()


def test_build_check_and_show_need_no_optional_package(monkeypatch, capsys, tmp_path, seed_fmu):
    """They have no optional package to miss: without the test, sweep and cosim extras they run."""
    from fmpy.util import write_csv

    from conical_pendulum.analysis.fmpy_runs import run_fmu

    results = tmp_path / "results.csv"
    write_csv(str(results), run_fmu(seed_fmu, stop_time=0.2, output_interval=0.05))
    hide(monkeypatch, "pydy", "dask", "distributed", "ecospy", "selenium")
    status, out, err = run_main(capsys, "build", "--no-check", "--output", tmp_path / "Seed.fmu")
    assert status == 0 and f"built {tmp_path / 'Seed.fmu'}" in out, err
    status, out, err = run_main(capsys, "check", seed_fmu, "--stop-time", "0.5")
    assert status == 0 and out.strip().endswith("rad: OK"), err
    status, out, err = run_main(capsys, "show", results, "--plot", tmp_path / "p.png")
    assert status == 0 and out == f"wrote {tmp_path / 'p.png'}\n", err


def bad_file(folder: Path, kind: str, suffix: str) -> Path:
    """A file that cannot be read as what is expected: not there, a directory, binary
    garbage, text of another kind, or without read permission."""
    path = folder / f"bad{suffix}"
    if kind == "directory":
        path.mkdir()
    elif kind == "garbage":
        path.write_bytes(bytes(range(256)) * 8)
    elif kind == "text":
        path.write_text("this is not it\n")
    elif kind == "unreadable":
        if os.geteuid() == 0:
            pytest.skip("root reads a file without read permission")
        path.write_text("time,alpha0\n0,0\n")
        path.chmod(0)
    return path


@pytest.mark.parametrize("kind", ["missing", "directory", "garbage", "text", "unreadable"])
@pytest.mark.parametrize(
    "name, args, suffix",
    [
        ("build", ["--scene", "BAD", "--output", "OUT/x.fmu"], ".toml"),
        ("check", ["BAD"], ".fmu"),
        ("linearize", ["BAD"], ".fmu"),
        ("show", ["BAD", "--plot", "OUT/p.png"], ".csv"),
        ("page", ["BAD", "--out", "OUT"], ".fmu"),
        ("sweep", ["BAD", "--grid", "l0=5,6", "--out", "OUT/s.parquet"], ".fmu"),
    ],
)
def test_a_bad_or_unreadable_file_is_one_line(capsys, tmp_path, name, args, suffix, kind):
    path = bad_file(tmp_path, kind, suffix)
    (tmp_path / "out").mkdir()
    status, out, err = run_main(
        capsys, name, *[str(path) if a == "BAD" else a.replace("OUT", str(tmp_path / "out")) for a in args]
    )
    assert status == 2 and str(path) in one_line(err, name)
    assert not out and not list((tmp_path / "out").iterdir())


@pytest.mark.parametrize(
    "name, args, message",
    [
        ("build", ["--no-check", "--output", "FOLDER"], "output: 'FOLDER' is a directory"),
        ("build", ["--no-check", "--output", "FILE/x.fmu"], "'FILE' is not a directory"),
        ("show", ["RESULTS", "--plot", "FOLDER"], "--plot FOLDER: is a directory"),
        ("show", ["RESULTS", "--gif", "FILE/x.gif"], "--gif FILE/x.gif: FILE is not a directory"),
        ("page", ["FMU", "--out", "FILE"], "--out FILE: not a directory"),
        ("sweep", ["FMU", "--grid", "l0=5,6", "--out", "FILE"], "out: FILE is a file"),
        ("demo", ["--out", "FILE"], "--out FILE: not a directory"),
        ("system", ["--out", "FILE"], "--out FILE: not a directory"),
    ],
)
def test_an_output_where_a_file_or_folder_cannot_be_is_one_line(
    monkeypatch, capsys, tmp_path, seed_fmu, name, args, message
):
    from conical_pendulum.demos import ecospy_run

    monkeypatch.setattr(ecospy_run, "missing", lambda: None)  # the demo's --out, even without ecospy
    folder, file, results = tmp_path / "folder.fmu", tmp_path / "file", tmp_path / "results.csv"
    folder.mkdir()
    file.write_text("x\n")
    results.write_text("time,alpha0\n0,0\n1,0.1\n")
    names = {"FOLDER": str(folder), "FILE": str(file), "RESULTS": str(results), "FMU": str(seed_fmu)}

    def named(text):
        for placeholder, value in names.items():
            text = text.replace(placeholder, value)
        return text

    status, out, err = run_main(capsys, name, *map(named, args))
    assert status == 2 and named(message) in one_line(err, name)
    assert not out and sorted(p.name for p in tmp_path.iterdir()) == ["file", "folder.fmu", "results.csv"]
    assert not list(folder.iterdir()) and file.read_text() == "x\n"


WORK = {  # what each command spends its time in, and a command line that gets there
    "build": ("conical_pendulum.builder.fmu", "build_fmu", ["--no-check", "--output", "OUT/x.fmu"]),
    "check": ("conical_pendulum.analysis.compare", "compare", ["FMU", "--stop-time", "1"]),
    "linearize": ("conical_pendulum.analysis.linearize", "linearize", ["FMU"]),
    "show": ("conical_pendulum.viz.plots", "plot", ["RESULTS", "--plot", "OUT/p.png"]),
    "page": ("conical_pendulum.analysis.fmpy_runs", "run_fmu", ["FMU", "--out", "OUT"]),
    "sweep": (
        "conical_pendulum.analysis.sweep",
        "sweep",
        ["FMU", "--grid", "l0=5,6", "--out", "OUT/s.parquet"],
    ),
    "demo": ("conical_pendulum.builder.fmu", "build_fmu", ["--out", "OUT"]),
    "system": ("conical_pendulum.builder.fmu", "build_fmu", ["--out", "OUT"]),
}


@pytest.mark.parametrize("name", NAMES)
def test_ctrl_c_is_one_line_and_status_130(monkeypatch, capsys, tmp_path, seed_fmu, name):
    pytest.importorskip({"page": "pydy", "sweep": "dask"}.get(name, "conical_pendulum"))
    from conical_pendulum.demos import ecospy_run

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    module, function, args = WORK[name]
    monkeypatch.setattr(importlib.import_module(module), function, interrupted)
    monkeypatch.setattr(ecospy_run, "missing", lambda: None)
    results = tmp_path / "results.csv"
    results.write_text("time,alpha0\n0,0\n1,0.1\n")
    (tmp_path / "out").mkdir()
    places = {"FMU": str(seed_fmu), "RESULTS": str(results)}
    status, _, err = run_main(
        capsys, name, *[places.get(a, a.replace("OUT", str(tmp_path / "out"))) for a in args]
    )
    assert status == 130 and err == f"conical-pendulum {name}: interrupted\n"


def test_build_fmu_py_names_itself_when_interrupted(monkeypatch, capsys, tmp_path):
    import conical_pendulum.builder.fmu

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(conical_pendulum.builder.fmu, "build_fmu", interrupted)
    assert (
        run_command("build", ["--no-check", "--output", str(tmp_path / "x.fmu")], prog="build_fmu.py") == 130
    )
    assert capsys.readouterr().err == "build_fmu.py: interrupted\n"


def test_a_failed_ecospy_run_is_the_demos_status_1(monkeypatch, capsys, tmp_path):
    """The demo's own failure (ecospy ran and failed) is status 1, printed by the CLI, not the demo."""
    import conical_pendulum.builder.fmu
    from conical_pendulum.demos import coupled, ecospy_run

    def failed(*args, **kwargs):
        raise RuntimeError("ecospy failed (exit 3): boom")

    monkeypatch.setattr(ecospy_run, "missing", lambda: None)
    monkeypatch.setattr(
        conical_pendulum.builder.fmu, "build_fmu", lambda scene, path: type("B", (), {"path": path})
    )
    monkeypatch.setattr(coupled, "build_cart_fmu", lambda path: path)
    monkeypatch.setattr(coupled, "reference", lambda *args: {})
    monkeypatch.setattr(coupled, "cosimulate", failed)
    status, _out, err = run_main(
        capsys,
        "demo",
        "--out",
        tmp_path,
        "--steps",
        "0.5",
        "--stop-time",
        "1",
        "--cart-mass",
        "5",
        "--scheme",
        "explicit",
    )
    assert status == 1 and one_line(err, "demo") == "ecospy failed (exit 3): boom"


def test_system_without_omsimulator_says_where_it_looks(monkeypatch, capsys, tmp_path):
    """No registry offers OMSimulator: the message says where it was looked for, before any build."""
    from conical_pendulum.demos import ssp_tools

    monkeypatch.delenv(ssp_tools.OMSIMULATOR, raising=False)
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    status, out, err = run_main(capsys, "system", "--out", tmp_path / "out", "--run", "omsimulator")
    assert status == 2 and one_line(err, "system") == (
        "--run omsimulator: needs OMSimulator (OpenModelica's; no package registry offers it): put it "
        "on PATH or name its executable in the environment variable OMSIMULATOR"
    )
    assert not out and not list(tmp_path.iterdir())


def test_system_names_an_omsimulator_that_is_not_an_executable(monkeypatch, capsys, tmp_path):
    """$OMSIMULATOR naming no executable is refused by name and value, not replaced by PATH's."""
    from conical_pendulum.demos import ssp_tools

    named = tmp_path / "OMSimulator"
    named.write_text("not a program")
    monkeypatch.setenv(ssp_tools.OMSIMULATOR, str(named))
    status, out, err = run_main(capsys, "system", "--out", tmp_path / "out", "--run", "omsimulator")
    assert status == 2 and one_line(err, "system") == (
        f"--run omsimulator: needs OMSimulator: OMSIMULATOR={named} is not an executable file"
    )
    assert not out and not (tmp_path / "out").exists()
    named.chmod(0o755)
    assert ssp_tools.omsimulator() == named


def test_omsimulator_is_taken_from_path_without_the_variable(monkeypatch, tmp_path):
    from conical_pendulum.demos import ssp_tools

    on_path = tmp_path / "OMSimulator"
    on_path.write_text("#!/bin/sh\n")
    on_path.chmod(0o755)
    monkeypatch.delenv(ssp_tools.OMSIMULATOR, raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))
    assert ssp_tools.omsimulator() == on_path


def test_build_without_the_arm_cross_compiler_says_what_to_install(monkeypatch, capsys, tmp_path):
    which = shutil.which
    monkeypatch.setattr(
        shutil, "which", lambda cmd, *a, **k: None if "aarch64" in cmd else which(cmd, *a, **k)
    )
    status, _, err = run_main(
        capsys, "build", "--native", "--fmi", "3", "--aarch64", "--no-check", "--output", tmp_path / "A.fmu"
    )
    assert status == 2
    assert one_line(err, "build") == (
        "the aarch64-linux binary needs the compiler aarch64-linux-gnu-gcc "
        "(Debian: apt-get install gcc-aarch64-linux-gnu)"
    )
    assert not (tmp_path / "A.fmu").exists()
