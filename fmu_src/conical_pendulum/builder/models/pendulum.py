"""The pendulum as a native model: its C files behind the model contract (fmu_model.h), its
own lines of fmu_config.h, its FMI 3.0 arrays' dimension, and its native FMU (FMI 2.0 or
3.0: builder.packaging.native packs it, as it packs the cart of builder.models.cart); and the fmu_config.h
of the same model compiled into the core for the pythonfmu slave (core_config)."""

from __future__ import annotations

import json
from pathlib import Path

from ...runtime.files import MODEL_NAME
from ...runtime.rules import SETTINGS, rule_of
from ...scene import Scene
from .. import c_literals as c
from ..fmi.contract import Dimension, NativeModel
from ..fmi.fmu_config import RULE_INDEX, config_header
from ..fmi.variables import Variable, groups, variables_of
from ..packaging.native import write_model_fmu

DEFAULT_SETTINGS = {name: setting.default for name, setting in SETTINGS.items()}


def _config(data: dict, records: list[Variable]) -> list[str]:
    """The pendulum's own lines of fmu_config.h: its value references checked against the
    core's arrays (model.h), its Integer settings' starts and rules (the solver's from its
    record: the native FMU's solvers in C, or every solver in the pythonfmu slave's), the
    carried step's rule."""
    n_state = sum(v.group == "states" for v in records)
    solver = next(v for v in records if v.name == "solver")
    step_rule, step_what = rule_of("h")
    return c.fill(
        "pendulum_config.h.in",
        n_state=n_state,
        defines="\n".join(
            [
                c.define("CP_SOLVER_START", data["settings"]["solver"]),
                c.define("CP_MAX_STEPS_START", data["settings"]["max_steps"]),
                c.define("CP_SOLVER_RULE", RULE_INDEX[solver.rule]),
                c.define("CP_MAX_STEPS_RULE", RULE_INDEX[rule_of("max_steps")[0]]),
                c.define("CP_ACROSS_POINTS_START", data["settings"]["across_points"]),
                c.define("CP_ACROSS_POINTS_RULE", RULE_INDEX[rule_of("across_points")[0]]),
                c.define("CP_STEP_RULE", RULE_INDEX[step_rule]),
                c.define("CP_STEP_WHAT", c.string(step_what)),
            ]
        ),
    ).splitlines()


# The C both the compiled core and the native FMU build: the model's numerics
# (runtime/csrc/core), then the model behind fmu_model.h. The native FMU adds the
# derivatives' complex-step copies; the compiled core adds them too, at its own -O levels
# (builder/compiler.py).
CORE_SOURCES = (
    "model.c",
    "dynamics.c",
    "solvers.c",
    "newton.c",
    "radau.c",
    "bdf.c",
    "diagnosis.c",
    "cosim.c",
    "chain.c",
)
MODEL_SOURCES = ("rules.c", "variable_table.c", "pendulum_model.c")

PENDULUM = NativeModel(
    MODEL_NAME,
    CORE_SOURCES + ("directional.c", "second_directional.c") + MODEL_SOURCES,
    ("model.h", "real.h", "dynamics.h", "chain.h", "solvers.h", "solver_common.h", "tableaus.h")
    + ("status.h", "diagnosis.h")
    + ("cosim.h", "directional.h", "model_copy.h", "rules.h", "variable_table.h"),
    lambda: groups("native"),
    _config,
    1.0 / 60.0,
    (2, 3),
    Dimension(
        "n_links",
        "number of links: the size of every per-link array",
        "the number of links is fixed when the FMU is built ({size}); build the FMU of another scene",
    ),
)


def core_config(scene: Scene, settings: dict) -> str:
    """fmu_config.h of the model the pythonfmu slave holds through the compiled core
    (builder.compiler): the native FMU's variable table (its value references, the state
    derivatives' too); no GUID, which only the FMI glue checks."""
    found = variables_of(groups("native"), scene, settings)
    return config_header(PENDULUM, {"settings": settings}, found, guid="")


def core_config_key(scene: Scene, settings: dict) -> str:
    """What core_config's fmu_config.h is made of beyond the scene's cache fields and the
    generator's sources, for the compiled core's cache key: the scene's parameter and state
    starts (two scenes of one structure differ in them, and the table's starts are what the
    pythonfmu FMU runs and resets to), the settings and the variable groups in order
    (builder.fmi.variables.GROUPS, which a caller may extend)."""
    layout = [
        [g.name, g.type, g.causality, g.variability, g.initial, g.c_name, g.named]
        + [g.members.__module__, g.members.__qualname__]
        for g in groups("native")
    ]
    starts = [list(scene.parameters()), list(scene.initial_state())]
    return json.dumps([starts, settings, layout], sort_keys=True)


def write_native_fmu(
    scene: Scene,
    core_directory: Path,
    data: dict,
    output: Path,
    platforms: tuple[str, ...] = ("linux64",),
    fmi_version: int = 2,
) -> None:
    """The native FMU of a scene at `output` (moved into place only when complete), with a
    binary for each of `platforms` ("linux64", "win64"), from its compiled core's generated
    C (in core_directory) and the data its model.json holds; builder.fmu.build_fmu(backend="native") checks the output
    and the settings (check_settings) and makes both. fmi_version=3: the FMI 3.0 FMU."""
    generated = {name: core_directory / name for name in ("model.c", "model.h")}
    write_model_fmu(PENDULUM, data, output, platforms, fmi_version, generated)
