"""The SSP package (demos/ssp.py) in each tool that reads SSP, as that tool reads it.

    ecospy    ecos' library through ecospy: EcosSimulation(ssp_path=...), the scheme's
              parameter set applied by name (demos/ecospy_run.py, its own process)
    ecos      ecos' command-line engine from the ecospy wheel, `ecos simulate --path ...
              --parameterSet ...`, in an empty environment but for LD_LIBRARY_PATH to a
              folder holding its libtbb alone: no Python in the loop
    libcosim  libcosim through libcosimpy: CosimExecution.from_ssp_file, the step from the
              package's OSP annotation (demos/libcosim_run.py, its own process)
    fmpy      FMPy's fmpy.ssp.simulation.simulate_ssp, in this process
    omsimulator
              OpenModelica's OMSimulator command line (omsimulator()), the .ssp as written:
              `OMSimulator PACKAGE.ssp --stopTime=...` for SystemStructure.ssd, and for
              another variant a Lua script that activates it (oms_activateVariant)

ecos and FMPy read SystemStructure.ssd only: a variant runs from the package unpacked
with its SSD in that file's place (ssp.variant; FMPy needs it zipped again); libcosim is
given the variant's .ssd; OMSimulator loads every .ssd of the package as a variant. ecos
and FMPy take the step and stop time from their caller, which reads them from the package
(ssp.experiment); OMSimulator the step from its annotation, the stop time from its caller
(its --stopTime, 1 s unless given, replaces the default experiment's). Each run gives the recorded variables
by their FMU names (x, v, a, F_pivot_x, alpha0, ...) with "time", as coupled.cosimulate
does, so coupled.coupling_errors compares them with the monolithic model.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import signal
import subprocess
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import ecospy_run, isolated, libcosim_run, ssp
from .coupled import DIVERGED, EXCHANGED

TOOLS = ("ecospy", "ecos", "libcosim", "fmpy", "omsimulator")
OUTSIDE_PIP = ("omsimulator",)  # tools no pip extra installs
# OMSimulator comes from no package registry: the environment variable that names its executable
# (.ci/run sets it for the workplace's build), else OMSimulator on PATH
OMSIMULATOR = "OMSIMULATOR"
ECOS_MIN_STEPS = 10  # ecos 0.7.2's command line reports progress every (steps // 10) steps


@dataclass
class ToolRun:
    tool: str
    scheme: str
    values: dict  # {"time": array, variable: array}, empty when refused
    seconds: float  # wall time of the call that runs it: a process for ecospy, ecos and libcosim
    warnings: list[str] = field(default_factory=list)  # what the tool printed as warnings or errors
    refused: str | None = None  # why the tool could not run it
    ended: str | None = None  # why the run stopped early (ecospy: the cart beyond coupled.DIVERGED)

    def as_run(self) -> dict:
        """The run as coupled.coupling_errors takes it."""
        return {**self.values, "seconds": self.seconds, "ended": self.ended}


def missing(tool: str) -> str | None:
    """What the environment lacks to run `tool` (a pip package), or None."""
    if tool in ("ecospy", "ecos"):
        return ecospy_run.missing()
    if tool == "libcosim":
        return libcosim_run.missing()
    if tool == "omsimulator" and omsimulator() is None:
        named = os.environ.get(OMSIMULATOR)
        if named:
            return f"OMSimulator: {OMSIMULATOR}={named} is not an executable file"
        return (
            f"OMSimulator (OpenModelica's; no package registry offers it): put it on PATH "
            f"or name its executable in the environment variable {OMSIMULATOR}"
        )
    return None


def _short(values: dict, separator: str) -> dict:
    return {name.split(separator)[-1]: np.array(column) for name, column in values.items()}


def _warnings(text: str) -> list[str]:
    return [line.strip() for line in text.splitlines() if any(w in line.lower() for w in ("warn", "error"))]


def run_ecospy(package: Path, scheme: str, work: Path) -> ToolRun:
    step, stop_time = ssp.experiment(package)
    folder = ssp.variant(package, scheme, work / f"ecospy-{scheme}")
    job = ecospy_run.check_job(
        {
            "ssp": str(folder),
            "parameter_set": scheme,
            "steps": [step],
            "stop_time": stop_time,
            "record": EXCHANGED,
            "limits": {"cart::x": DIVERGED},
        }
    )
    start = time.perf_counter()
    child = isolated.call(ecospy_run.MODULE, job, 1800.0, "ecospy")
    (run,) = isolated.answer(child, "ecospy")["runs"]
    seconds = time.perf_counter() - start
    return ToolRun(
        "ecospy", scheme, _short(run["values"], "::"), seconds, _warnings(child.stderr), None, run["ended"]
    )


def ecos_binary() -> Path:
    """ecos' command-line engine as the ecospy wheel ships it (found without importing
    ecospy, whose library needs libtbb loaded first)."""
    return Path(importlib.util.find_spec("ecospy").submodule_search_locations[0]) / "binaries" / "ecos"


def run_ecos(package: Path, scheme: str, work: Path) -> ToolRun:
    step, stop_time = ssp.experiment(package)
    if round(stop_time / step) < ECOS_MIN_STEPS:
        return ToolRun(
            "ecos",
            scheme,
            {},
            0.0,
            refused=f"fewer than {ECOS_MIN_STEPS} steps: ecos 0.7.2's command line takes its progress "
            "step modulo (steps // 10) and dies of SIGFPE",
        )
    home = work / f"ecos-{scheme}"
    folder = ssp.variant(package, scheme, home / "package")
    (home / "lib").mkdir(exist_ok=True)
    engine = home / "ecos"
    shutil.copy2(ecos_binary(), engine)
    engine.chmod(0o755)
    shutil.copy2(Path(ecospy_run.TBB), home / "lib")  # its one dependency outside the system
    command = [str(engine), "simulate", "--path", str(folder), "--stopTime", repr(stop_time)]
    command += ["--stepSize", repr(step), "--parameterSet", scheme, "--noParallel", "-l", "warn"]
    start = time.perf_counter()
    child = subprocess.run(
        command,
        cwd=home,
        env={"LD_LIBRARY_PATH": str(home / "lib")},
        check=False,
        capture_output=True,
        text=True,
        timeout=1800,
    )
    seconds = time.perf_counter() - start
    warnings = _warnings(child.stdout + child.stderr)
    if child.returncode != 0:
        how = (
            f"killed by {signal.Signals(-child.returncode).name}"
            if child.returncode < 0
            else f"exit {child.returncode}"
        )
        return ToolRun(
            "ecos", scheme, {}, seconds, warnings, f"{how}: {(child.stderr or child.stdout)[-500:]}"
        )
    # its CSV: a row after initialisation and after each step, every value with six decimals
    table = np.genfromtxt(home / "package.csv", delimiter=",", names=True, deletechars="", autostrip=True)
    values = {"time": table["time"]}
    for name in EXCHANGED:
        values[name.split("::")[-1]] = table[f"{name}[REAL]"]
    return ToolRun("ecos", scheme, values, seconds, warnings)


def run_libcosim(package: Path, scheme: str, work: Path) -> ToolRun:
    _, stop_time = ssp.experiment(package)
    if ssp.VARIANTS[scheme] == "SystemStructure.ssd":
        source = package  # the .ssp itself
    else:
        folder = work / "libcosim-unpacked"
        if not folder.exists():
            with zipfile.ZipFile(package) as archive:
                archive.extractall(folder)
        source = folder / ssp.VARIANTS[scheme]
    start = time.perf_counter()
    job = {"ssp": str(source), "stop_time": stop_time, "record": EXCHANGED}
    child = isolated.call(libcosim_run.MODULE, job, 1800.0, "libcosim")
    run = isolated.answer(child, "libcosim")
    seconds = time.perf_counter() - start
    return ToolRun("libcosim", scheme, _short(run["values"], "::"), seconds, _warnings(child.stderr))


def run_fmpy(package: Path, scheme: str, work: Path) -> ToolRun:
    """simulate_ssp takes neither the package's parameter bindings nor its default
    experiment: the scheme's .ssv goes in as its parameter_set, with the names prefixed by
    the component as its set_parameters matches them, and the step and stop time as
    arguments. Its rows carry the time a step started and the values after it: they are
    put at the time the values hold. Its loop adds the step to the time while time <
    stop_time, so rounding can give it one step more than asked: that row is left out. When
    an FMU refuses a step (a diverging run), simulate_ssp raises and gives back none of it."""
    from fmpy.fmi1 import FMICallException
    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import read_ssv

    step, stop_time = ssp.experiment(package)
    source = package
    if ssp.VARIANTS[scheme] != "SystemStructure.ssd":
        folder = ssp.variant(package, scheme, work / f"fmpy-{scheme}")
        source = Path(shutil.make_archive(str(work / f"fmpy-{scheme}"), "zip", folder)).rename(
            work / f"fmpy-{scheme}.ssp"
        )
    parameters = read_ssv(str(package), resource=ssp.parameter_file(scheme))
    for parameter in parameters.parameters:
        parameter.name = f"cart.{parameter.name}"
    start = time.perf_counter()
    try:
        rows = simulate_ssp(str(source), stop_time=stop_time, step_size=step, parameter_set=parameters)
    except FMICallException as exc:  # an FMU refused a step (a diverging run): none of its rows come back
        return ToolRun("fmpy", scheme, {}, time.perf_counter() - start, refused=f"simulate_ssp raised: {exc}")
    seconds = time.perf_counter() - start
    values = {"time": rows["time"] + step}
    values.update({name.split(".")[-1]: rows[name] for name in rows.dtype.names if name != "time"})
    kept = values["time"] <= stop_time + step / 2
    return ToolRun("fmpy", scheme, {name: column[kept] for name, column in values.items()}, seconds)


def omsimulator() -> Path | None:
    """OMSimulator's executable: the one $OMSIMULATOR names, else OMSimulator on PATH; None if neither."""
    named = os.environ.get(OMSIMULATOR)
    if named:
        path = Path(named)
        return path if path.is_file() and os.access(path, os.X_OK) else None
    found = shutil.which("OMSimulator")
    return Path(found) if found else None


def _oms_messages(text: str, level: str) -> list[str]:
    """OMSimulator's messages of a level ("error", "warning"), each with its indented lines."""
    messages: list[str] = []
    for line in text.splitlines():
        if line.startswith(f"{level}:"):
            messages.append(line.split(":", 1)[1].strip())
        elif messages and line.startswith(" ") and not line.lstrip().startswith(("info", "warning", "error")):
            messages[-1] += " " + line.strip()
    return messages


def _oms_values(result: Path, model: str) -> dict:
    """The recorded variables from OMSimulator's CSV by their FMU names, one row per
    communication point: it writes two for each, the outputs after the step with the
    inputs still held, then again once the inputs are set (the loop solved); the last is
    kept, the values the next step starts from, as the other tools report them."""
    table = np.genfromtxt(result, delimiter=",", names=True, deletechars="", autostrip=True, ndmin=1)
    last = np.append(table["time"][1:] != table["time"][:-1], True)
    values = {"time": table["time"][last]}
    for name in EXCHANGED:
        instance, variable = name.split("::")
        values[variable] = table[f"{model}.{ssp.SYSTEM}.{instance}.{variable}"][last]
    return values


def run_omsimulator(package: Path, scheme: str, work: Path, options: tuple[str, ...] = ()) -> ToolRun:
    """The package as written: its default variant from the command line, another one
    activated by a Lua script (this OMSimulator's scripting; its command line runs
    SystemStructure.ssd only); `options`, its command line's (--inputExtrapolation=true, ...),
    apply to both. It exits 0 whether or not the run failed: what it printed says, `error:`
    lines. A run that stopped before the stop time keeps its rows, with the first error as
    why it ended; one that reached it despite errors lists them with its warnings."""
    _, stop_time = ssp.experiment(package)
    home = work / f"omsimulator-{scheme}"
    if home.exists():
        shutil.rmtree(home)
    home.mkdir(parents=True)
    model = ssp.model_name(scheme)
    result = home / "result.csv"
    if ssp.VARIANTS[scheme] == "SystemStructure.ssd":
        command = [str(package), f"--stopTime={stop_time!r}", f"--resultFile={result.name}"]
    else:
        script = home / "run.lua"
        default = ssp.model_name(next(s for s, name in ssp.VARIANTS.items() if name == "SystemStructure.ssd"))
        script.write_text(
            f'oms_importFile("{package}")\n'
            f'oms_activateVariant("{default}", "{model}")\n'
            f'oms_setResultFile("{model}", "{result.name}", 1)\n'
            f'oms_setStopTime("{model}", {stop_time!r})\n'
            + "".join(f'oms_{call}("{model}")\n' for call in ("instantiate", "initialize", "simulate"))
            + f'oms_terminate("{model}")\noms_delete("{model}")\n'
        )
        command = [script.name]
    start = time.perf_counter()
    child = subprocess.run(
        [str(omsimulator()), *command, *options, f"--tempDir={home}"],
        cwd=home,
        check=False,
        capture_output=True,
        text=True,
        timeout=1800,
    )
    seconds = time.perf_counter() - start
    printed = child.stdout + child.stderr
    (home / "omsimulator.log").write_text(printed)
    errors, warnings = _oms_messages(printed, "error"), _oms_messages(printed, "warning")
    values = _oms_values(result, model) if result.exists() and result.stat().st_size else {}
    if child.returncode or not values or len(values["time"]) < 2:
        why = "; ".join(errors) or f"exit {child.returncode}, no result: {printed[-500:]}"
        return ToolRun("omsimulator", scheme, {}, seconds, warnings, why)
    step, _ = ssp.experiment(package)
    ended = errors[0] if errors and values["time"][-1] < stop_time - step / 2 else None
    return ToolRun("omsimulator", scheme, values, seconds, warnings + errors, None, ended)


RUNNERS = {
    "ecospy": run_ecospy,
    "ecos": run_ecos,
    "libcosim": run_libcosim,
    "fmpy": run_fmpy,
    "omsimulator": run_omsimulator,
}


def run(tool: str, package: Path, scheme: str, work: Path) -> ToolRun:
    """The package's `scheme` variant in `tool` (one of TOOLS), with scratch files in `work`
    (a folder for this package alone); a run that the tool refused says why in `refused`."""
    work = work.absolute()
    work.mkdir(parents=True, exist_ok=True)
    try:
        return RUNNERS[tool](package.absolute(), scheme, work)
    except RuntimeError as exc:  # an engine's process failed: what it said
        return ToolRun(tool, scheme, {}, 0.0, refused=str(exc))
