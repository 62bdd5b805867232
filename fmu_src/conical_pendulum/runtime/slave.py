"""ConicalPendulum: FMI 2.0 co-simulation slave on the model the native FMUs hold.

One class for every scene: it registers the variables MODEL_FILE in the FMU's resources
describes (conical_pendulum.builder.fmu) and hands every value, setting, step and FMU state
to the compiled core's Model, pendulum_model.c behind fmu_model.h, whose C checks them and
words every refusal and diagnosis; every solver, the implicit one too, is the core's. Only
the FMI mode (pythonfmu keeps none) stays here. Shipped under a package name unique to the runtime's sources, imported through its
entry module (runtime/entry.py); needs numpy and the core.
"""

import functools
import importlib.util
import json
import os
import struct
import sys

from pythonfmu import Fmi2Slave, Integer, Real
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Status, Fmi2Variability

from .files import MODEL_FILE

KINDS = {"Real": Real, "Integer": Integer}
NAMED = {Real: "a Real", Integer: "an Integer"}
MODES = ("instantiated", "initialization", "step")  # where an instance is in FMI's state machine
STEPPING = MODES.index("step")  # past initialization: only inputs may still be set
# An FMU state: the mode (an index of MODES), what only this FMU has, then the model's data (its
# ModelData, the bytes a native FMU's state holds of it).
OWN = struct.Struct("<i4x")
THE_STATE = "fmi2SetFMUstate: the state's "  # what a refusal of a restored state begins with


def _load_core(resources, core):
    """The compiled core, from this FMU's resources (one copy per process and build)."""
    name = core["module"]
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, os.path.join(resources, core["file"]))
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        sys.modules[name] = module
    return sys.modules[name]


def _fmi_call(method):
    """An FMI entry point whose failures the host's logger hears of: pythonfmu turns the
    exception into fmi2Fatal, and passes on only the messages logged before it."""

    @functools.wraps(method)
    def call(self, *args):
        try:
            if self._broken:
                raise RuntimeError(self._broken)
            return method(self, *args)
        except BaseException as exc:
            if not isinstance(exc, Refused):  # refusals are logged where they are made
                self.log(f"{method.__name__}: {exc}", Fmi2Status.error)
            raise

    return call


class Refused(ValueError):
    """An input the slave refuses; its message went to the FMI logger already."""


class ConicalPendulum(Fmi2Slave):
    author = "conical-pendulum-fmu"
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=10.0, step_size=1.0 / 60.0)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        if sys.path.count(self.resources) > 1:  # pythonfmu adds it again per instance
            sys.path.remove(self.resources)
        # An exception here would crash the host (pythonfmu 0.7): keep it for later calls.
        self._broken = None
        try:
            with open(os.path.join(self.resources, MODEL_FILE), encoding="utf-8") as file:
                model = json.load(file)
            self._core = _load_core(self.resources, model["core"])
        except Exception as exc:
            self._broken = f"cannot load the model from {self.resources}: {exc!r}"
            self.log(self._broken, Fmi2Status.fatal)
            return
        self.description = model["description"]  # the scene's: no class attribute, or it would win
        self._model = self._core.Model()  # every variable at its start value
        self._vr = {v["name"]: v["value_reference"] for v in model["variables"]}
        self._mode = 0
        self._of = {Real: set(), Integer: set()}  # the value references of each type
        for v in model["variables"]:  # in value-reference order: pythonfmu numbers them
            fmi = {
                "causality": Fmi2Causality[v["causality"]],
                "variability": Fmi2Variability[v["variability"]],
            }
            fmi["initial"] = v["initial"] and Fmi2Initial[v["initial"]]
            self.register_variable(KINDS[v["type"]](v["name"], description=v["description"], **fmi))
            self._of[KINDS[v["type"]]].add(v["value_reference"])

    @_fmi_call
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        if tolerance is not None:
            self._refusing(self._model.set_tolerance, tolerance)
        self._refusing(self._model.set_experiment_times, start_time, stop_time)

    @_fmi_call
    def enter_initialization_mode(self):
        self._mode = MODES.index("initialization")

    @_fmi_call
    def exit_initialization_mode(self):
        self._model.initialize()
        self._mode = STEPPING

    @_fmi_call
    def do_step(self, current_time, step_size):
        failure = self._model.do_step(current_time, step_size)
        if failure:
            self.log(failure, Fmi2Status.discard)
            return False
        return True

    @_fmi_call
    def get_real(self, vrs):
        return self._model.get_reals(self._typed(vrs, Real))

    @_fmi_call
    def set_real(self, vrs, values):
        self._refusing(self._model.set_reals, self._typed(vrs, Real), values, self._mode == STEPPING)

    @_fmi_call
    def get_integer(self, vrs):
        return self._model.get_integers(self._typed(vrs, Integer))

    @_fmi_call
    def set_integer(self, vrs, values):
        self._refusing(self._model.set_integers, self._typed(vrs, Integer), values, self._mode == STEPPING)

    get_boolean, set_boolean = _fmi_call(Fmi2Slave.get_boolean), _fmi_call(Fmi2Slave.set_boolean)
    get_string, set_string = _fmi_call(Fmi2Slave.get_string), _fmi_call(Fmi2Slave.set_string)

    @_fmi_call
    def _get_fmu_state(self):
        return OWN.pack(self._mode) + self._model.data

    @_fmi_call
    def _set_fmu_state(self, state):
        """Taken only whole: the mode checked here, the model's data by model_invalid
        (Model.data), before any of it is taken."""
        if len(state) != OWN.size + len(self._model.data):
            self._fail(f"fmi2SetFMUstate: {len(state)} bytes are not a state of this FMU")
        (mode,) = OWN.unpack_from(state)
        if not 0 <= mode < len(MODES):
            modes = ", ".join(f"{k} ({name})" for k, name in enumerate(MODES))
            self._fail(f"{THE_STATE}mode = {mode}: choose one of {modes}")
        self._refusing(setattr, self._model, "data", state[OWN.size :], prefix=THE_STATE)
        self._mode = mode

    # bytes as they are: fmi2SetFMUstate checks them, naming what is wrong (these have no logger)
    _fmu_state_to_bytes = _fmu_state_from_bytes = staticmethod(bytes)

    def _fail(self, message):
        """Report a bad input through the FMI logger and stop the call (pythonfmu: fmi2Fatal)."""
        self.log(message, Fmi2Status.error)
        raise Refused(message)

    def _refusing(self, take, *args, prefix=""):
        """take(*args), or the model's refusal logged (after prefix) and the call stopped."""
        try:
            return take(*args)
        except self._core.Refusal as exc:
            self._fail(f"{prefix}{exc}")

    def _typed(self, vrs, kind):
        """vrs, if each is a variable of kind (Real or Integer) of this FMU."""
        if not self._of[kind].issuperset(vrs):
            bad = next(vr for vr in vrs if vr not in self._of[kind])
            raise TypeError(f"value reference {bad} is not {NAMED[kind]} variable")
        return vrs


SLAVE = ConicalPendulum  # what the FMU's entry module exports (runtime/entry.py)
