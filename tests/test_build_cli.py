"""build_fmu.py and `conical-pendulum build`: what they build, and clear refusals of options
they cannot build."""

import subprocess
import sys
from pathlib import Path

import fmpy
import pytest

from conical_pendulum.analysis.fmpy_runs import simulate_fmu
from conical_pendulum.builder.fmu import fmu_scene
from conical_pendulum.cli import main
from conical_pendulum.commands import build as build_command

ROOT = Path(__file__).resolve().parent.parent
# the same code behind two names; messages start with the name
ENTRY_POINTS = {
    "build_fmu.py": [sys.executable, str(ROOT / "build_fmu.py")],
    "conical-pendulum build": [str(Path(sys.executable).with_name("conical-pendulum")), "build"],
}


@pytest.fixture(params=list(ENTRY_POINTS))
def build(request):
    def run(*args, cwd=ROOT):
        result = subprocess.run(
            [*ENTRY_POINTS[request.param], *args],
            cwd=cwd,
            check=False,
            capture_output=True,
            text=True,
            timeout=600,
        )
        result.name = request.param
        return result

    return run


def test_builds_the_requested_scene(tmp_path, build):
    out = tmp_path / "Two.fmu"
    run = build("--links", "2", "--no-bobs", "--output", str(out), "--no-check")
    assert run.returncode == 0, run.stderr
    assert f"built {out}" in run.stdout and "2 links" in run.stdout
    assert out.exists()


@pytest.mark.parametrize(
    "args, message",
    [
        (["--links", "0"], "links: 0 is out of range"),
        (["--links", "1000"], "links: 1000 is out of range"),
        (["--massless-links", "--no-bobs"], "scene has no mass"),
        (["--kinematics", "seed"], "invalid choice: 'seed'"),
        (["--links", "6", "--kinematics", "pydy-example"], "only reproduced up to 4 links"),
        (["--coupling", "--kinematics", "pydy-example"], "coupling: the pivot's inputs and force need"),
        (["--joint-damping", "-0.5"], "--joint-damping: must be a finite number >= 0, got -0.5"),
        (
            ["--joint-damping", "1", "--kinematics", "pydy-example"],
            "joint_damping: the joints' damping needs kinematics 'consistent'",
        ),
        (["--air-drag", "--no-bobs"], "air_drag: the scene has no bob for the air to drag"),
        (["--output", "dist/model.zip"], "must end in .fmu"),
        (["--frobnicate"], "unrecognized arguments: --frobnicate"),
        (
            ["--scene", str(ROOT / "scenes" / "seed.toml"), "--links", "2"],
            "--scene describes the whole scene; drop --links",
        ),
        (["--scene", "missing.toml"], "scene file 'missing.toml': No such file or directory"),
        (["--win64"], "--win64: only the native FMU carries a Windows binary; add --native"),
        (["--native", "--scalars"], "--scalars: only the FMI 3.0 FMU has arrays; add --native --fmi 3"),
        (["--native", "--aarch64"], "--aarch64: only the FMI 3.0 FMU carries an ARM binary"),
    ],
)
def test_refuses_what_it_cannot_build(tmp_path, build, args, message):
    run = build(*args, "--no-check", cwd=tmp_path)
    assert run.returncode == 2
    assert message in run.stderr
    assert run.stderr.startswith(f"{run.name}: ") and run.stderr.count("\n") == 1  # one line
    assert "Traceback" not in run.stderr
    assert not list(tmp_path.rglob("*.fmu"))


def test_a_scene_without_the_outputs_a_picture_needs_still_builds(tmp_path, build):
    """Bobs on the first link only, no poses, no energy: the FMU builds and checks, the plot
    has the angles, and one line says what was left out and why; exit status 0."""
    scene = tmp_path / "no_poses.toml"
    scene.write_text('outputs = ["bobs"]\n[[link]]\nbob = { mass = 5.0, radius = 1.0 }\n[[link]]\n')
    run = build("--scene", str(scene), "--output", str(tmp_path / "NoPoses.fmu"), cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    lines = run.stdout.splitlines()
    assert lines[-3].endswith("rad: OK")
    assert lines[-2] == f"wrote {tmp_path / 'NoPoses.csv'} and {tmp_path / 'NoPoses.png'}"
    assert lines[-1] == (
        "left out the paths and the animation: the results have neither link poses "
        "(link<i>_x/y/z, the scene's output 'poses') nor a bob on every link (bob<i>_x/y/z); "
        "the energy drift: the results have no energy output"
    )
    assert (tmp_path / "NoPoses.png").stat().st_size > 10_000 and not (tmp_path / "NoPoses.gif").exists()
    assert "Traceback" not in run.stderr


# about a minute: the README's three builds through the command line, as a user runs them (what
# is tested is that none overwrites another's file, so the test fixtures' cached FMUs cannot do)
def test_each_kind_of_fmu_has_its_own_default_name(tmp_path, monkeypatch, capsys):
    """The README's builds in its order (pythonfmu, --native, --native --fmi 3) leave three
    FMUs, and its fmpy snippet still runs the first: no build overwrites another's."""
    monkeypatch.chdir(tmp_path)
    for flavour in ([], ["--native"], ["--native", "--fmi", "3"]):
        assert main(["build", *flavour, "--no-check"]) == 0, capsys.readouterr().err
    versions = {}
    for name in ("ConicalPendulum.fmu", "ConicalPendulum_native.fmu", "ConicalPendulum_fmi3.fmu"):
        description = fmpy.read_model_description(str(tmp_path / "dist" / name))
        versions[name] = (description.fmiVersion, description.generationTool.split()[0])
    assert versions["ConicalPendulum.fmu"][0] == "2.0" and versions["ConicalPendulum_native.fmu"][0] == "2.0"
    assert versions["ConicalPendulum_fmi3.fmu"][0] == "3.0"
    assert (
        versions["ConicalPendulum.fmu"][1] != versions["ConicalPendulum_native.fmu"][1]
    )  # pythonfmu, native
    result = simulate_fmu(
        "dist/ConicalPendulum.fmu",
        stop_time=0.5,
        output_interval=1 / 60,
        start_values={"l0": 8.0, "alpha0": 0.5, "solver": 2, "rtol": 1e-10},
    )
    assert result["alpha0"][0] == 0.5


def test_a_scene_files_build_is_named_after_the_scene(tmp_path, monkeypatch, capsys):
    """--scene FILE without --output writes dist/<file's name><kind>.fmu beside the seed's FMU;
    a build that replaces an FMU of another scene says so, a rebuild of the same scene does not."""
    monkeypatch.chdir(tmp_path)
    Path("one_link.toml").write_text("[[link]]\nbob = { mass = 2.0, radius = 0.5 }\n")
    assert main(["build", "--native", "--no-check"]) == 0, capsys.readouterr().err
    seed = Path("dist/ConicalPendulum_native.fmu")
    seed_bytes = seed.read_bytes()
    capsys.readouterr()
    assert main(["build", "--scene", "one_link.toml", "--native", "--no-check"]) == 0
    assert "replacing" not in capsys.readouterr().out
    assert fmu_scene("dist/one_link_native.fmu").n == 1 and seed.read_bytes() == seed_bytes
    assert main(["build", "--scene", "one_link.toml", "--native", "--no-check"]) == 0  # the same scene
    assert "replacing" not in capsys.readouterr().out
    assert main(["build", "--links", "2", "--native", "--no-check"]) == 0  # another scene, the seed's name
    assert f"{seed}: replacing the FMU of another scene" in capsys.readouterr().out
    assert fmu_scene(seed).n == 2


def test_the_run_is_named_after_its_fmu():
    assert build_command.run_files(Path("dist/ConicalPendulum_native.fmu")) == (
        Path("dist/ConicalPendulum_native.csv"),
        Path("dist/ConicalPendulum_native.png"),
        Path("dist/ConicalPendulum_native.gif"),
    )
