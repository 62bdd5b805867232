"""ConicalPendulum: FMI 2.0 co-simulation slave, thin glue between FMI variables and the compiled core.

An ordinary module: one class for every scene. What a scene's FMU holds (its variables
with their start values and descriptions, the compiled core's file) is read at
instantiation from MODEL_FILE in the FMU's resources, written at build time
(conical_pendulum.builder.fmu). Shipped in each FMU as part of a package with a name
unique to the runtime's sources, and imported once per process through the FMU's
entry module (runtime/entry.py). At run time it needs numpy and the compiled core,
nothing else.
"""

import functools
import importlib.machinery
import importlib.util
import json
import math
import os
import sys

import numpy as np
from pythonfmu import Fmi2Slave, Integer, Real
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Status, Fmi2Variability

from .files import MODEL_FILE
from .rules import (
    CALCULATED,
    FIXED,
    SETTINGS,
    SOLVERS,
    STATISTICS,
    BadValue,
    check_rule,
    check_setting,
    check_value,
    rule_of,
)

RADAU = SOLVERS.index("radau")
STAT = {name: k for k, name in enumerate(STATISTICS)}  # the core's stats slots (model.h's CP_STAT_*)
KINDS = {"Real": Real, "Integer": Integer}
MODES = ("instantiated", "initialization", "step")  # where an instance is in FMI's state machine
STATE_FIELDS = ("reals", "ints", "solver", "mode", "tolerance")  # of an FMU state (_get_fmu_state)
MEMORY_FIELDS = ("h", "fsal", "f")  # of the solver memory in it (the core's Stepper.memory)


def read_model(resources: str) -> dict:
    """The scene's FMU data written at build time: model, core, variables, settings."""
    with open(os.path.join(resources, MODEL_FILE), encoding="utf-8") as file:
        return json.load(file)


def _span(variables, *groups) -> slice:
    """The value references of the variables of `groups`, which follow one another."""
    refs = [v["value_reference"] for v in variables if v["group"] in groups]
    first = refs[0] if refs else 0
    if refs != list(range(first, first + len(refs))):
        raise ValueError(f"the variables of {', '.join(groups)} do not follow one another")
    return slice(first, first + len(refs))


def _load_core(resources, core):
    """The compiled core, from this FMU's resources (one copy per process and build)."""
    name = core["module"]
    if name in sys.modules:
        return sys.modules[name]
    path = os.path.join(resources, core["file"])
    loader = importlib.machinery.ExtensionFileLoader(name, path)
    spec = importlib.util.spec_from_file_location(name, path, loader=loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    sys.modules[name] = module
    return module


def _fmi_call(method):
    """An FMI entry point whose failures the host's logger hears of: pythonfmu turns the
    exception into fmi2Fatal, and passes on only the messages logged before it."""

    @functools.wraps(method)
    def call(self, *args):
        try:
            return method(self, *args)
        except BaseException as exc:
            if not isinstance(exc, Refused):  # refusals are logged where they are made
                self.log(f"{method.__name__}: {exc}", Fmi2Status.error)
            raise

    return call


class Refused(ValueError):
    """An input the slave refuses; its message went to the FMI logger already."""


class Unreadable(dict):
    """What fmi2DeSerializeFMUstate makes of bytes that are no state: refused when set."""


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
            model = read_model(self.resources)
            self._core = _load_core(self.resources, model["core"])
            # The variables as the build described them (builder.variables), in value-reference
            # order: the Reals first, one array that getReal answers from in one indexing; the
            # core reads parameters and inputs as one array p, the state and outputs as one, the
            # statistics as one. Then the Integers.
            variables = model["variables"]
            n_real = sum(v["type"] == "Real" for v in variables)
            reals = _span(variables, "parameters", "inputs")
            state_values, stats = _span(variables, "states", "outputs"), _span(variables, "statistics")
            if [v["type"] for v in variables[:n_real]] != ["Real"] * n_real:
                raise ValueError("the Real variables do not come first")
            if [v["value_reference"] for v in variables] != list(range(len(variables))):
                raise ValueError("the variables are not in value-reference order")
        except Exception as exc:
            self._broken = f"cannot load the model from {self.resources}: {exc!r}"
            self.log(self._broken, Fmi2Status.fatal)
            return
        self.description = model["description"]  # the scene's: no class attribute, or it would win
        self._reals = np.array(
            [0.0 if v["start"] is None else v["start"] for v in variables[:n_real]], dtype=float
        )
        self._ints = [v["start"] for v in variables[n_real:]]
        self._int_names = [v["name"] for v in variables[n_real:]]
        self._vr = {v["name"]: v["value_reference"] for v in variables}
        self._rules = [(v["rule"], v["what"]) for v in variables]  # each record's, not its name's
        n_state = sum(v["group"] == "states" for v in variables)
        self._state = self._reals[state_values.start : state_values.start + n_state]
        self._stepper = self._core.Stepper(self._reals[reals], self._reals[state_values], self._reals[stats])
        self._stepper.update_outputs()
        self._mode = "instantiated"
        self._tolerance = None
        self._register(variables)

    def _register(self, variables):
        """Declare the variables as described, in value-reference order (pythonfmu numbers them)."""
        for v in variables:
            self.register_variable(
                KINDS[v["type"]](
                    v["name"],
                    causality=Fmi2Causality[v["causality"]],
                    variability=Fmi2Variability[v["variability"]],
                    initial=v["initial"] and Fmi2Initial[v["initial"]],
                    description=v["description"],
                )
            )

    def _setting(self, name):
        """A solver setting's current value, by name."""
        vr = self._vr[name]
        if vr >= len(self._reals):
            return self._ints[vr - len(self._reals)]
        return float(self._reals[vr])

    # --- FMI calls -------------------------------------------------------------------

    def _check_alive(self):
        if self._broken:
            raise RuntimeError(self._broken)

    @_fmi_call
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._check_alive()
        if tolerance is not None:
            self._tolerance = self._fail_unless_valid(
                "tolerance (from setupExperiment)", tolerance, rule_of("rtol")
            )

    @_fmi_call
    def enter_initialization_mode(self):
        self._check_alive()
        self._mode = "initialization"

    @_fmi_call
    def exit_initialization_mode(self):
        self._check_alive()
        if self._tolerance is not None:
            self._reals[self._vr["rtol"]] = self._tolerance
        self._stepper.update_outputs()
        self._configure()
        self._mode = "step"

    def _configure(self):
        """Settings are fixed from here on: hand them to the stepper once."""
        self._stepper.configure(
            *(self._setting(name) for name in ("solver", "rtol", "atol", "max_step", "max_steps"))
        )

    @_fmi_call
    def do_step(self, current_time, step_size):
        if self._setting("solver") == RADAU:
            failure = self._radau_step(current_time, step_size)
        else:
            status = self._stepper.advance(current_time, step_size)
            failure = status and self._stepper.diagnosis(status)
        if failure:
            self.log(failure, Fmi2Status.discard)
            return False
        return True

    @_fmi_call
    def get_real(self, vrs):
        try:
            return self._reals[vrs].tolist()
        except IndexError:
            raise TypeError(f"value references {vrs} include one that is not a Real variable") from None

    @_fmi_call
    def set_real(self, vrs, values):
        changed = False
        for vr, value in zip(vrs, values):
            if not isinstance(self.vars.get(vr), Real):
                raise TypeError(f"value reference {vr} is not a Real variable")
            name = self.vars[vr].name
            self._check_settable(vr, name)
            value = self._fail_unless_valid(name, value, self._rules[vr])
            changed |= self._reals[vr] != value
            self._reals[vr] = value
        if changed:  # outputs depend on inputs at once (the pivot force), and so does x'
            self._stepper.update_outputs()

    @_fmi_call
    def get_integer(self, vrs):
        first = len(self._reals)
        if not all(first <= vr < first + len(self._ints) for vr in vrs):
            raise TypeError(f"value references {vrs} include one that is not an Integer variable")
        return [self._ints[vr - first] for vr in vrs]

    @_fmi_call
    def set_integer(self, vrs, values):
        first = len(self._reals)
        for vr, value in zip(vrs, values):
            if not isinstance(self.vars.get(vr), Integer):
                raise TypeError(f"value reference {vr} is not an Integer variable")
            name = self.vars[vr].name
            self._check_settable(vr, name)
            self._ints[vr - first] = self._fail_unless_valid(name, int(value))

    def _radau_step(self, t, dt):
        """The stiff fallback: scipy's Radau IIA on the compiled right-hand side.

        Imports scipy, only when chosen. Returns None, or a message on failure.
        """
        from scipy.integrate import Radau

        if not (dt >= 0 and math.isfinite(dt)):
            return self._step_failure(self._core.BAD_STEP, t, dt)
        rtol, atol, max_step, max_steps = (
            self._setting(name) for name in ("rtol", "atol", "max_step", "max_steps")
        )
        core, stepper = self._core, self._stepper
        unworkable = core.unworkable(RADAU, t, dt, max_step, max_steps)
        if unworkable:
            return self._step_failure(unworkable, t, dt)
        if dt == 0:
            return None
        state, params = self._state, stepper.params
        options = {"first_step": min(stepper.h, dt)} if stepper.h > 0 else {}
        steps, solver = 0, None
        try:  # scipy's overflows and non-finite matrices end in a diagnosis, not on stderr
            with np.errstate(all="ignore"):
                solver = Radau(
                    lambda _, x: core.rhs(x, params),
                    t,
                    state.copy(),
                    t + dt,
                    rtol=rtol,
                    atol=atol,
                    max_step=max_step or np.inf,
                    **options,
                )
                while solver.status == "running" and steps < max_steps:
                    solver.step()  # "failed" only where the step size underflows
                    steps += 1
        except core.CoreError as exc:
            return self._step_failure(exc.status, t, dt, exc.dof, exc.pivot_ratio)
        except (ArithmeticError, ValueError, np.linalg.LinAlgError) as exc:  # no finite step
            return f"{self._step_failure(core.STEP_UNDERFLOW, t, dt)} (scipy: {exc})"
        finally:
            stepper.stats[STAT["n_rhs"]] += solver.nfev if solver else 0
            stepper.stats[STAT["n_steps"]] += steps
        if solver.status == "failed":
            return self._step_failure(core.STEP_UNDERFLOW, t, dt)
        if solver.status == "running":
            return self._step_failure(core.TOO_MANY_STEPS, t, dt)
        if not (np.all(np.isfinite(solver.y)) and np.all(np.isfinite(core.outputs(solver.y, params)))):
            try:  # the pivot force where M is singular: the right-hand side says where
                core.rhs(solver.y, params)
            except core.CoreError as exc:
                return self._step_failure(exc.status, t, dt, exc.dof, exc.pivot_ratio)
            return self._step_failure(core.NONFINITE, t, dt)
        state[:] = solver.y
        stepper.h = solver.h_abs
        stepper.update_outputs()
        return None

    get_boolean = _fmi_call(Fmi2Slave.get_boolean)
    set_boolean = _fmi_call(Fmi2Slave.set_boolean)
    get_string = _fmi_call(Fmi2Slave.get_string)
    set_string = _fmi_call(Fmi2Slave.set_string)

    # --- the complete state: variables, solver memory, statistics, mode and time ---

    @_fmi_call
    def _get_fmu_state(self):
        return {
            "reals": self._reals.tolist(),
            "ints": list(self._ints),
            "solver": self._stepper.memory(),
            "mode": self._mode,
            "tolerance": self._tolerance,
        }

    @_fmi_call
    def _set_fmu_state(self, state):
        self._check_alive()
        reals, ints, memory, mode, tolerance = self._checked_state(state)
        self._reals[:] = reals
        self._ints[:] = ints
        self._stepper.restore(memory)
        self._mode, self._tolerance = mode, tolerance
        self._configure()

    @staticmethod
    def _fmu_state_from_bytes(state: bytes) -> dict:
        """The state in pythonfmu's bytes (JSON); bytes that are none, refused when set.

        Not raised here: a static method has no logger to say why, so the refusal comes
        at fmi2SetFMUstate, naming it."""
        try:
            return Fmi2Slave._fmu_state_from_bytes(state)
        except ValueError as exc:  # not UTF-8, not JSON
            return Unreadable(unreadable=str(exc))

    def _checked_state(self, state):
        """A state to restore, checked as values set through the API are, before any is taken.

        The fields of _get_fmu_state with their types and sizes; every Real keeps its
        variable's rule (runtime.rules: states and inputs finite, statistics whole counts),
        the Integer settings theirs (and fit an fmi2Integer), the tolerance is None or keeps
        setupExperiment's; the solver's carried step is finite and not negative, fsal 0 or 1,
        the carried derivative finite where fsal says it is valid; the mode is one of MODES.
        Returns (reals, ints, solver memory, mode, tolerance), or refuses naming what is wrong.
        """

        def refuse(what):
            self._fail(f"fmi2SetFMUstate: the state's {what}")

        if isinstance(state, Unreadable):
            self._fail(
                f"fmi2SetFMUstate: the bytes given to fmi2DeSerializeFMUstate are not a "
                f"state of this FMU ({state['unreadable']})"
            )

        def numbers_list(name, value, size):
            if not (isinstance(value, list) and len(value) == size):
                refuse(f"{name}: expected a list of {size} numbers, got {value!r:.80}")
            return value

        if not (isinstance(state, dict) and sorted(state) == sorted(STATE_FIELDS)):
            refuse(f"fields: expected {', '.join(STATE_FIELDS)}, got {state!r:.80}")
        memory = state["solver"]
        if not (isinstance(memory, dict) and sorted(memory) == sorted(MEMORY_FIELDS)):
            refuse(f"solver memory: expected {', '.join(MEMORY_FIELDS)}, got {memory!r:.80}")
        if not (isinstance(state["mode"], str) and state["mode"] in MODES):
            refuse(f"mode = {state['mode']!r:.80}: choose one of {', '.join(MODES)}")
        reals = numbers_list("reals", state["reals"], len(self._reals))
        ints = numbers_list("ints", state["ints"], len(self._ints))
        f = numbers_list("solver memory f", memory["f"], len(self._state))
        fsal = memory["fsal"]
        if isinstance(fsal, bool) or fsal not in (0, 1):
            refuse(f"fsal = {fsal!r:.80}: must be 0 or 1")
        try:
            reals = [
                check_rule(self.vars[vr].name, value, *self._rules[vr]) for vr, value in enumerate(reals)
            ]
            ints = [check_setting(name, value) for name, value in zip(self._int_names, ints)]
            for name, value in zip(self._int_names, ints):
                if not -(2**31) <= value < 2**31:
                    raise BadValue(f"{name} = {value}: not a 32-bit fmi2Integer")
            tolerance = state["tolerance"]
            if tolerance is not None:
                tolerance = check_value("tolerance (from setupExperiment)", tolerance, "rtol")
            h = check_value("h", memory["h"])
            names = [f"carried der({name})" for name in self._core.STATE_NAMES]
            if fsal:
                f = [check_value(name, value) for name, value in zip(names, f)]
            else:  # not used: any double
                f = [self._double(name, value) for name, value in zip(names, f)]
        except BadValue as exc:
            refuse(str(exc))
        return reals, ints, {"h": h, "fsal": int(fsal), "f": f}, state["mode"], tolerance

    @staticmethod
    def _double(name, value):
        """value as a double (any, even not finite), or BadValue."""
        try:
            if not isinstance(value, bool) and isinstance(value, (int, float)):
                return float(value)
        except OverflowError:
            pass
        raise BadValue(f"{name} = {value!r:.80}: not a double")

    # --- helpers ----------------------------------------------------------------------

    def _fail(self, message):
        """Report a bad input through the FMI logger and stop the call (pythonfmu: fmi2Fatal)."""
        self.log(message, Fmi2Status.error)
        raise Refused(message)

    def _fail_unless_valid(self, name, value, rule=("finite", "")):
        """The value as its variable takes it (a setting by its type too; else `rule`, its
        record's (rule, what)), or a refusal naming it (runtime.rules)."""
        try:
            if name in SETTINGS:
                return check_setting(name, value)
            return check_rule(name, value, *rule)
        except BadValue as exc:
            self._fail(str(exc))

    def _check_settable(self, vr, name):
        var = self.vars[vr]
        if var.causality == Fmi2Causality.output and var.initial != Fmi2Initial.exact:
            self._fail(CALCULATED.format(name=name))
        if self._mode == "step" and var.causality != Fmi2Causality.input:
            self._fail(FIXED.format(name=name))

    def _step_failure(self, status, t, dt, bad_dof=-1, pivot_ratio=1.0):
        """The diagnosis of a failed Radau step (the core's, as in every FMU of this package)."""
        return self._core.diagnose(
            status,
            t,
            dt,
            bad_dof,
            pivot_ratio,
            *(self._setting(name) for name in ("rtol", "atol", "max_step", "max_steps")),
        )


SLAVE = ConicalPendulum  # what the FMU's entry module exports (runtime/entry.py)
