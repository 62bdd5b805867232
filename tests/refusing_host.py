"""A Python host that has an FMU refuse values, then exits as a script does.

    python refusing_host.py FMU KIND [KIND ...]

Each KIND is one refusal (REFUSALS): a run of fmpy.simulate_fmu with a bad start value or
setting, which fails at the first call and leaves the FMU's library loaded as fmpy does, or
a state the FMU refuses in fmi2SetFMUstate, after which the instance stays unfreed. Prints
"refused N" when every call was refused, then returns from the script normally: whatever
happens after that line is the process's exit.
"""

from __future__ import annotations

import sys

import fmpy
from fmpy.fmi2 import FMU2Slave
from fmpy.simulation import FMICallException

START_VALUES = {  # bad values of each kind, refused at their fmi2SetReal / fmi2SetInteger
    "nan": {"g": float("nan")},
    "inf": {"alpha0": float("inf")},
    "negative_length": {"l0": -1.0},
    "bad_setting": {"max_steps": 0},
}
REFUSALS = (*START_VALUES, "state")


def refuse_start_value(fmu: str, kind: str) -> None:
    try:
        fmpy.simulate_fmu(fmu, stop_time=0.1, start_values=START_VALUES[kind])
    except FMICallException:
        return
    raise SystemExit(f"{kind}: not refused")


def refuse_state(fmu: str) -> None:
    """Bytes that are no state, deserialized and set: refused, and the instance left as it is."""
    md = fmpy.read_model_description(fmu)
    slave = FMU2Slave(
        guid=md.guid,
        unzipDirectory=fmpy.extract(fmu),
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="refusing_host",
    )
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    try:
        slave.setFMUState(slave.deserializeFMUState(b"\xff not a state"))
    except FMICallException:
        return
    raise SystemExit("state: not refused")


def main(fmu: str, kinds: list[str]) -> None:
    for kind in kinds:
        if kind == "state":
            refuse_state(fmu)
        else:
            refuse_start_value(fmu, kind)
    print(f"refused {len(kinds)}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
