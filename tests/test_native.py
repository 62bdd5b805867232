"""The native FMU: the same C as the pythonfmu FMU with FMI glue in C, in hosts that are not Python."""

import os
import re
import shutil
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

import c_hosts
from conical_pendulum import Link, Scene
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.analysis.simulate import simulate
from conical_pendulum.builder.fmu import build_fmu
from fmu_helpers import BAD_VALUES, INSTANCES, Instance
from required_tools import require_tool

SCENES = {
    "seed": Scene.uniform(3),
    "coupled": Scene.uniform(3, coupling=True),
    "mixed": Scene(links=(Link(has_mass=False), Link(has_bob=False), Link(length=4.0))),
    "published": Scene.uniform(2, kinematics="pydy-example", outputs=("energy",)),
}
COUPLED = SCENES["coupled"]
START = {"l0": 8.0, "alpha0": 0.5, "delta2": 0.3}
ERROR, DISCARD = 3, 2  # fmi2Error, fmi2Discard (fmi3Error, fmi3Discard the same)


@pytest.fixture(scope="module")
def fmus(built_fmu):
    """{scene name: (native FMU, pythonfmu FMU)}, built on first use."""
    return lambda name: tuple(built_fmu(SCENES[name], backend=backend) for backend in ("native", "pythonfmu"))


@pytest.fixture(scope="module")
def native(fmus):
    return fmus("seed")[0]


@pytest.fixture(scope="module")
def host(c_host):
    """tests/hosts/fmi_host.c compiled: a host that is a plain C program."""
    return c_host(2)


def unzipped(path, folder):
    with zipfile.ZipFile(path) as archive:
        archive.extractall(folder)
    return folder


def library(path, folder) -> Path:
    return unzipped(path, folder) / "binaries" / "linux64" / "ConicalPendulum.so"


def vrs(path, names):
    variables = {v.name: v.valueReference for v in read_model_description(str(path)).modelVariables}
    return [variables[name] for name in names]


def test_fmpy_and_fmutool_validate_it(native):
    assert validate_fmu(str(native)) == []
    fmutool = shutil.which("fmutool", path=os.path.dirname(sys.executable)) or shutil.which("fmutool")
    run = subprocess.run(
        [fmutool, "-input", str(native), "-check"], check=False, capture_output=True, text=True
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert "compliant with FMI-2.0" in run.stdout and "No semantic error" in run.stdout


def test_binary_needs_only_libc_and_libm_and_exports_only_fmi(native, tmp_path):
    so = library(native, tmp_path)
    dynamic = subprocess.run(["readelf", "-d", str(so)], capture_output=True, text=True, check=True).stdout
    needed = {line.split("[")[1].rstrip("]") for line in dynamic.splitlines() if "(NEEDED)" in line}
    assert needed == {"libc.so.6", "libm.so.6"}
    symbols = subprocess.run(
        ["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True
    ).stdout.split()[2::3]
    assert symbols and all(name.startswith("fmi2") for name in symbols)


def test_model_description_matches_the_pythonfmu_fmu_and_is_complete(fmus):
    native, python = fmus("coupled")
    ours, theirs = (read_model_description(str(path)) for path in (native, python))
    by_name = {v.name: v for v in ours.modelVariables}
    # every solver in both, the implicit one and the automatic choice included
    assert (
        "3 = Radau IIA order 5" in by_name["solver"].description
        and "4 = automatic" in by_name["solver"].description
    )
    for v in theirs.modelVariables:
        mine = by_name[v.name]
        assert (
            mine.valueReference,
            mine.type,
            mine.causality,
            mine.variability,
            mine.initial,
            mine.start,
            mine.description,
        ) == (v.valueReference, v.type, v.causality, v.variability, v.initial, v.start, v.description)
    derivatives = [v for v in ours.modelVariables if v.name.startswith("der(")]
    assert [d.derivative.name for d in derivatives] == SCENES["coupled"].state_names()
    assert len(ours.derivatives) == len(derivatives)
    assert {u.variable.name for u in ours.initialUnknowns} >= {d.name for d in derivatives} | {"energy"}
    assert ours.coSimulation.canGetAndSetFMUstate and ours.modelExchange.canSerializeFMUstate
    root = ET.fromstring(zipfile.ZipFile(native).read("modelDescription.xml"))
    for interface in ("ModelExchange", "CoSimulation"):
        element = root.find(interface)
        assert element.get("needsExecutionTool") == "false"
        assert [f.get("name") for f in element.find("SourceFiles")]
    feedthrough = {u.variable.name: u.dependencies for u in ours.outputs}
    assert {d.name for d in feedthrough["F_pivot_x"]} >= {"a_pivot_x", "a_pivot_y", "a_pivot_z"}
    assert not {d.name for d in feedthrough["energy"]} & {"a_pivot_x", "a_pivot_y", "a_pivot_z"}


@pytest.mark.parametrize("scene", list(SCENES))
@pytest.mark.parametrize(
    "settings",
    [
        {},
        {"solver": 2, "rtol": 1e-11, "atol": 1e-11},
        {"across_points": 0},
        {"solver": 2, "rtol": 1e-11, "atol": 1e-11, "across_points": 0},
        {"solver": 0, "max_step": 0.005},
    ],
)
def test_co_simulation_equals_the_pythonfmu_fmu_bit_for_bit(fmus, scene, settings):
    """Same generated C, same solvers, same settings: the same numbers."""
    native, python = fmus(scene)
    start = {
        **{
            k: v
            for k, v in START.items()
            if k in SCENES[scene].parameter_names() + SCENES[scene].state_names()
        },
        **settings,
    }
    if scene == "coupled":
        start["a_pivot_x"] = 0.7
    ours, theirs = (run_fmu(path, stop_time=5.0, start_values=start) for path in (native, python))
    assert ours.dtype.names == theirs.dtype.names
    for name in theirs.dtype.names:
        np.testing.assert_array_equal(ours[name], theirs[name], err_msg=name)


def test_model_exchange_matches_the_native_reference(fmus):
    native, _ = fmus("seed")
    run = run_fmu(
        native, stop_time=10.0, fmi_type="ModelExchange", relative_tolerance=1e-10, start_values=START
    )
    reference = simulate(
        SCENES["seed"],
        run["time"],
        parameters={"l0": 8.0},
        state={"alpha0": 0.5, "delta2": 0.3},
        rtol=1e-12,
        atol=1e-12,
    )
    for name in SCENES["seed"].state_names()[:6]:  # the angles
        assert np.abs(run[name] - reference[name]).max() < 1e-6, name
    assert np.abs(run["energy"] - reference["energy"]).max() < 1e-6 * abs(reference["energy"][0])


# about a minute: CMake's configure and compile, as a host rebuilding the FMU does
def test_a_host_rebuilds_the_binary_from_the_fmus_sources(native, tmp_path):
    """fmpy's build_platform_binary (CMake) on the FMU's sources/ alone."""
    from fmpy.build import build_platform_binary

    folder = unzipped(native, tmp_path / "fmu")
    shutil.rmtree(folder / "binaries")
    (tmp_path / "build").mkdir()
    build_platform_binary(folder, build_dir=tmp_path / "build")
    assert (folder / "binaries" / "linux64" / "ConicalPendulum.so").exists()
    rebuilt = run_fmu(folder, stop_time=2.0, start_values=START)
    shipped = run_fmu(native, stop_time=2.0, start_values=START)
    for name in ("alpha0", "beta2", "energy"):
        np.testing.assert_allclose(rebuilt[name], shipped[name], rtol=1e-9, atol=1e-12)


def test_the_fmi_layer_knows_the_model_only_through_the_contract(native):
    """fmi2_glue.c includes the FMI headers, the body both FMI layers share fmi_layer.h,
    fmu_config.h (GUID, log categories, names) and the model contract fmu_model.h, and touches
    none of the model's value references, sizes, rules or C; the model's file knows nothing of
    FMI, and fmi_layer.c knows the model only through the contract and neither standard's
    headers, types or functions."""
    with zipfile.ZipFile(native) as archive:
        glue = archive.read("sources/fmi2_glue.c").decode()
        model = archive.read("sources/pendulum_model.c").decode()
        layer = archive.read("sources/fmi_layer.c").decode()
    included = re.findall(r'#include "([^"]+)"', glue)
    assert included == ["fmi2Functions.h", "fmi_layer.h", "fmu_config.h", "fmu_model.h"]
    assert re.findall(r'#include "([^"]+)"', layer) == ["fmi_layer.h", "fmu_model.h"]
    assert not re.search(r"\bfmi[23][A-Z]", layer)
    for word in (
        "CP_VR_",
        "CP_NREAL",
        "CP_NSTATE",
        "CP_NPARAM",
        "CP_NOUTPUT",
        "cp_rules",
        "cp_real_",
        "cp_rhs",
        "cp_cosim",
        "cp_directional",
        "CP_STEP",
        "CP_SOLVER",
        "CP_FIXED",
        "CP_CALCULATED",
    ):
        assert word not in glue, word
        assert word not in layer, word
    assert "fmi2" not in model


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_a_c_host_runs_it_with_a_clean_environment_as_fmpy_does(built_fmu, c_host, fmi_version, tmp_path):
    """dlopen and the FMI calls from a C program: no Python, no preload, no paths."""
    path = built_fmu(COUPLED, backend="native", fmi_version=fmi_version)
    run = subprocess.run(
        [
            str(c_host(fmi_version)),
            str(c_hosts.binary(fmi_version, unzipped(path, tmp_path))),
            *c_hosts.host_arguments(fmi_version, path),
        ],
        capture_output=True,
        text=True,
        env={},
        check=True,
    )
    rows = c_hosts.rows_of(run)
    ours = run_fmu(path, stop_time=10.0, start_values={"l0": 8.0})
    names = c_hosts.OUTPUTS[fmi_version]
    assert rows.shape == (601, 1 + len(names))
    for k, name in enumerate(names, start=1):
        np.testing.assert_array_equal(rows[:, k], ours[name], err_msg=name)


def test_two_instances_side_by_side_keep_their_own_parameters(native, host, tmp_path):
    md = read_model_description(str(native))
    l0, alpha0 = vrs(native, ["l0", "alpha0"])
    run = subprocess.run(
        [
            str(host),
            str(library(native, tmp_path)),
            md.guid,
            "3",
            "0.05",
            "1",
            str(alpha0),
            "--",
            f"{l0}=5",
            "--",
            f"{l0}=12",
        ],
        capture_output=True,
        text=True,
        env={},
        check=True,
    )
    rows = np.array([[float(x) for x in line.split(",")] for line in run.stdout.split()])
    for column, length in ((1, 5.0), (2, 12.0)):
        alone = run_fmu(native, stop_time=3.0, output_interval=0.05, start_values={"l0": length})
        np.testing.assert_array_equal(rows[:, column], alone["alpha0"])


@pytest.mark.tools
def test_ecos_command_line_engine_runs_it_with_a_clean_environment(native, tmp_path):
    """ecos' own executable (from the ecospy wheel), 600 steps/s, nothing of Python around it."""
    import importlib.util

    # not imported: ecospy's module loads its library, which needs libtbb preloaded
    binaries = Path(importlib.util.find_spec("ecospy").submodule_search_locations[0]) / "binaries"
    ecos = tmp_path / "ecos"
    shutil.copy2(binaries / "ecos", ecos)
    ecos.chmod(0o755)
    tbb = Path(sys.prefix) / "lib"  # ecos' own dependency, libtbb, from the tbb wheel
    step = 1 / 600
    run = subprocess.run(
        [
            str(ecos),
            "simulate",
            "--path",
            str(native),
            "--stopTime",
            "10",
            "--stepSize",
            repr(step),
            "--noParallel",
            "-l",
            "warn",
        ],
        cwd=tmp_path,
        check=False,
        capture_output=True,
        text=True,
        env={"LD_LIBRARY_PATH": str(tbb)},
        timeout=300,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    table = np.genfromtxt(
        next(tmp_path.glob("*.csv")), delimiter=",", names=True, deletechars="", autostrip=True
    )
    columns = {name.split("::")[-1].split("[")[0]: name for name in table.dtype.names}
    ours = run_fmu(native, stop_time=10.0, output_interval=step)
    assert len(table) == 6000  # ecos writes the points before each of its 6000 steps
    np.testing.assert_allclose(table["time"], ours["time"][:6000], rtol=0, atol=1e-5)
    for name in ("alpha0", "bob2_x", "energy"):  # ecos writes six decimals
        np.testing.assert_allclose(
            table[columns[name]], ours[name][:6000], rtol=1e-6, atol=1e-6, err_msg=name
        )


# under a minute each: valgrind runs the host some 30 times slower; the only check of the C glue's
# memory over many instance lifetimes
@pytest.mark.tools
@pytest.mark.parametrize("fmi_version", [2, 3])
def test_a_thousand_cycles_under_valgrind(built_fmu, c_host, fmi_version, tmp_path):
    require_tool("valgrind", None, "Debian's valgrind (.ci/run installs it)")
    path = built_fmu(COUPLED, backend="native", fmi_version=fmi_version)
    run = subprocess.run(
        [
            "valgrind",
            "--error-exitcode=3",
            "--leak-check=full",
            "--errors-for-leak-kinds=definite,indirect,possible",
            "--quiet",
            str(c_host(fmi_version)),
            str(c_hosts.binary(fmi_version, unzipped(path, tmp_path))),
            *c_hosts.host_arguments(fmi_version, path, stop="1", cycles="1000"),
        ],
        check=False,
        capture_output=True,
        text=True,
        env={},
        timeout=1200,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    assert len(run.stdout.split()) == 61


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_fmu_state_get_set_and_serialize_replay_bit_for_bit_and_corrupt_bytes_are_refused(
    built_fmu, fmi_version
):
    """A saved state, and one serialized and restored in another instance, replay the run
    bit for bit; bytes with a NaN time, or not of this FMU, are refused and change nothing."""
    path = built_fmu(COUPLED, backend="native", fmi_version=fmi_version)
    fmu = INSTANCES[fmi_version](path, start_values=START)
    fmu.step(0.5)
    saved = fmu.get_state()
    data = fmu.serialize(saved)
    names = [*COUPLED.state_names(), "energy", "n_rhs"]

    def run_on(instance):
        for _ in range(30):
            instance.step(1 / 60)
        return instance.get(*names)

    start_time = fmu.time
    first = run_on(fmu)
    fmu.set_state(saved)
    fmu.time = start_time
    if fmi_version == 3:  # the independent variable, a variable in FMI 3.0
        assert fmu.get("time") == [start_time]
    assert run_on(fmu) == first
    other = INSTANCES[fmi_version](path, name="other")
    restored = other.deserialize(data)
    other.set_state(restored)
    other.time = start_time
    assert run_on(other) == first
    # the state's time (the first 0.5 after the header) made NaN: refused, naming it
    at = data.index(struct.pack("<d", 0.5))
    corrupt = data[:at] + struct.pack("<d", float("nan")) + data[at + 8 :]
    with pytest.raises(FMICallException) as refusal:
        other.deserialize(corrupt)
    assert refusal.value.status == ERROR
    assert "the state's time = nan: must be finite" in other.texts(ERROR)
    with pytest.raises(FMICallException):
        other.deserialize(b"\0" + data[1:])
    assert "the bytes are not a state of this FMU" in other.texts(ERROR)
    assert other.get(*names) == first  # nothing taken
    fmu.free_state(saved)
    other.free_state(restored)
    fmu.close()
    other.close()


@pytest.mark.parametrize("fmi_version", [2, 3])
@pytest.mark.parametrize(
    "name, value, message",
    BAD_VALUES
    + [
        (
            "solver",
            6,
            "solver = 6: choose 0 to 5 (0 = rk4, 1 = rk45, 2 = dop853, 3 = radau, 4 = auto, 5 = bdf)",
        ),
    ],
)
def test_a_bad_value_is_an_error_and_the_instance_goes_on(built_fmu, fmi_version, name, value, message):
    """fmi2Error, fmi3Error naming the value, which is not taken; the instance goes on as it
    was, and after a reset."""
    fmu = INSTANCES[fmi_version](
        built_fmu(COUPLED, backend="native", fmi_version=fmi_version), initialize=False
    )
    with pytest.raises(FMICallException) as failure:
        fmu.set({name: value})
    assert failure.value.status == ERROR
    assert any(status == ERROR and text.startswith(message) for status, text in fmu.messages), fmu.messages
    fmu.initialize()
    fmu.step(0.1)
    assert np.isfinite(fmu.get("alpha0", "energy")).all()
    fmu.fmu.reset()
    fmu.time = 0.0
    fmu.set({"l0": 7.0})
    fmu.initialize()
    fmu.step(0.5)
    assert np.isfinite(fmu.get("alpha0", "energy")).all()
    fmu.close()


def test_wrong_references_and_states_are_errors_not_crashes(native):
    fmu = Instance(native, initialize=False)
    fmu.fmu.setupExperiment(startTime=0.0)
    fmu.fmu.enterInitializationMode()  # where getters are allowed (tests/test_state_machine.py)
    for call in (
        lambda: fmu.fmu.getReal([10_000]),
        lambda: fmu.fmu.setInteger([0], [1]),
        lambda: fmu.fmu.doStep(0.0, 0.1),
        lambda: fmu.fmu.getBoolean([0]),
        lambda: fmu.fmu.fmi2GetReal(fmu.fmu.component, None, 1, None),
    ):  # null pointers
        with pytest.raises(FMICallException) as failure:
            call()
        assert failure.value.status == 3
    texts = " ".join(text for _, text in fmu.messages)
    assert "10000 is not a Real variable" in texts and "no Boolean variables" in texts
    assert "fmi2DoStep is not allowed in state initializationMode" in texts
    assert "fmi2GetReal: vr or value is NULL" in texts
    fmu.close(after_fatal=True)


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_a_failed_step_is_discarded_with_the_diagnosis_and_reset_goes_on(built_fmu, fmi_version):
    """The singular two-angle joint of the envelope: a massless link along its parent's x axis.
    The instance stays at its start; FMI 2.0 says so by fmi2LastSuccessfulTime, FMI 3.0 by time."""
    path = built_fmu(Scene(links=(Link(), Link(has_mass=False))), backend="native", fmi_version=fmi_version)
    fmu = INSTANCES[fmi_version](path, start_values={"alpha1": np.pi / 2, "beta1": 0.0, "solver": 0})
    before = fmu.get("alpha0", "alpha1", "omega0")
    with pytest.raises(FMICallException) as failure:
        fmu.step(0.1)
    assert failure.value.status == DISCARD
    text = fmu.texts(DISCARD)
    assert "singular mass matrix" in text and "link 1" in text
    assert fmu.get("alpha0", "alpha1", "omega0") == before
    if fmi_version == 2:
        assert fmu.fmu.getRealStatus(2) == 0.0  # fmi2LastSuccessfulTime: nothing was taken
        with pytest.raises(FMICallException):  # a discarded step: only reset or a saved state go on
            fmu.step(0.1)
    else:
        assert fmu.get("time") == [0.0]
    fmu.fmu.reset()
    fmu.initialize()
    fmu.time = 0.0
    fmu.step(0.1)
    assert np.isfinite(fmu.get("alpha0")).all()
    fmu.close()


@pytest.mark.tools
@pytest.mark.parametrize("fmi_version", [2, 3])
def test_the_windows_binary_runs_under_wine(built_fmu, c_host, fmi_version, tmp_path):
    """The Windows binary cross-compiled with Debian's mingw-w64 (it needs only Windows' own
    DLLs), run by the same C host built for Windows, under Debian's wine64; it agrees with the
    Linux binary."""
    compiler = require_tool(
        "x86_64-w64-mingw32-gcc", None, "Debian's gcc-mingw-w64-x86-64 (.ci/run installs it)"
    )
    wine = require_tool("wine64", "/usr/lib/wine/wine64", "Debian's wine64 (.ci/run installs it)")
    both = built_fmu(COUPLED, backend="native", fmi_version=fmi_version, platforms=("linux64", "win64"))
    assert validate_fmu(str(both)) == []
    folder = unzipped(both, tmp_path / "fmu")
    dll = c_hosts.binary(fmi_version, folder, "win64")
    objdump = subprocess.run(
        ["x86_64-w64-mingw32-objdump", "-p", str(dll)], capture_output=True, text=True, check=True
    ).stdout
    assert {line.split(":")[1].strip() for line in objdump.splitlines() if "DLL Name" in line} == {
        "KERNEL32.dll",
        "msvcrt.dll",
    }
    exe = c_hosts.compile_host(fmi_version, compiler, tmp_path / "fmi_host.exe", "-static-libgcc")
    shutil.copy2(dll, tmp_path / dll.name)
    args = c_hosts.host_arguments(fmi_version, both)
    env = {"WINEDEBUG": "-all", "HOME": str(tmp_path), "WINEPREFIX": str(tmp_path / "wine")}
    servers = set(Path("/tmp").glob("wine-*"))
    try:
        windows = subprocess.run(
            [wine, str(exe), dll.name, *args], cwd=tmp_path, check=False, capture_output=True,
            text=True, timeout=600, env=env,
        )  # fmt: skip
    finally:  # wine's server keeps a folder in /tmp whatever TMPDIR says: stopped, and removed
        subprocess.run([str(Path(wine).parent / "wineserver"), "-k"], env=env, check=False, timeout=60)
        for server in set(Path("/tmp").glob("wine-*")) - servers:
            shutil.rmtree(server, ignore_errors=True)
    assert windows.returncode == 0, windows.stderr[-2000:]
    linux = subprocess.run(
        [str(c_host(fmi_version)), str(c_hosts.binary(fmi_version, folder)), *args],
        capture_output=True,
        text=True,
        env={},
        check=True,
    )
    rows = [c_hosts.rows_of(run) for run in (windows, linux)]
    assert rows[0].shape == rows[1].shape == (601, 1 + len(c_hosts.OUTPUTS[fmi_version]))
    np.testing.assert_allclose(rows[0], rows[1], rtol=1e-12, atol=1e-12)  # libm differs, not the C


# a minute or two: the cross-compiled FMU built for three platforms, and qemu emulating every
# ARM instruction of the host's run; the only run of the aarch64 binary
@pytest.mark.tools
def test_the_aarch64_binary_runs_under_qemu_as_the_x86_64_one(built_fmu, c_host, tmp_path):
    """One FMI 3.0 FMU carrying every platform: its aarch64-linux binary, cross-compiled with
    Debian's gcc-aarch64-linux-gnu, run by the C host cross-compiled alike under qemu-user
    (the ARM libc from the cross toolchain, -L), gives the x86-64 binary's results: to 1e-12
    asked; both compile the same C with contraction off (-std=c99), so bit for bit here."""
    compiler = require_tool(
        "aarch64-linux-gnu-gcc", None, "Debian's gcc-aarch64-linux-gnu (.ci/run installs it)"
    )
    require_tool("x86_64-w64-mingw32-gcc", None, "Debian's gcc-mingw-w64-x86-64 (.ci/run installs it)")
    qemu = require_tool("qemu-aarch64", None, "Debian's qemu-user (.ci/run installs it)")
    loader = require_tool(
        "the aarch64 libc",
        "/usr/aarch64-linux-gnu/lib/ld-linux-aarch64.so.1",
        "Debian's libc6-arm64-cross (with gcc-aarch64-linux-gnu)",
    )
    every = built_fmu(
        COUPLED, backend="native", fmi_version=3, platforms=("linux64", "win64", "aarch64-linux")
    )
    assert validate_fmu(str(every)) == []
    with zipfile.ZipFile(every) as archive:
        folders = {Path(name).parent.name for name in archive.namelist() if name.startswith("binaries/")}
    assert folders == {"x86_64-linux", "x86_64-windows", "aarch64-linux"}
    folder = unzipped(every, tmp_path / "fmu")
    arm = c_hosts.binary(3, folder, "aarch64-linux")
    header = arm.read_bytes()[:20]
    assert header[:4] == b"\x7fELF" and struct.unpack("<H", header[18:20])[0] == 183  # EM_AARCH64
    host = c_hosts.compile_host(3, compiler, tmp_path / "fmi3_host_aarch64", "-ldl")
    args = c_hosts.host_arguments(3, every)
    runs = [
        subprocess.run(command, capture_output=True, text=True, env={}, check=False, timeout=600)
        for command in (
            [qemu, "-L", str(Path(loader).parents[1]), str(host), str(arm), *args],
            [str(c_host(3)), str(c_hosts.binary(3, folder)), *args],
        )
    ]
    assert [run.returncode for run in runs] == [0, 0], runs[0].stderr[-2000:]
    rows = [c_hosts.rows_of(run) for run in runs]
    assert rows[0].shape == rows[1].shape == (601, 1 + len(c_hosts.OUTPUTS[3]))
    np.testing.assert_allclose(rows[0], rows[1], rtol=0, atol=1e-12)


def test_the_fmi2_fmu_has_no_arm_binary_and_says_why(tmp_path):
    """FMI 2.0.4 names an ARM Linux binary's folder aarch64-linux, FMPy 0.3.32 and OpenModelica
    look in linux64 (docs/native.md#platforms): the build refuses rather than pick one."""
    with pytest.raises(ValueError, match=r"FMI 2.0 names no binaries folder for 'aarch64-linux' "):
        build_fmu(COUPLED, tmp_path / "A.fmu", backend="native", platforms=("linux64", "aarch64-linux"))
    assert not list(tmp_path.iterdir())
