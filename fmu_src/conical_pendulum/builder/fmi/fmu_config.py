"""fmu_config.h: a native FMU's variable table as C data, from its records (builder.fmi.variables).

Value references, start values, names, value rules, when each variable may be set and its
part in directional derivatives, the log categories; then the defines only its model reads
(NativeModel.config). The C that reads these tables is hand-written: runtime/csrc/
variable_table.c, and each model's own C."""

from __future__ import annotations

import re

from ...runtime.rules import CALCULATED, FIXED, RULES, TUNABLE
from .. import c_literals as c
from .contract import LOG_CATEGORIES, NativeModel
from .variables import Variable, first_references

RULE_INDEX = {name: k for k, name in enumerate(RULES)}  # cp_rules' rows


def real_variables(records: list[Variable]) -> list[Variable]:
    """The Real variables the glue holds in one array by value reference (CP_NREAL): every
    variable before the first Integer (builder.fmi.variables.GROUPS's order)."""
    return records[: next((k for k, v in enumerate(records) if v.type != "Real"), len(records))]


def log_constant(category: str) -> str:
    """The C name of a log category: logStatusError -> CP_LOG_STATUS_ERROR."""
    return "CP_" + re.sub(r"(?<!^)(?=[A-Z])", "_", category).upper()


def settable(variable: Variable) -> str:
    """When a variable may be set, as cp_settable says it: an input always, a tunable
    parameter also at events (not in continuous-time mode), a fixed parameter or an exact start
    value before initialization, a calculated one never."""
    if variable.causality == "input":
        return "CP_SET_ALWAYS"
    if variable.variability == "tunable":
        return "CP_SET_AT_EVENTS"
    if variable.causality == "parameter" or variable.initial in ("exact", "approx"):
        return "CP_SET_BEFORE_INIT"
    return "CP_SET_NEVER"


def role(variable: Variable) -> str:
    """A variable's part in directional derivatives, as cp_role says it: a state is a known
    and an unknown (an output of its own value), an input or a Real parameter a known (FMI
    2.0's knowns of the InitialUnknowns, FMI 3.0's of every list), an output or a state
    derivative an unknown."""
    known = variable.group in ("states", "inputs") or (
        variable.causality == "parameter" and variable.type == "Real"
    )
    unknown = variable.causality == "output" or bool(variable.derivative_of)
    return " | ".join(["CP_KNOWN"] * known + ["CP_UNKNOWN"] * unknown) or "0"


def _rule(rule) -> str:
    return c.initializer(
        [c.double(rule.low), int(rule.low_open), c.double(rule.high), c.string(rule.refusal), int(rule.whole)]
    )


def config_header(model: NativeModel, data: dict, records: list[Variable], guid: str) -> str:
    """fmu_config.h of `model` from its variables' records (and model.json's data, which
    model.config may read)."""
    reals = real_variables(records)
    first = first_references(records, model.groups())
    named = {group.name for group in model.groups() if group.named}
    return c.fill(
        "fmu_config.h.in",
        guid=c.define("CP_GUID", c.string(guid)),
        value_references="\n".join(
            [
                *(c.define(f"CP_VR_{group.c_name}", first[group.name]) for group in model.groups()),
                *(
                    c.define(f"CP_VR_{v.name.upper()}", v.value_reference)
                    for v in records
                    if v.group in named
                ),
            ]
        ),
        n_real=c.define("CP_NREAL", len(reals)),
        finite_rule=c.define("CP_FINITE_RULE", RULE_INDEX["finite"]),
        calculated_message=c.define("CP_CALCULATED_MESSAGE", c.string(CALCULATED.replace("{name}", "%s"))),
        fixed_message=c.define("CP_FIXED_MESSAGE", c.string(FIXED.replace("{name}", "%s"))),
        tunable_message=c.define("CP_TUNABLE_MESSAGE", c.string(TUNABLE.replace("{name}", "%s"))),
        log_constants=", ".join(map(log_constant, LOG_CATEGORIES)),
        log_categories=c.initializer(map(c.string, LOG_CATEGORIES)),
        rules=c.rows([_rule(rule) for rule in RULES.values()], list(RULES)),
        real_starts=c.rows(
            [c.double(v.start if v.start is not None else 0.0) for v in reals], [v.name for v in reals]
        ),
        real_rules=c.initializer(RULE_INDEX[v.rule] for v in reals),
        real_whats=c.initializer(c.string(v.what) for v in reals),
        state_nominals=c.rows(
            [c.double(v.nominal) for v in records if v.group == "states"],
            [v.name for v in records if v.group == "states"],
        ),
        n_variable=c.define("CP_NVARIABLE", len(records)),
        settable=c.initializer(map(settable, records)),
        names=c.rows([c.string(v.name) for v in records]),
        roles=c.initializer(map(role, records)),
        model_lines="\n".join(model.config(data, records)),
    )
