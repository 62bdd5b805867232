"""Co-simulations in ecospy (libecos), one process per job, results as JSON on stdout.

    python -m conical_pendulum.demos.ecospy_run JOB_JSON

JOB_JSON is a JSON object (the text itself):

    {"models": {"p": "dist/Coupled.fmu", "cart": "dist/Cart.fmu"},      # instance name -> FMU
     "connections": [["cart::a", "p::a_pivot_x"], ["p::F_pivot_x", "cart::F_x"]],  # real, from -> to
     "parameters": {"cart::m_cart": 30.0},     # one parameter set, applied at initialisation
     "steps": [0.1, 0.05],                     # communication step sizes [s], one run each
     "stop_time": 10.0,
     "record": ["cart::x", "p::alpha0"],       # variables read at every communication point
     "limits": {"cart::x": 1000.0},            # a run ends where a recorded |value| exceeds its
                                               # limit or is not finite (a diverging exchange)
     "warm_up": true}                          # first one step at the largest step, not reported

Instead of "models", "connections" and "parameters", a job may name an SSP package:
"ssp": its path (a .ssp, or a folder holding it unpacked), whose SystemStructure.ssd ecos
reads, and "parameter_set": the name of one of its parameter sets, applied at
initialisation (demos/ssp.py writes such packages).

Only "steps", "stop_time", "record" and "models" or "ssp" are required. The last line printed is
{"runs": [{"step": dt, "seconds": s, "ended": why or null, "values": {"time": [...], name:
[...]}}]}, one run per step in the order given; "seconds" is the wall time spent in ecospy's
step() (a warm-up run pays the first step's imports, a Python slave's lazy ones, outside
the timings); "ended" says why a run stopped before stop_time (its values end there).

It must be a process of its own (demos/isolated.py): ecospy's library needs libtbb loaded
first, globally (ctypes RTLD_GLOBAL), and pythonfmu 0.7's exit-time destructor can abort
an interpreter that still has an FMU's library mapped. `cosimulate(job)` runs it and
returns the runs.
"""

from __future__ import annotations

import json
import os
import sys

from ..errors import needs
from . import isolated

MODULE = "conical_pendulum.demos.ecospy_run"  # run as python -m MODULE, also when this is __main__
TBB = os.path.join(sys.prefix, "lib", "libtbb.so.12")  # the tbb wheel's library, which ecospy's needs
REQUIRED = ("steps", "stop_time", "record")  # and "models" or "ssp"


def missing() -> str | None:
    """The package of the cosim extra this environment lacks (ecospy, or tbb's library), or
    None: checked without importing ecospy, which needs libtbb loaded first."""
    import importlib.util

    if importlib.util.find_spec("ecospy") is None:
        return "ecospy"
    if not os.path.exists(TBB):
        return "tbb"
    return None


def check_job(job) -> dict:
    """The job with its defaults filled in; ValueError naming what is wrong."""
    if not isinstance(job, dict):
        raise ValueError(f"job: expected a JSON object, got {type(job).__name__}")
    missing = [key for key in REQUIRED if key not in job] + (
        [] if {"models", "ssp"} & set(job) else ["models"]
    )
    if missing:
        raise ValueError(f"job: missing {', '.join(missing)}")
    structure = {"ssp", "parameter_set"} if "ssp" in job else {"models", "connections", "parameters"}
    unknown = sorted(set(job) - {*REQUIRED, *structure, "limits", "warm_up"})
    if unknown:
        raise ValueError(f"job: unknown key(s) {', '.join(unknown)}")
    if "ssp" in job:
        if not isinstance(job["ssp"], str):
            raise ValueError(f"job: ssp must be the path of an SSP package, got {job['ssp']!r}")
    elif not (isinstance(job["models"], dict) and job["models"]):
        raise ValueError("job: models must name at least one FMU, as {instance: path}")
    steps = job["steps"]
    if not (
        isinstance(steps, list)
        and steps
        and all(isinstance(dt, (int, float)) and not isinstance(dt, bool) and dt > 0 for dt in steps)
    ):
        raise ValueError(f"job: steps must be a list of positive numbers, got {steps!r}")
    stop_time = job["stop_time"]
    if isinstance(stop_time, bool) or not isinstance(stop_time, (int, float)) or not stop_time > 0:
        raise ValueError(f"job: stop_time must be a positive number, got {stop_time!r}")
    limits = job.get("limits", {})
    if not (
        isinstance(limits, dict)
        and set(limits) <= set(job["record"])
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0 for v in limits.values())
    ):
        raise ValueError(f"job: limits must map recorded variables to positive numbers, got {limits!r}")
    defaults = {"parameter_set": None} if "ssp" in job else {"connections": [], "parameters": {}}
    return {**defaults, "limits": {}, "warm_up": False, **job}


def _beyond_limits(values: dict, limits: dict) -> str | None:
    """Why the last recorded values end the run, or None."""
    for name, limit in limits.items():
        value = values[name][-1]
        if not abs(value) <= limit:
            return f"{name} = {value:.3g} beyond its limit {limit:g} at t = {values['time'][-1]:.6g} s"
    return None


def cosimulate(job: dict, timeout: float = 1800.0) -> list[dict]:
    """Run the job in a fresh interpreter (demos/isolated.py); its runs, as printed.
    RuntimeError when ecospy fails."""
    run = isolated.call(MODULE, check_job(job), timeout, "ecospy")
    if run.returncode != 0 and ("No module named 'ecospy'" in run.stderr or "libtbb" in run.stderr):
        raise RuntimeError(f"ecospy co-simulation {needs('ecospy and tbb', 'cosim')}")
    return isolated.answer(run, "ecospy")["runs"]


def _simulate(job: dict) -> list[dict]:
    """In this process, with libtbb already loaded: every run of the job."""
    from ecospy import EcosLib, EcosSimulation, EcosSimulationStructure

    EcosLib.set_log_level("warn")
    runs = []
    plan = [(True, max(job["steps"]))] if job["warm_up"] else []
    for warm_up, dt in plan + [(False, dt) for dt in job["steps"]]:
        if "ssp" in job:
            with EcosSimulation(ssp_path=os.path.abspath(job["ssp"]), step_size=dt) as sim:
                run = _run(sim, job, dt, warm_up, job["parameter_set"])
        else:
            with EcosSimulationStructure() as structure:
                for name, path in job["models"].items():
                    structure.add_model(name, os.path.abspath(path))
                for source, target in job["connections"]:
                    structure.make_real_connection(source, target)
                if job["parameters"]:
                    structure.add_parameter_set("job", job["parameters"])
                with EcosSimulation(structure=structure, step_size=dt) as sim:
                    run = _run(sim, job, dt, warm_up, "job" if job["parameters"] else None)
        if not warm_up:
            runs.append(run)
    return runs


def _run(sim, job: dict, dt: float, warm_up: bool, parameter_set: str | None) -> dict:
    """One run of an initialised-to-be EcosSimulation at the step dt (one step if warm_up)."""
    import time

    if parameter_set:
        sim.init(parameter_set=parameter_set)
    else:
        sim.init()
    values = {name: [] for name in ["time", *job["record"]]}
    steps = 1 if warm_up else round(job["stop_time"] / dt)
    ended, stepping = None, 0.0
    for k in range(steps + 1):
        if k:
            start = time.perf_counter()
            sim.step()
            stepping += time.perf_counter() - start
        values["time"].append(sim.get_time())
        for name in job["record"]:
            values[name].append(sim.get_real(name))
        ended = _beyond_limits(values, job["limits"])
        if ended:
            break
    sim.terminate()
    return {"step": dt, "seconds": stepping, "ended": ended, "values": values}


def main(argv=None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print(f"usage: python -m {MODULE} JOB_JSON (see its docstring)", file=sys.stderr)
        sys.exit(2)
    try:
        job = check_job(json.loads(argv[0]))
    except json.JSONDecodeError as exc:
        print(f"ecospy_run: JOB_JSON is not JSON: {exc}", file=sys.stderr)
        sys.exit(2)
    except ValueError as exc:
        print(f"ecospy_run: {exc}", file=sys.stderr)
        sys.exit(2)
    import ctypes

    # before ecospy: its library needs tbb's symbols, which the tbb wheel does not put on its path
    ctypes.CDLL(TBB, mode=ctypes.RTLD_GLOBAL)
    isolated.reply({"runs": _simulate(job)})


if __name__ == "__main__":
    main()
