"""The pendulum as a native model: its C files behind the model contract (fmu_model.h), its
own lines of fmu_config.h, its FMI 3.0 arrays' dimension, and its native FMU (FMI 2.0 or
3.0: builder.native packs it, as it packs the cart of builder.cart)."""

from __future__ import annotations

from pathlib import Path

from ..runtime.files import MODEL_NAME
from ..runtime.rules import RULES, rule_of
from ..scene import Scene
from . import c_literals as c
from .compiler import CoreBuild
from .fmu_config import RULE_INDEX
from .native import write_model_fmu
from .native_model import Dimension, NativeModel
from .variables import Variable, groups


def _config(data: dict, records: list[Variable]) -> list[str]:
    """The pendulum's own lines of fmu_config.h: its value references checked against the
    core's arrays (model.h), its Integer settings' starts and rules, the carried step's rule."""
    n_state = sum(v.group == "states" for v in records)
    step_rule, step_what = rule_of("h")
    return c.fill(
        "pendulum_config.h.in",
        n_state=n_state,
        defines="\n".join(
            [
                c.define("CP_SOLVER_START", data["settings"]["solver"]),
                c.define("CP_MAX_STEPS_START", data["settings"]["max_steps"]),
                c.define("CP_SOLVER_RULE", RULE_INDEX["native-solver"]),
                c.define("CP_MAX_STEPS_RULE", RULE_INDEX[rule_of("max_steps")[0]]),
                c.define("CP_ACROSS_POINTS_START", data["settings"]["across_points"]),
                c.define("CP_ACROSS_POINTS_RULE", RULE_INDEX[rule_of("across_points")[0]]),
                c.define("CP_STEP_RULE", RULE_INDEX[step_rule]),
                c.define("CP_STEP_WHAT", c.string(step_what)),
            ]
        ),
    ).splitlines()


PENDULUM = NativeModel(
    MODEL_NAME,
    (
        "model.c",
        "dynamics.c",
        "chain.c",
        "solvers.c",
        "diagnosis.c",
        "cosim.c",
        "directional.c",
        "second_directional.c",
        "rules.c",
    )
    + ("variable_table.c", "pendulum_model.c"),
    ("model.h", "real.h", "dynamics.h", "chain.h", "solvers.h", "tableaus.h", "status.h", "diagnosis.h")
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


def check_settings(settings: dict) -> None:
    """What the native FMU refuses of settings the pythonfmu FMU takes (its solvers)."""
    if settings["solver"] >= RULES["native-solver"].high:
        raise ValueError(f"solver = {settings['solver']}: {RULES['native-solver'].refusal}")


def write_native_fmu(
    scene: Scene,
    core: CoreBuild,
    data: dict,
    output: Path,
    platforms: tuple[str, ...] = ("linux64",),
    fmi_version: int = 2,
) -> None:
    """The native FMU of a scene at `output` (moved into place only when complete), with a
    binary for each of `platforms` ("linux64", "win64"), from its compiled core and the
    data its model.json holds; builder.fmu.build_fmu(backend="native") checks the output
    and the settings (check_settings) and makes both. fmi_version=3: the FMI 3.0 FMU."""
    generated = {name: core.directory / name for name in ("model.c", "model.h")}
    write_model_fmu(PENDULUM, data, output, platforms, fmi_version, generated)
