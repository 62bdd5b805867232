"""Scene -> a native FMU: the same generated C with FMI glue in C, no Python at run time.

One FMI 2.0 FMU with both interfaces: Co-Simulation (the core's C solvers, the settings
and statistics of the pythonfmu FMU) and Model Exchange (the host integrates
fmi2GetDerivatives). Same variable names, value references, starts and descriptions as
the pythonfmu FMU of the scene, plus the state derivatives `der(<state>)` that Model
Exchange needs. The binary links only libc and libm; the C sources ship in `sources/`
and are listed in the model description, so a host can compile it for its platform.
The same code paths write any model behind fmu_model.h, given as a NativeModel: the
coupled demo's cart (builder.cart) is the second.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import tempfile
import time
import uuid
import xml.etree.ElementTree as ET
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..errors import UserError
from ..runtime.files import MODEL_FILE, MODEL_NAME
from ..runtime.rules import CALCULATED, FIXED, RULES, rule_of
from ..scene import Scene
from .compiler import CSRC_FILES, CoreBuild
from .variables import Group, first_references, groups

# The C files of the FMI layers, which serve every model behind fmu_model.h.
LAYER_SOURCES = {2: ("fmi_layer.c", "fmi2_glue.c"), 3: ("fmi_layer.c", "fmi3_glue.c")}
LAYER_HEADERS = ("fmu_model.h", "fmi_layer.h", "fmu_variables.h", "fmu_config.h")


@dataclass(frozen=True)
class NativeModel:
    """What builder.native needs of a model behind the model contract (fmu_model.h) besides
    its variables: the FMU's name, the model's C files, and what its fmu_config.h holds
    beyond what every model's does."""

    name: str  # modelName, modelIdentifier and the binary's name
    sources: tuple[str, ...]  # the model's C files in runtime/csrc (or generated: `generated`)
    headers: tuple[str, ...]
    groups: Callable[[], list[Group]]  # its variables' groups, in value-reference order
    config: Callable[[dict], list[str]]  # fmu_config.h's lines only this model reads
    step_size: float  # the DefaultExperiment's stepSize
    fmi_versions: tuple[int, ...] = (2,)


# The log categories, written once: the model description's LogCategories and fmu_config.h's
# CP_LOG_* (the only categories fmi2_glue.c can log in, and those fmi2SetDebugLogging takes).
LOG_CATEGORIES = {
    "logStatusError": "refused values and calls",
    "logStatusDiscard": "steps that could not complete, with a diagnosis",
}


def glue_sources(fmi_version: int = 2, model: NativeModel | None = None) -> list[str]:
    """The C sources of a native FMU of an FMI version (the pendulum's by default): the
    model's, then its FMI layer's."""
    model = model or PENDULUM
    if fmi_version not in model.fmi_versions:
        raise ValueError(f"fmi_version: {fmi_version!r} is not one of {model.fmi_versions} ({model.name})")
    return [*model.sources, *LAYER_SOURCES[fmi_version]]


def glue_headers(model: NativeModel | None = None) -> list[str]:
    """The C headers a native FMU ships: the model's, then its FMI layer's."""
    return [*(model or PENDULUM).headers, *LAYER_HEADERS]


def fmi_headers() -> Path:
    """The FMI 2.0 and 3.0 headers, from the installed fmpy (its c-code folder)."""
    import fmpy

    return Path(fmpy.__file__).parent / "c-code"


def real_variables(data: dict) -> list[dict]:
    """The Real variables the glue holds in one array by value reference (CP_NREAL): every
    variable before the first Integer (builder.variables.GROUPS's order)."""
    variables = data["variables"]
    return variables[: next((k for k, v in enumerate(variables) if v["type"] != "Real"), len(variables))]


def _c_string(text: str) -> str:
    return json.dumps(text)  # a JSON string of ASCII text is a valid C string literal


def log_constant(category: str) -> str:
    """The C name of a log category: logStatusError -> CP_LOG_STATUS_ERROR."""
    return "CP_" + re.sub(r"(?<!^)(?=[A-Z])", "_", category).upper()


def _c_double(value: float) -> str:
    return (
        "INFINITY"
        if value == float("inf")
        else ("-INFINITY" if value == -float("inf") else repr(float(value)))
    )


def settable(variable: dict) -> str:
    """When a variable may be set, as fmu_config.h's cp_settable says it: an input always, a
    parameter or an exact start value before initialization, a calculated one never."""
    if variable["causality"] == "input" or variable["variability"] == "tunable":
        return "CP_SET_ALWAYS"
    if variable["causality"] == "parameter" or variable["initial"] in ("exact", "approx"):
        return "CP_SET_BEFORE_INIT"
    return "CP_SET_NEVER"


def role(variable: dict) -> str:
    """A variable's part in directional derivatives, as fmu_config.h's cp_role says it: a
    state is a known and an unknown (an output of its own value), an input a known, an output
    or a state derivative an unknown."""
    known = variable["group"] in ("states", "inputs")
    unknown = variable["causality"] == "output" or bool(variable["derivative_of"])
    return " | ".join(["CP_KNOWN"] * known + ["CP_UNKNOWN"] * unknown) or "0"


def config_header(data: dict, guid: str, model: NativeModel | None = None) -> str:
    """fmu_config.h: value references, start values, names, rules and log categories for
    the FMI layer and the model (the pendulum's by default), from the variables' description
    (builder.variables, in model.json); then the lines only the model reads (model.config)."""
    model = model or PENDULUM
    variables, reals = data["variables"], real_variables(data)
    rule_names = list(RULES)
    first = first_references(variables, model.groups())
    named = {group.name for group in model.groups() if group.named}
    names = [v["name"] for v in variables]
    rules = [(v["rule"], rule_of(v["name"])[1]) for v in reals]
    lines = [
        "/* Generated by conical_pendulum.builder.native: do not edit. */",
        "#ifndef CP_FMU_CONFIG_H",
        "#define CP_FMU_CONFIG_H",
        "",
        "#include <math.h>",
        "#include <stdio.h>",
        "",
        '#include "rules.h"',
        "",
        f"#define CP_GUID {_c_string(guid)}",
        "/* Value references: each group's first, in value-reference order. */",
        *(f"#define CP_VR_{group.c_name} {first[group.name]}" for group in model.groups()),
        *(
            f"#define CP_VR_{v['name'].upper()} {v['value_reference']}"
            for v in variables
            if v["group"] in named
        ),
        f"#define CP_NREAL {len(reals)}",
        f"#define CP_FINITE_RULE {rule_names.index('finite')}",
        f"#define CP_CALCULATED_MESSAGE {_c_string(CALCULATED.replace('{name}', '%s'))}",
        f"#define CP_FIXED_MESSAGE {_c_string(FIXED.replace('{name}', '%s'))}",
        "",
        "/* The log categories, as the model description's LogCategories declares them. */",
        "enum { " + ", ".join(map(log_constant, LOG_CATEGORIES)) + ", CP_NLOG };",
        "static const char *const cp_log_categories[CP_NLOG] = {"
        + ", ".join(map(_c_string, LOG_CATEGORIES))
        + "};",
        "static const cp_rule cp_rules[] = {",
        *(
            f"    {{{_c_double(r.low)}, {int(r.low_open)}, {_c_double(r.high)}, "
            f"{_c_string(r.refusal)}, {int(r.whole)}}},  /* {name} */"
            for name, r in RULES.items()
        ),
        "};",
        "static const double cp_real_start[CP_NREAL] = {",
        *(
            f"    {_c_double(v['start'] if v['start'] is not None else 0.0)},  /* {v['name']} */"
            for v in reals
        ),
        "};",
        "static const unsigned char cp_real_rule[CP_NREAL] = {"
        + ", ".join(str(rule_names.index(rule)) for rule, _ in rules)
        + "};",
        "static const char *const cp_real_what[CP_NREAL] = {"
        + ", ".join(_c_string(what) for _, what in rules)
        + "};",
        "/* When each variable may be set, by value reference (its causality, variability and",
        " * initial). */",
        "enum { CP_SET_NEVER, CP_SET_BEFORE_INIT, CP_SET_ALWAYS };",
        f"#define CP_NVARIABLE {len(variables)}",
        "static const unsigned char cp_settable[CP_NVARIABLE] = {"
        + ", ".join(settable(v) for v in variables)
        + "};",
        "static const char *const cp_names[] = {",
        *(f"    {_c_string(name)}," for name in names),
        "};",
        "",
        "/* The directional derivatives' knowns (states and inputs) and unknowns (outputs, states",
        " * among them, and state derivatives), by value reference. */",
        "enum { CP_KNOWN = 1, CP_UNKNOWN = 2 };",
        "static const unsigned char cp_role[CP_NVARIABLE] = {" + ", ".join(map(role, variables)) + "};",
        "",
        "/* What reads these tables: hand-written C (runtime/csrc/fmi/fmu_variables.h). */",
        '#include "fmu_variables.h"',
        "",
        *model.config(data),
        "#endif",
        "",
    ]
    return "\n".join(lines)


def _pendulum_config(data: dict) -> list[str]:
    """The pendulum's own lines of fmu_config.h: its value references checked against the
    core's arrays (model.h), its Integer settings' starts and rules, the carried step's rule."""
    n_state = sum(v["group"] == "states" for v in data["variables"])
    rule_names = list(RULES)
    return [
        '#include "model.h"',
        "/* What the glue takes from that order: the core's p (parameters, then inputs), x and",
        " * y lie in the Reals as the core reads them. */",
        "#if CP_VR_STATE != CP_NPARAM || CP_VR_OUTPUT != CP_VR_STATE + CP_NSTATE \\",
        "    || CP_VR_STATISTICS != CP_VR_OUTPUT + CP_NOUTPUT || CP_VR_INPUT + CP_NINPUT != CP_NPARAM",
        '#error "the value-reference order does not fit the core\'s arrays (builder/variables.py)"',
        "#endif",
        f"#if CP_NSTATE != {n_state}",
        '#error "fmu_config.h and model.h come from different scenes"',
        "#endif",
        f"#define CP_SOLVER_START {data['settings']['solver']}",
        f"#define CP_MAX_STEPS_START {data['settings']['max_steps']}",
        f"#define CP_SOLVER_RULE {rule_names.index('native-solver')}",
        f"#define CP_MAX_STEPS_RULE {rule_names.index(rule_of('max_steps')[0])}",
        f"#define CP_STEP_RULE {rule_names.index(rule_of('h')[0])}",
        f"#define CP_STEP_WHAT {_c_string(rule_of('h')[1])}",
    ]


PENDULUM = NativeModel(
    MODEL_NAME,
    ("model.c", "dynamics.c", "chain.c", "solvers.c", "diagnosis.c", "cosim.c", "directional.c", "rules.c")
    + ("pendulum_model.c",),
    ("model.h", "real.h", "dynamics.h", "chain.h", "solvers.h", "tableaus.h", "status.h", "diagnosis.h")
    + ("cosim.h", "directional.h", "rules.h"),
    lambda: groups("native"),
    _pendulum_config,
    1.0 / 60.0,
    (2, 3),
)


def model_description(data: dict, guid: str, model: NativeModel | None = None) -> bytes:
    """modelDescription.xml for both interfaces, with a complete ModelStructure, from the
    variables' description (builder.variables, in model.json), of the pendulum by default."""
    model = model or PENDULUM
    root = ET.Element(
        "fmiModelDescription",
        {
            "fmiVersion": "2.0",
            "modelName": model.name,
            "guid": guid,
            "description": data["description"],
            "author": "conical-pendulum-fmu",
            "generationTool": "conical_pendulum.builder.native",
            "generationDateAndTime": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "variableNamingConvention": "structured",
            "numberOfEventIndicators": "0",
        },
    )
    common = {
        "modelIdentifier": model.name,
        "needsExecutionTool": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false",
        "canGetAndSetFMUstate": "true",
        "canSerializeFMUstate": "true",
        "providesDirectionalDerivative": "true",
    }
    for kind, extra in (
        ("ModelExchange", {"completedIntegratorStepNotNeeded": "true"}),
        (
            "CoSimulation",
            {
                "canHandleVariableCommunicationStepSize": "true",
                "canInterpolateInputs": "false",
                "maxOutputDerivativeOrder": "0",
            },
        ),
    ):
        interface = ET.SubElement(root, kind, {**common, **extra})
        files = ET.SubElement(interface, "SourceFiles")
        for name in glue_sources(2, model):
            ET.SubElement(files, "File", name=name)
    categories = ET.SubElement(root, "LogCategories")
    for name, text in LOG_CATEGORIES.items():
        ET.SubElement(categories, "Category", name=name, description=text)
    ET.SubElement(root, "DefaultExperiment", startTime="0.0", stopTime="10.0", stepSize=repr(model.step_size))
    variables = ET.SubElement(root, "ModelVariables")

    def add(vr, name, description, causality, variability, initial=None, kind="Real", **value):
        attributes = {
            "name": name,
            "valueReference": str(vr),
            "description": description,
            "causality": causality,
            "variability": variability,
        }
        if initial:
            attributes["initial"] = initial
        ET.SubElement(
            ET.SubElement(variables, "ScalarVariable", attributes),
            kind,
            {k: str(v) for k, v in value.items()},
        )

    index = {v["name"]: str(v["value_reference"] + 1) for v in data["variables"]}  # in ModelVariables
    for v in data["variables"]:
        value = {}
        if v["start"] is not None:
            value["start"] = repr(float(v["start"])) if v["type"] == "Real" else v["start"]
        if v["derivative_of"]:
            value["derivative"] = index[v["derivative_of"]]
        add(
            v["value_reference"],
            v["name"],
            v["description"],
            v["causality"],
            v["variability"],
            v["initial"],
            kind=v["type"],
            **value,
        )

    structure = ET.SubElement(root, "ModelStructure")
    outputs = ET.SubElement(structure, "Outputs")
    derivatives = ET.SubElement(structure, "Derivatives")
    initial = ET.SubElement(structure, "InitialUnknowns")
    for v in data["variables"]:  # each list in the order of ModelVariables, as FMI 2.0 asks
        unknown = {
            "index": index[v["name"]],
            "dependencies": " ".join(index[name] for name in v["depends_on"]),
        }
        if v["causality"] == "output":
            ET.SubElement(outputs, "Unknown", unknown)
        if v["derivative_of"]:
            ET.SubElement(derivatives, "Unknown", unknown)
    for v in data["variables"]:
        if v["initial"] in ("approx", "calculated") and (v["causality"] == "output" or v["derivative_of"]):
            ET.SubElement(initial, "Unknown", index=index[v["name"]])
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


# How each platform's binary is compiled from the FMU's sources: Linux natively, Windows
# cross-compiled with Debian's mingw-w64 (gcc-mingw-w64-x86-64).
COMPILERS = {
    "linux64": (["cc", "-fPIC", "-fvisibility=hidden"], ".so", ["-lm", "-Wl,-z,defs"]),
    "win64": (["x86_64-w64-mingw32-gcc"], ".dll", ["-static-libgcc"]),
}


def compile_binary(
    sources: Path,
    folder: Path,
    platform: str = "linux64",
    fmi_version: int = 2,
    model: NativeModel | None = None,
) -> Path:
    """The platform's shared library from the FMU's own sources (the pendulum's by default),
    exporting only the FMI functions: on Linux it needs libc and libm only, on Windows
    kernel32 and msvcrt."""
    model = model or PENDULUM
    if platform not in COMPILERS:
        raise ValueError(f"platform: {platform!r} is not one of {sorted(COMPILERS)}")
    compiler, suffix, libraries = COMPILERS[platform]
    library = folder / f"{model.name}{suffix}"
    command = [
        *compiler,
        "-std=c99",
        "-O2",
        "-shared",
        "-Wall",
        "-Wextra",
        "-Werror",
        f"-I{sources}",
        f"-I{fmi_headers()}",
        *(str(sources / name) for name in glue_sources(fmi_version, model)),
        "-o",
        str(library),
        *libraries,
        "-s",
    ]
    if shutil.which(compiler[0]) is None:
        raise UserError(
            f"the {platform} binary needs the compiler {compiler[0]}"
            + (" (Debian: apt-get install gcc-mingw-w64-x86-64)" if platform == "win64" else "")
        )
    run = subprocess.run(command, check=False, capture_output=True, text=True)
    if run.returncode:
        raise RuntimeError(f"compiling the native FMU failed:\n{' '.join(command)}\n{run.stderr}")
    return library


def guid_of(data: dict, fmi_version: int = 2, model: NativeModel | None = None) -> str:
    """A GUID that changes with anything the model description or binary says: the
    variables and start values, for the pendulum the core's build (scene structure and
    generator) and the settings, and every C file it ships from runtime/csrc."""
    files = glue_sources(fmi_version, model) + glue_headers(model)
    shipped = [CSRC_FILES[name] for name in files if name in CSRC_FILES]
    glue = b"".join(path.read_bytes() for path in shipped) + Path(__file__).read_bytes()
    if fmi_version == 3:
        glue += (Path(__file__).parent / "fmi3.py").read_bytes()
    text = json.dumps(data, sort_keys=True) + glue.hex()
    return "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, text)) + "}"


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
    and the settings (check_settings) and makes both. fmi_version=3: the FMI 3.0 FMU
    (fmi3_glue.c, builder.fmi3's model description and buildDescription.xml)."""
    generated = {name: core.directory / name for name in ("model.c", "model.h")}
    write_model_fmu(PENDULUM, data, output, platforms, fmi_version, generated)


def write_model_fmu(
    model: NativeModel,
    data: dict,
    output: Path,
    platforms: tuple[str, ...] = ("linux64",),
    fmi_version: int = 2,
    generated: dict[str, Path] | None = None,
) -> None:
    """The native FMU of any model behind fmu_model.h at `output` (moved into place only
    when complete): its sources (from runtime/csrc, or `generated` by name), fmu_config.h
    and the model description written from data's variables, a binary per platform, and
    model.json in its resources. fmi_version=3 (a model with 3 in fmi_versions): fmi3_glue.c
    with the model's fmi3_arrays.h, builder.fmi3's model description and buildDescription.xml."""
    from . import fmi3

    guid = guid_of(data, fmi_version, model)
    shipped = glue_sources(fmi_version, model)
    output.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="conical_pendulum_native_") as tmp:
        sources = Path(tmp) / "sources"
        sources.mkdir()
        for name in shipped + glue_headers(model):
            if name != "fmu_config.h":
                shutil.copy2((generated or {}).get(name) or CSRC_FILES[name], sources / name)
        (sources / "fmu_config.h").write_text(config_header(data, guid, model))
        if fmi_version == 3:
            (sources / "fmi3_arrays.h").write_text(fmi3.arrays_header(data))
        libraries = {}
        for platform in dict.fromkeys(platforms):
            (Path(tmp) / platform).mkdir()
            libraries[platform] = compile_binary(sources, Path(tmp) / platform, platform, fmi_version, model)
        if fmi_version == 3:
            (sources / "buildDescription.xml").write_bytes(fmi3.build_description(shipped, model.name))
        staged = Path(tmp) / "staged.fmu"
        with zipfile.ZipFile(staged, "w", zipfile.ZIP_DEFLATED) as archive:
            description = (
                model_description(data, guid, model)
                if fmi_version == 2
                else fmi3.model_description(data, guid, LOG_CATEGORIES, model.name, model.step_size)
            )
            archive.writestr("modelDescription.xml", description)
            for platform, library in libraries.items():  # stored: hosts extract them at every run
                folder = platform if fmi_version == 2 else fmi3.PLATFORM_FOLDERS[platform]
                archive.write(library, f"binaries/{folder}/{library.name}", compress_type=zipfile.ZIP_STORED)
            for path in sorted(sources.iterdir()):
                archive.write(path, f"sources/{path.name}")
            archive.writestr(f"resources/{MODEL_FILE}", json.dumps(data, indent=1))
        os.replace(staged, output)
