"""An SSP package in libcosim (libcosimpy), one process per job, results as JSON on stdout.

    python -m conical_pendulum.demos.libcosim_run JOB_JSON

JOB_JSON: {"ssp": path, "stop_time": 10.0, "record": ["cart::x", "p::alpha0"]}. "ssp" is a
.ssp file (libcosim reads its SystemStructure.ssd) or an .ssd file among the package's
unpacked files (a variant). libcosim takes the step from the package itself (the
default experiment's osp:FixedStepAlgorithm) and applies each component's first
parameter set. The last line printed is {"values": {"time": [...], name: [...]}}: the
recorded variables after each step (libcosim initialises at its first step).

A process of its own (demos/isolated.py): libcosim aborts the process on an internal
error, and a pythonfmu FMU can abort an interpreter at exit.
"""

from __future__ import annotations

import json
import sys

from . import isolated

MODULE = "conical_pendulum.demos.libcosim_run"


def missing() -> str | None:
    """'libcosimpy' when this environment lacks it, else None."""
    import importlib.util

    return "libcosimpy" if importlib.util.find_spec("libcosimpy") is None else None


def simulate(job: dict, timeout: float = 600.0) -> dict:
    """The job's run, in a fresh interpreter; RuntimeError when libcosim failed."""
    return isolated.answer(isolated.call(MODULE, job, timeout, "libcosim"), "libcosim")


def _simulate(job: dict) -> dict:
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_ssp_file(job["ssp"])
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    slaves = {info.name.decode(): info.index for info in execution.slave_infos()}
    references = {
        name: {v.name.decode(): v.reference for v in execution.slave_variables(index)}
        for name, index in slaves.items()
    }
    record = [name.split("::") for name in job["record"]]
    values = {name: [] for name in ["time", *job["record"]]}
    while True:
        if not execution.step():
            raise RuntimeError(
                f"libcosim: a step failed at t = {values['time'][-1] if values['time'] else 0} s"
            )
        now = execution.status().current_time * 1e-9  # libcosim counts nanoseconds
        values["time"].append(now)
        for name, (instance, variable) in zip(job["record"], record):
            values[name].append(
                observer.last_real_values(slaves[instance], [references[instance][variable]])[0]
            )
        if now >= job["stop_time"] - 1e-9:
            break
    return {"values": values}


def main(argv=None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print(f"usage: python -m {MODULE} JOB_JSON (see its docstring)", file=sys.stderr)
        sys.exit(2)
    isolated.reply(_simulate(json.loads(argv[0])))


if __name__ == "__main__":
    main()
