"""ConicalPendulum: FMI 2.0 co-simulation slave, thin glue between FMI variables and the compiled core.

Rendered by conical_pendulum.fmu for one scene under a module name unique to the build,
and imported once per process by the FMU's entry module (fmu.ENTRY). At run time it
needs numpy and the compiled core in the FMU's resources, nothing else; files are found
through the `resources` argument, never at import.
"""
import ctypes
import functools
import importlib.machinery
import importlib.util
import math
import os
import sys

import numpy as np
from pythonfmu import Fmi2Slave, Integer, Real
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Status, Fmi2Variability


# --- rendered by conical_pendulum.fmu ---
CORE_MODULE = "cp_core"
CORE_FILE = "cp_core.abi3.so"
PARAMETER_START = {}
INPUT_START = {}
STATE_START = {}
DESCRIPTION = ""
SETTINGS_START = {}
# --- end of rendered values ---

SOLVERS = ("rk4", "rk45", "dop853", "radau")
RADAU = SOLVERS.index("radau")
NEAR_SINGULAR = 1e-8  # pivot ratio worth naming when a step fails for another reason
REAL_SETTINGS = ("rtol", "atol", "max_step")
INTEGER_SETTINGS = ("solver", "max_steps")
STATS = ("n_rhs", "n_steps", "n_rejected")


def _load_core(resources):
    """The compiled core, from this FMU's resources (one copy per process and build)."""
    if CORE_MODULE in sys.modules:
        return sys.modules[CORE_MODULE]
    path = os.path.join(resources, CORE_FILE)
    loader = importlib.machinery.ExtensionFileLoader(CORE_MODULE, path)
    spec = importlib.util.spec_from_file_location(CORE_MODULE, path, loader=loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    sys.modules[CORE_MODULE] = module
    return module


def _fmi_call(method):
    """An FMI entry point whose exceptions the host survives.

    pythonfmu 0.7 turns an exception into fmi2Fatal and releases the Python instance,
    its class and its log queue once right away and once more in fmi2FreeInstance (the
    queue left dangling crashed later garbage collections). Taking one extra reference
    to each before the exception leaves keeps the host's memory intact when it frees
    the instance, as FMI asks it to.
    """
    @functools.wraps(method)
    def call(self, *args):
        try:
            return method(self, *args)
        except BaseException as exc:
            if not isinstance(exc, Refused):  # refusals are logged where they are made
                self.log(f"{method.__name__}: {exc}", Fmi2Status.error)
            for obj in (self, type(self), self.log_queue):
                ctypes.pythonapi.Py_IncRef(ctypes.py_object(obj))
            raise
    return call


class Refused(ValueError):
    """An input the slave refuses; its message went to the FMI logger already."""


class ConicalPendulum(Fmi2Slave):
    author = "conical-pendulum-fmu"
    description = DESCRIPTION
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=10.0, step_size=1.0 / 60.0)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        if sys.path.count(self.resources) > 1:  # pythonfmu adds it again per instance
            sys.path.remove(self.resources)
        # An exception here would crash the host (pythonfmu 0.7): keep it for later calls.
        self._broken = None
        try:
            self._core = _load_core(self.resources)
        except Exception as exc:  # noqa: BLE001 - reported at the next FMI call
            self._broken = f"cannot load the compiled core {CORE_FILE} from {self.resources}: {exc!r}"
            self.log(self._broken, Fmi2Status.fatal)
            return
        core = self._core
        # One array for every Real variable: parameters, inputs, state, outputs,
        # statistics, settings; getReal answers from it in one indexing. The core reads
        # parameters and inputs as one array p.
        n_p, n_state = len(PARAMETER_START) + len(INPUT_START), len(STATE_START)
        self._n_state = n_state
        stats_vr = n_p + n_state + core.NOUTPUT
        self._setting_vr = stats_vr + len(STATS)
        self._reals = np.zeros(self._setting_vr + len(REAL_SETTINGS))
        self._reals[:n_p] = list(PARAMETER_START.values()) + list(INPUT_START.values())
        self._reals[n_p:n_p + n_state] = list(STATE_START.values())
        self._reals[self._setting_vr:] = [SETTINGS_START[name] for name in REAL_SETTINGS]
        self._ints = [SETTINGS_START[name] for name in INTEGER_SETTINGS]
        self._state = self._reals[n_p:n_p + n_state]
        self._stepper = core.Stepper(self._reals[:n_p], self._reals[n_p:stats_vr],
                                     self._reals[stats_vr:self._setting_vr])
        self._stepper.update_outputs()
        self._mode = "instantiated"
        self._tolerance = None
        self._register()

    def _register(self):
        """Declare the variables in the order of self._reals, then the Integers.

        Their descriptions are added to the model description at build time."""
        fixed, continuous = Fmi2Variability.fixed, Fmi2Variability.continuous
        parameter, output = Fmi2Causality.parameter, Fmi2Causality.output
        for name in PARAMETER_START:
            self.register_variable(Real(name, causality=parameter, variability=fixed))
        for name in INPUT_START:  # held constant over each communication step
            self.register_variable(Real(name, causality=Fmi2Causality.input, variability=continuous))
        for name in STATE_START:
            self.register_variable(Real(name, causality=output, variability=continuous,
                                        initial=Fmi2Initial.exact))
        for name in self._core.OUTPUT_NAMES:
            self.register_variable(Real(name, causality=output, variability=continuous,
                                        initial=Fmi2Initial.calculated))
        for name in STATS:  # counts, as Real so that one getReal serves every output
            self.register_variable(Real(name, causality=output, variability=Fmi2Variability.discrete,
                                        initial=Fmi2Initial.calculated))
        for name in REAL_SETTINGS:
            self.register_variable(Real(name, causality=parameter, variability=fixed))
        for name in INTEGER_SETTINGS:
            self.register_variable(Integer(name, causality=parameter, variability=fixed))

    # --- FMI calls -------------------------------------------------------------------

    def _check_alive(self):
        if self._broken:
            raise RuntimeError(self._broken)

    @_fmi_call
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._check_alive()
        if tolerance is not None:
            self._tolerance = self._fail_unless_valid("tolerance (from setupExperiment)", tolerance)

    @_fmi_call
    def enter_initialization_mode(self):
        self._check_alive()
        self._mode = "initialization"

    @_fmi_call
    def exit_initialization_mode(self):
        self._check_alive()
        if self._tolerance is not None:
            self._reals[self._setting_vr] = self._tolerance
        self._stepper.update_outputs()
        self._configure()
        self._mode = "step"

    def _configure(self):
        """Settings are fixed from here on: hand them to the stepper once."""
        rtol, atol, max_step = self._reals[self._setting_vr:].tolist()
        self._stepper.configure(self._ints[0], rtol, atol, max_step, self._ints[1])

    @_fmi_call
    def do_step(self, current_time, step_size):
        if self._ints[0] == RADAU:
            failure = self._radau_step(current_time, step_size)
        else:
            status = self._stepper.advance(current_time, step_size)
            failure = status and self._step_failure(status, current_time, step_size)
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
            value = self._fail_unless_valid(name, value)
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
            value = int(value)
            if name == "solver" and not 0 <= value < len(SOLVERS):
                self._fail(f"solver = {value}: choose 0 to {len(SOLVERS) - 1} "
                           f"({', '.join(f'{k} = {s}' for k, s in enumerate(SOLVERS))})")
            if name == "max_steps" and value < 1:
                self._fail(f"max_steps = {value}: must be at least 1")
            self._ints[vr - first] = value

    def _radau_step(self, t, dt):
        """The stiff fallback: scipy's Radau IIA on the compiled right-hand side.

        Imports scipy, only when chosen. Returns None, or a message on failure.
        """
        from scipy.integrate import Radau

        if not (dt >= 0 and math.isfinite(dt)):
            return self._step_failure(self._core.BAD_STEP, t, dt)
        rtol, atol, max_step = self._reals[self._setting_vr:].tolist()
        core, stepper = self._core, self._stepper
        state, params = self._state, stepper.params
        options = {"first_step": min(stepper.h, dt)} if stepper.h > 0 else {}
        solver = Radau(lambda _, x: core.rhs(x, params), t, state.copy(), t + dt, rtol=rtol,
                       atol=atol, max_step=max_step or np.inf, **options)
        steps, problem = 0, None
        try:
            while solver.status == "running" and steps < self._ints[1]:
                problem = solver.step()
                steps += 1
        except core.CoreError as exc:
            problem = str(exc)
        stepper.stats[0] += solver.nfev
        stepper.stats[1] += steps
        if solver.status != "finished":
            problem = problem or f"more than max_steps = {self._ints[1]} internal steps were needed"
            return (f"do_step from t = {t:.9g} s by {dt:.3g} s failed (radau): {problem}. "
                    f"The state is kept at t = {t:.9g} s.")
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
        return {"reals": self._reals.tolist(), "ints": list(self._ints),
                "solver": self._stepper.memory(), "mode": self._mode,
                "tolerance": self._tolerance}

    @_fmi_call
    def _set_fmu_state(self, state):
        self._check_alive()
        self._reals[:] = state["reals"]
        self._ints[:] = state["ints"]
        self._stepper.restore(state["solver"])
        self._mode, self._tolerance = state["mode"], state["tolerance"]
        self._configure()

    # --- helpers ----------------------------------------------------------------------

    def _fail(self, message):
        """Report a bad input through the FMI logger and stop the call (pythonfmu: fmi2Fatal)."""
        self.log(message, Fmi2Status.error)
        raise Refused(message)

    def _fail_unless_valid(self, name, value):
        try:
            value = self._core.check_value(name, value)
        except self._core.BadValue as exc:
            self._fail(str(exc))
        if name in ("rtol", "atol") or name.startswith("tolerance"):
            if value <= 0:
                self._fail(f"{name} = {value!r}: a tolerance must be positive")
        if name == "max_step" and value < 0:
            self._fail(f"max_step = {value!r}: must be positive, or 0 for no limit")
        return value

    def _check_settable(self, vr, name):
        var = self.vars[vr]
        if var.causality == Fmi2Causality.output and var.initial != Fmi2Initial.exact:
            self._fail(f"{name} is a calculated output: it cannot be set")
        if self._mode == "step" and var.causality != Fmi2Causality.input:
            self._fail(f"{name} cannot be set after initialization (variability fixed); "
                       "set it before exitInitializationMode, or instantiate again")

    def _step_failure(self, status, t, dt):
        core, n = self._core, self._n_state // 4
        stepper = self._stepper
        what = core.STATUS.get(status, f"status {status}")
        dof = stepper.bad_dof
        speed = (f"omega{dof}" if dof < n else f"delta{dof - n}") if 0 <= dof < 2 * n else "?"
        rtol, atol, max_step = self._reals[self._setting_vr:].tolist()
        link = dof % n if dof >= 0 else "?"
        joint = (f"link {link}'s two-angle joint cannot represent this orientation (it lies "
                 "along its parent's x axis, alpha = +-90 degrees) or a link has too little "
                 "inertia")
        if status == core.BAD_STEP:
            hint = f"a communication step must be a non-negative finite number, not {dt!r}"
        elif status == core.SINGULAR:
            hint = (f"the mass matrix is singular (pivot ratio {stepper.pivot_ratio:.2g}, at "
                    f"{speed}): {joint}; give the link inertia or start elsewhere")
        elif status == core.NONFINITE:
            hint = f"the acceleration of {speed} is not finite; check parameters and state"
        else:
            if status == core.TOO_MANY_STEPS:
                hint = (f"more than max_steps = {self._ints[1]} internal steps were needed; raise "
                        f"max_steps, loosen rtol = {rtol:g} / atol = {atol:g}, or take shorter "
                        "communication steps")
            else:
                hint = (f"the step size fell below what time t can resolve; rtol = {rtol:g} / "
                        f"atol = {atol:g} cannot be met here: loosen them")
            if stepper.pivot_ratio < NEAR_SINGULAR:
                hint += (f". The mass matrix came close to singular on the way (pivot ratio "
                         f"{stepper.pivot_ratio:.2g}, at {speed}): {joint}")
        return (f"do_step from t = {t:.9g} s by {dt:.3g} s failed: {what}. {hint}. "
                f"The state is kept at t = {t:.9g} s.")
