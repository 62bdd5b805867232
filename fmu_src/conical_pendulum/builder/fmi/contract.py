"""What a native FMU is made of besides the FMI glue: a model behind the model contract
(fmu_model.h, a NativeModel: the pendulum's in builder.models.pendulum, the cart's in builder.models.cart)
and an FMI standard's writer (a Standard: builder.fmi.fmi2, builder.fmi.fmi3), which builder.packaging.native
compiles and packs together. Data types only, so that the models and the standards import
this and not each other."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from .variables import Group, Variable

CSRC = Path(__file__).parents[2] / "runtime" / "csrc"
# Every C file of runtime/csrc by name, whichever role's folder holds it (core/, fmi/: the FMI
# layers, models/: the models behind fmu_model.h); names are unique, so an FMU's sources/
# folder, or the compiled core's build folder, holds them side by side.
CSRC_FILES = {path.name: path for path in sorted(CSRC.glob("*/*.[ch]"))}


@dataclass(frozen=True)
class Dimension:
    """The FMI 3.0 structural parameter that sizes a model's arrays, fixed by its build."""

    name: str
    description: str
    refusal: str  # why another value is refused; {size}: the built one


@dataclass(frozen=True)
class NativeModel:
    """What builder.packaging.native needs of a model behind the model contract (fmu_model.h) besides
    its variables: the FMU's name, the model's C files, and what its fmu_config.h holds
    beyond what every model's does."""

    name: str  # modelName, modelIdentifier and the binary's name
    sources: tuple[str, ...]  # the model's C files in runtime/csrc (or generated: `generated`)
    headers: tuple[str, ...]
    groups: Callable[[], list[Group]]  # its variables' groups, in value-reference order
    config: Callable[[dict, list[Variable]], list[str]]  # fmu_config.h's lines only this model reads
    step_size: float  # the DefaultExperiment's stepSize
    fmi_versions: tuple[int, ...] = (2,)
    dimension: Dimension | None = None  # its FMI 3.0 arrays' size, if it has arrays


# The log categories, written once: the model description's LogCategories and fmu_config.h's
# CP_LOG_* (the only categories the FMI layers log in, and those SetDebugLogging takes).
# The highest order of the time derivatives a native FMU gives of its continuous outputs and
# takes of its inputs (fmu_model.h's MODEL_MAX_DERIVATIVE_ORDER): FMI's maxOutputDerivativeOrder,
# and FMI 2.0's canInterpolateInputs.
MAX_DERIVATIVE_ORDER = 2
LOG_CATEGORIES = {
    "logStatusError": "refused values and calls",
    "logStatusDiscard": "steps that could not complete, with a diagnosis",
    "logStatusWarning": "values taken but not honoured in full, and what is lost",
}


@dataclass(frozen=True)
class Description:
    """What a model description is written from: the model, model.json's data and its records,
    the GUID (FMI 3.0: the instantiation token) and the C sources the FMU ships."""

    model: NativeModel
    data: dict
    records: list[Variable]
    guid: str
    sources: list[str]


@dataclass(frozen=True)
class Standard:
    """One FMI version's writer, behind one interface: builder.packaging.native packs whatever it says."""

    version: int
    model_description: Callable[[Description], bytes]
    platform_folders: dict[str, str]  # builder.packaging.native's platforms -> the binaries' folders
    headers: Callable[[Description], dict[str, str]]  # generated headers the glue compiles with
    files: Callable[[Description], dict[str, bytes]]  # other files of sources/ (not compiled)
