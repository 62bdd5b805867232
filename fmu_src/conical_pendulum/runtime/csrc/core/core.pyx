# cython: language_level=3, boundscheck=False, wraparound=False, initializedcheck=False
"""Compiled core of one scene: right-hand side, outputs and solvers, all in C, and the
model behind the model contract (fmu_model.h: pendulum_model.c with the scene's variable
table) that the pythonfmu slave holds.

Copied to a module name unique to the scene and compiled against the limited API
(abi3). Imports numpy only.
"""
import numpy as np

cdef extern from "status.h":
    int CP_OK, CP_TOO_MANY_STEPS, CP_STEP_UNDERFLOW, CP_BAD_STEP, CP_MAX_STEP_UNRESOLVED, CP_STIFF
    int CP_SINGULAR, CP_NONFINITE
    const int cp_status_codes[]
    int CP_NSTATUS
    const char *cp_status_message(int status)

cdef extern from "solvers.h":
    ctypedef int (*cp_rhs_fn)(void *ctx, double t, const double *x, double *dx) noexcept nogil
    ctypedef int (*cp_jac_fn)(void *ctx, double t, const double *x, double *J) noexcept nogil
    ctypedef struct cp_watch:
        int n_events
    ctypedef struct cp_system:
        int dim
        cp_rhs_fn rhs
        void *ctx
        cp_jac_fn jac
        const cp_watch *watch
    ctypedef struct cp_stats:
        long long nfev, naccept, nreject, njev, nlu, nswitch
    ctypedef struct cp_newton:
        int jac_valid, current_jac, lu_valid, method
        double rho, h
    int CP_RK4, CP_RK45, CP_DOP853, CP_RADAU, CP_AUTO, CP_BDF
    int CP_WORK_SIZE(int dim)
    int CP_NEWTON_SIZE(int dim)
    int cp_unworkable(int method, double t, double dt, double max_step, long long max_steps)
    int cp_dense_grid(int method, const cp_system *sys, const double *times, int ntimes,
                      double *out, double rtol, double atol, double max_step,
                      long long max_steps, double *work, cp_newton *newton, double *matrices,
                      cp_stats *stats) noexcept nogil

cdef extern from "dynamics.h":
    int CP_NDOF, CP_NSTATE, CP_NPARAM, CP_NINPUT, CP_NOUTPUT, CP_PSIZE, CP_NHOIST_ACC
    int CP_NSTAT, CP_STAT_N_RHS, CP_STAT_N_STEPS, CP_STAT_N_REJECTED, CP_STAT_N_JACOBIANS
    int CP_STAT_N_FACTORIZATIONS
    const char *CP_STATE_NAMES
    const char *CP_PARAMETER_NAMES
    const char *CP_OUTPUT_NAMES
    double CP_SINGULAR_RATIO
    ctypedef struct cp_model:
        const double *p
        double pivot_ratio
        int bad_dof
    int cp_rhs(void *ctx, const double *x, double *dx) noexcept nogil
    void cp_mass_forcing(const double *x, const double *p, double *M, double *F) noexcept nogil
    void cp_rope_law(const double *x, double *p) noexcept nogil
    void cp_eval_outputs(const double *x, const double *p, double *y) noexcept nogil

cdef extern from "diagnosis.h":
    ctypedef struct cp_failure:
        double t, dt
        int bad_dof
        double pivot_ratio
        double rtol, atol, max_step
        long long max_steps
        double kept
        int rope
        double at, value, low, high
    int cp_diagnose(char *buf, size_t size, int status, const cp_failure *failure)

cdef extern from "cosim.h":
    ctypedef struct cp_settings:
        int method
        double rtol, atol, max_step
        long long max_steps
    ctypedef struct cp_jacobian_record:
        cp_newton newton
    ctypedef struct cp_matrices:
        cp_jacobian_record made_for
    int CP_STEP_WORK_SIZE
    int cp_cosim_step(const cp_settings *settings, const double *p, double *x, double *y,
                      double t, double dt, double *h, double *work, int *fsal,
                      cp_jacobian_record *jacobian, cp_matrices *matrices, double *stats,
                      cp_failure *failure) noexcept nogil
    int cp_held_rhs(void *ctx, double t, const double *x, double *dx) noexcept nogil
    int cp_held_jac(void *ctx, double t, const double *x, double *J) noexcept nogil
    const cp_watch *cp_held_watch(void *model, cp_watch *watch) noexcept nogil
    int cp_ropes_hold(const double *x, const double *y, double t, cp_failure *failure) noexcept nogil

cdef extern from "directional.h":
    int cp_directional(const double *x, const double *p, const double *dx_seed,
                       const double *dp_seed, double *d_derivatives, double *d_outputs,
                       double *pivot_ratio, int *bad_dof) noexcept nogil

cdef extern from "fmu_model.h":
    ctypedef struct ModelData:
        pass
    ctypedef enum ModelStatus:
        MODEL_OK, MODEL_DISCARD, MODEL_REFUSED, MODEL_WARNING, MODEL_NO_VARIABLE
    ctypedef struct ModelSizes:
        size_t data_size, scratch_size
        int n_real, n_integer, n_state
    const ModelSizes model_sizes
    void model_reset(ModelData *m)
    const char *model_tolerance_refusal(double tolerance, const char *name, char *message,
                                        size_t size)
    void model_set_tolerance(ModelData *m, double tolerance)
    const char *experiment_times_refusal(double start_time, int stop_time_defined,
                                         double stop_time, char *message, size_t size)
    void model_set_stop_time(ModelData *m, double stop_time)
    void model_initialize(ModelData *m)
    ModelStatus model_get_real(ModelData *m, unsigned vr, double *value, double time,
                               char *message, size_t size)
    ctypedef enum ModelPhase:
        MODEL_BEFORE_INIT, MODEL_AT_EVENT
    ModelStatus model_check_real(const ModelData *m, unsigned vr, double value, int phase,
                                 char *message, size_t size)
    void model_set_real(ModelData *m, unsigned vr, double value, int phase)
    ModelStatus model_get_integer(const ModelData *m, unsigned vr, int *value)
    ModelStatus model_check_integer(const ModelData *m, unsigned vr, int value, int initialized,
                                    char *message, size_t size)
    void model_set_integer(ModelData *m, unsigned vr, int value)
    void model_get_states(const ModelData *m, double x[])
    const char *model_set_states(ModelData *m, const double x[], char *message, size_t size)
    ModelStatus model_do_step(ModelData *m, double t, double dt, char *message, size_t size)
    const char *model_invalid(const ModelData *m, char *message, size_t size)

cdef extern from "<math.h>" nogil:
    double INFINITY

cdef extern from "<time.h>" nogil:
    cdef struct timespec:
        long tv_sec
        long tv_nsec
    int clock_gettime(int clk, timespec *ts)
    int CLOCK_MONOTONIC

NDOF = CP_NDOF
NSTATE = CP_NSTATE
NPARAM = CP_NPARAM  # parameters, then inputs: the p every function here takes
NINPUT = CP_NINPUT
NROPE = CP_NHOIST_ACC  # the ropes: the accelerations hoist_acc takes, their l''
NOUTPUT = CP_NOUTPUT
STATISTICS_SLOTS = {"n_rhs": CP_STAT_N_RHS, "n_steps": CP_STAT_N_STEPS, "n_rejected": CP_STAT_N_REJECTED,
                    "n_jacobians": CP_STAT_N_JACOBIANS, "n_factorizations": CP_STAT_N_FACTORIZATIONS}
SINGULAR_RATIO = CP_SINGULAR_RATIO
STATE_NAMES = tuple(CP_STATE_NAMES.decode().split())
PARAMETER_NAMES = tuple(CP_PARAMETER_NAMES.decode().split())
OUTPUT_NAMES = tuple(CP_OUTPUT_NAMES.decode().split())
TOO_MANY_STEPS, STEP_UNDERFLOW, BAD_STEP = CP_TOO_MANY_STEPS, CP_STEP_UNDERFLOW, CP_BAD_STEP
MAX_STEP_UNRESOLVED, STIFF = CP_MAX_STEP_UNRESOLVED, CP_STIFF
SINGULAR, NONFINITE = CP_SINGULAR, CP_NONFINITE
METHODS = {
    "rk4": CP_RK4, "rk45": CP_RK45, "dop853": CP_DOP853, "radau": CP_RADAU, "auto": CP_AUTO, "bdf": CP_BDF
}
STATUS = {cp_status_codes[k]: cp_status_message(cp_status_codes[k]).decode()  # status.h's list
          for k in range(CP_NSTATUS)}


class CoreError(RuntimeError):
    """The right-hand side failed: singular mass matrix or non-finite result."""

    def __init__(self, status, dof, pivot_ratio):
        self.status, self.dof, self.pivot_ratio = status, dof, pivot_ratio
        super().__init__(f"{STATUS.get(status, status)} at generalized speed {dof} "
                         f"(pivot ratio {pivot_ratio:.3g})")


cdef cp_model _fresh_model(const double *p) noexcept nogil:
    """The model at the core's p, its diagnostics fresh (no pivot seen, no speed at fault)."""
    cdef cp_model model
    model.p = p
    model.pivot_ratio = 1.0
    model.bad_dof = -1
    return model


cdef void _system(cp_system *system, cp_model *model, const double *p, cp_stats *stats) noexcept nogil:
    """The model's right-hand side as a solver's system, with fresh diagnostics and counters."""
    model[0] = _fresh_model(p)
    system.dim = CP_NSTATE
    system.rhs = cp_held_rhs
    system.ctx = model
    system.jac = cp_held_jac
    system.watch = NULL
    stats.nfev = stats.naccept = stats.nreject = stats.njev = stats.nlu = stats.nswitch = 0


cdef void _check(const double[::1] a, int size, str what) except *:
    if a.shape[0] != size:
        raise ValueError(f"{what}: expected {size} values, got {a.shape[0]}")


cdef const double[::1] _vector(object a, int size, str what):
    """Any 1-d sequence of numbers as contiguous doubles (scipy passes strided views)."""
    cdef const double[::1] v
    try:
        v = a
    except (ValueError, TypeError):
        v = np.ascontiguousarray(a, dtype=float).reshape(-1)
    _check(v, size, what)
    return v


cdef const double[::1] _core_p(object p_in, object hoist_acc):
    """The core's p (dynamics.h): the parameters and inputs p, then each rope's l'' (the
    rates of its v_hoist, Scene.ropes' order; None: 0, the winches at constant speed), then
    the elastic ropes' law (0 here: the core computes it from the state). Without ropes, p
    itself."""
    cdef const double[::1] parameters = _vector(p_in, CP_NPARAM, "parameters")
    if CP_PSIZE == CP_NPARAM and hoist_acc is None:
        return parameters
    p = np.zeros(CP_PSIZE)
    p[:CP_NPARAM] = parameters
    if hoist_acc is not None:
        p[CP_NPARAM:CP_NPARAM + CP_NHOIST_ACC] = _vector(hoist_acc, CP_NHOIST_ACC, "hoist_acc")
    return p


def rhs(x_in, p_in, hoist_acc=None):
    """x' = f(x, p) as a new array, the ropes' lengths accelerating at hoist_acc (_core_p);
    raises CoreError where M is singular."""
    cdef const double[::1] x = _vector(x_in, CP_NSTATE, "state")
    cdef const double[::1] p = _core_p(p_in, hoist_acc)
    out = np.empty(CP_NSTATE)
    cdef double[::1] dx = out
    cdef cp_model model = _fresh_model(&p[0])
    cdef int status
    with nogil:
        status = cp_rhs(&model, &x[0], &dx[0])
    if status:
        raise CoreError(status, model.bad_dof, model.pivot_ratio)
    return out


def mass_forcing(x_in, p_in, hoist_acc=None):
    """(M, F) with M u' = F at state x (hoist_acc: as rhs's)."""
    cdef const double[::1] x = _vector(x_in, CP_NSTATE, "state")
    cdef const double[::1] p = _core_p(p_in, hoist_acc)
    M = np.empty((CP_NDOF, CP_NDOF))
    F = np.empty(CP_NDOF)
    cdef double[:, ::1] m = M
    cdef double[::1] f = F
    cdef double[::1] law = np.array(p)  # with the elastic ropes' law at x
    with nogil:
        cp_rope_law(&x[0], &law[0])
        cp_mass_forcing(&x[0], &law[0], &m[0, 0], &f[0])
    return M, F


def outputs(x_in, p_in, hoist_acc=None):
    """The scene's calculated outputs at state x (hoist_acc: as rhs's)."""
    cdef const double[::1] x = _vector(x_in, CP_NSTATE, "state")
    cdef const double[::1] p = _core_p(p_in, hoist_acc)
    out = np.empty(CP_NOUTPUT)
    cdef double[::1] y = out
    if CP_NOUTPUT:
        with nogil:
            cp_eval_outputs(&x[0], &p[0], &y[0])
    return out


def jacobian(x_in, p_in, hoist_acc=None):
    """J = df/dx at state x as a new (NSTATE, NSTATE) array, exact (directional.h's
    cp_jacobian, the implicit solver's own); raises CoreError where M is singular."""
    cdef const double[::1] x = _vector(x_in, CP_NSTATE, "state")
    cdef const double[::1] p = _core_p(p_in, hoist_acc)
    out = np.empty((CP_NSTATE, CP_NSTATE))
    cdef double[:, ::1] J = out
    cdef cp_model model = _fresh_model(&p[0])
    cdef int status
    with nogil:
        status = cp_held_jac(&model, 0.0, &x[0], &J[0, 0])
    if status:
        raise CoreError(status, model.bad_dof, model.pivot_ratio)
    return out


def directional(x_in, p_in, seed_in, hoist_acc=None):
    """(df/dx) seed at state x as a new array, by one complex step of the whole right-hand
    side (what the FMUs' directional derivatives take): the independent check of jacobian,
    which the recursive formulation computes otherwise."""
    cdef const double[::1] x = _vector(x_in, CP_NSTATE, "state")
    cdef const double[::1] p = _core_p(p_in, hoist_acc)
    cdef const double[::1] seed = _vector(seed_in, CP_NSTATE, "seed")
    cdef const double[::1] no_dp = np.zeros(CP_PSIZE)
    out = np.empty(CP_NSTATE)
    cdef double[::1] d = out
    cdef double pivot_ratio = 1.0
    cdef int bad_dof = -1, status
    with nogil:
        status = cp_directional(&x[0], &p[0], &seed[0], &no_dp[0], &d[0], NULL, &pivot_ratio,
                                &bad_dof)
    if status:
        raise CoreError(status, bad_dof, pivot_ratio)
    return out


def integrate_grid(x0, p_in, times_in, double rtol=1e-10, double atol=1e-10,
                   double max_step=0.0, long long max_steps=10**7, str method="dop853",
                   dict counts=None):
    """States at every time, by the core's DOP853 (or method="rk45", "radau", "bdf", "auto") with
    dense output: (array, nfev).

    One integration over the whole grid, as solve_ivp(method="DOP853", t_eval=times)
    does, with no Python per step, its steps ending on the elastic ropes' switches as the
    FMUs' do (cosim.h's cp_held_watch); counts (a dict), when given, receives every count
    (nfev, naccept, nreject, njev, nlu, nswitch: the automatic choice's switches). Raises CoreError or RuntimeError on failure.
    """
    if method not in ("rk45", "dop853", "radau", "bdf", "auto"):
        raise ValueError(f"method: 'rk45', 'dop853', 'radau', 'bdf' or 'auto', not {method!r}")
    cdef int solver = METHODS[method]
    cdef const double[::1] p = _core_p(p_in, None)
    cdef const double[::1] times = np.ascontiguousarray(times_in, dtype=float)
    if times.shape[0] < 1 or np.any(np.diff(times) < 0):
        raise ValueError("times: expected a non-empty, non-decreasing sequence")
    result = np.empty((times.shape[0], CP_NSTATE))
    result[0] = _vector(x0, CP_NSTATE, "state")
    cdef double[:, ::1] out = result
    cdef double[::1] work = np.zeros(CP_WORK_SIZE(CP_NSTATE))
    cdef double[::1] matrices = np.zeros(CP_NEWTON_SIZE(CP_NSTATE))
    cdef cp_newton newton
    newton.jac_valid = newton.current_jac = newton.lu_valid = newton.method = 0
    newton.rho = newton.h = 0.0
    cdef cp_model model
    cdef cp_system system
    cdef cp_stats stats
    cdef cp_watch watch
    _system(&system, &model, &p[0], &stats)
    system.watch = cp_held_watch(&model, &watch)  # the elastic ropes' switches, located
    cdef int status
    with nogil:
        status = cp_dense_grid(solver, &system, &times[0], times.shape[0], &out[0, 0], rtol,
                               atol, max_step, max_steps, &work[0], &newton, &matrices[0], &stats)
    if counts is not None:
        counts.update(nfev=stats.nfev, naccept=stats.naccept, nreject=stats.nreject,
                      njev=stats.njev, nlu=stats.nlu, nswitch=stats.nswitch)
    if status >= CP_SINGULAR:
        raise CoreError(status, model.bad_dof, model.pivot_ratio)
    if status:
        raise RuntimeError(f"{method.upper()} failed: {STATUS[status]}")
    return result, stats.nfev


def seconds_per_call(str what, x_in, p_in, long calls):
    """Seconds per call of the C right-hand side (what="rhs") or outputs ("outputs"),
    timed in a C loop."""
    cdef const double[::1] x = _vector(x_in, CP_NSTATE, "state")
    cdef const double[::1] p = _core_p(p_in, None)
    if what not in ("rhs", "outputs"):
        raise ValueError(f"what: 'rhs' or 'outputs', not {what!r}")
    cdef bint outputs = what == "outputs"
    cdef double[::1] buffer = np.zeros(max(CP_NSTATE, CP_NOUTPUT, 1))
    cdef double *out = &buffer[0]
    cdef cp_model model
    cdef cp_system system
    cdef cp_stats stats
    _system(&system, &model, &p[0], &stats)
    cdef timespec start, stop
    cdef long i
    with nogil:
        clock_gettime(CLOCK_MONOTONIC, &start)
        for i in range(calls):
            if outputs:
                cp_eval_outputs(&x[0], &p[0], out)
            else:
                cp_rhs(&model, &x[0], out)
        clock_gettime(CLOCK_MONOTONIC, &stop)
    return ((stop.tv_sec - start.tv_sec) + 1e-9 * (stop.tv_nsec - start.tv_nsec)) / calls


cdef class Stepper:
    """State, parameters and solver memory of one simulation, advanced in C.

    `values` holds the state followed by the outputs, so an FMU answers get_real
    from one array. A failed step leaves the state as it was. max_steps bounds the
    internal steps of one call, so a step always returns.

    Stepper(params, values, stats=None): float64 arrays of NPARAM values, of NSTATE +
    NOUTPUT values (the state first) and of NSTAT counters (right-hand side evaluations,
    accepted and rejected steps, in runtime.rules.STATISTICS's order), used in place, so whoever owns them sees every step.
    """
    cdef public object values, params, stats
    cdef double[::1] _values, _params, _stats, _work, _jacobian, _matrices
    cdef int _fsal
    cdef cp_settings _settings
    cdef cp_failure _failure
    cdef public double h

    def __init__(self, params, values, stats=None):
        self.params, self.values = params, values
        self.stats = np.zeros(CP_NSTAT) if stats is None else stats
        self._params = params
        self._values = values
        self._stats = self.stats
        _check(self._params, CP_NPARAM, "parameters")
        _check(self._values, CP_NSTATE + CP_NOUTPUT, "state and outputs")
        _check(self._stats, CP_NSTAT, "statistics")
        self._work = np.zeros(CP_STEP_WORK_SIZE)
        # the implicit solver's cp_jacobian_record and cp_matrices, zeroed (no Jacobian yet),
        # aligned as a double
        self._jacobian = np.zeros((sizeof(cp_jacobian_record) + sizeof(double) - 1) // sizeof(double))
        self._matrices = np.zeros((sizeof(cp_matrices) + sizeof(double) - 1) // sizeof(double))
        self.h = 0.0
        self._fsal = 0

    @property
    def nfev(self):
        return int(self._stats[CP_STAT_N_RHS])

    @property
    def naccept(self):
        return int(self._stats[CP_STAT_N_STEPS])

    @property
    def nreject(self):
        return int(self._stats[CP_STAT_N_REJECTED])

    def update_outputs(self):
        """Recompute the outputs after the state or the parameters were changed in place."""
        self._fsal = 0
        cdef const double[::1] p = _core_p(self._params, None)
        if CP_NOUTPUT:
            with nogil:
                cp_eval_outputs(&self._values[0], &p[0], &self._values[CP_NSTATE])

    def configure(self, int method, double rtol, double atol, double max_step,
                  long long max_steps):
        """Fix the solver settings that advance() uses."""
        self._settings.method, self._settings.rtol, self._settings.atol = method, rtol, atol
        self._settings.max_step, self._settings.max_steps = max_step, max_steps

    def advance(self, double t, double dt):
        """One co-simulation step with the configured settings (cosim.c, as the native FMU
        takes it): a status code, 0 when the state and outputs reached t + dt."""
        cdef int status
        with nogil:
            status = cp_cosim_step(&self._settings, &self._params[0], &self._values[0],
                                   &self._values[CP_NSTATE], t, dt, &self.h, &self._work[0],
                                   &self._fsal, <cp_jacobian_record *>&self._jacobian[0],
                                   <cp_matrices *>&self._matrices[0], &self._stats[0],
                                   &self._failure)
        return status

    def step(self, int method, double t, double dt, double rtol, double atol, double max_step,
             long long max_steps):
        """configure() and advance() in one call; returns a status code (0: ok; see STATUS)."""
        self.configure(method, rtol, atol, max_step, max_steps)
        return self.advance(t, dt)


class Refusal(ValueError):
    """A value, setting or state the model refuses; the message is the model's (fmu_model.h),
    the words the native FMUs log."""


cdef class Model:
    """One instance of the model behind the model contract (fmu_model.h): pendulum_model.c
    with the FMU's variable table, as the native FMUs hold it. The pythonfmu slave keeps
    its variables, settings and solver memory here and takes its values, checks, steps and
    FMU states from these methods, so both FMUs answer with the same C.

    A new Model is model_reset's: every variable at its start value. Value references are
    the FMU's (fmu_config.h); the slave checks that a variable is of the type asked for.
    """
    cdef double[::1] _data  # the ModelData and its scratch, aligned as a double (fmu_model.h)
    cdef ModelData *m
    cdef char message[2048]

    def __cinit__(self):
        self._data = np.zeros((model_sizes.data_size + model_sizes.scratch_size + sizeof(double) - 1)
                              // sizeof(double))
        self.m = <ModelData *>&self._data[0]
        model_reset(self.m)

    cdef _refused(self, ModelStatus status, unsigned vr):
        if status == MODEL_NO_VARIABLE:
            raise TypeError(f"value reference {vr} is not a variable of this type")
        if status != MODEL_OK:
            raise Refusal(self.message.decode())

    def get_reals(self, vrs):
        """The Real variables vrs (model_get_real), as a list."""
        cdef double value
        cdef ModelStatus status
        values = []
        for vr in vrs:
            status = model_get_real(self.m, vr, &value, 0.0, self.message, sizeof(self.message))
            if status != MODEL_OK:
                self._refused(status, vr)
            values.append(value)
        return values

    def set_reals(self, vrs, values, bint initialized):
        """Every value checked (model_check_real) before any is taken (model_set_real), as
        the FMI layers take them; raises Refusal with the model's message. Initialized, the
        slave (Co-Simulation) is at a communication point: a change that moves the energy
        jumps its book."""
        cdef int phase = MODEL_AT_EVENT if initialized else MODEL_BEFORE_INIT
        for vr, value in zip(vrs, values):
            self._refused(model_check_real(self.m, vr, value, phase, self.message,
                                           sizeof(self.message)), vr)
        for vr, value in zip(vrs, values):
            model_set_real(self.m, vr, value, phase)

    def get_integers(self, vrs):
        cdef int value
        values = []
        for vr in vrs:
            self._refused(model_get_integer(self.m, vr, &value), vr)
            values.append(value)
        return values

    def set_integers(self, vrs, values, bint initialized):
        """As set_reals, for Integers (model_check_integer, model_set_integer)."""
        for vr, value in zip(vrs, values):
            self._refused(model_check_integer(self.m, vr, value, initialized, self.message,
                                              sizeof(self.message)), vr)
        for vr, value in zip(vrs, values):
            model_set_integer(self.m, vr, value)

    def set_tolerance(self, double tolerance):
        """The experiment's tolerance, taken at initialize(); Refusal as the model refuses it."""
        if model_tolerance_refusal(tolerance, NULL, self.message, sizeof(self.message)):
            raise Refusal(self.message.decode())
        model_set_tolerance(self.m, tolerance)

    def set_experiment_times(self, double start_time, stop_time):
        """The experiment's stop time (None: none), beyond which no solver step goes; Refusal
        as the FMI layers refuse the times (experiment_times_refusal)."""
        defined = stop_time is not None
        if experiment_times_refusal(start_time, defined, stop_time if defined else 0.0,
                                    self.message, sizeof(self.message)):
            raise Refusal(self.message.decode())
        model_set_stop_time(self.m, stop_time if defined else INFINITY)

    def initialize(self):
        model_initialize(self.m)

    def do_step(self, double t, double dt):
        """One communication step (model_do_step): None, or the diagnosis of a discarded one."""
        if model_do_step(self.m, t, dt, self.message, sizeof(self.message)) == MODEL_OK:
            return None
        return self.message.decode()

    @property
    def states(self):
        """The continuous states x, as a new array."""
        x = np.empty(CP_NSTATE)
        cdef double[::1] out = x
        model_get_states(self.m, &out[0])
        return x

    def set_states(self, x_in):
        """Takes x (model_set_states), or raises Refusal and takes nothing."""
        cdef const double[::1] x = _vector(x_in, CP_NSTATE, "state")
        if model_set_states(self.m, &x[0], self.message, sizeof(self.message)):
            raise Refusal(self.message.decode())

    @property
    def data(self):
        """The ModelData's bytes: what the native FMUs' FMU states hold of the model."""
        return np.asarray(self._data).view(np.uint8)[: model_sizes.data_size].tobytes()

    @data.setter
    def data(self, bytes data):
        """Takes bytes of a ModelData, checked first (model_invalid): Refusal naming the
        field and its value, and nothing taken."""
        if len(data) != <Py_ssize_t>model_sizes.data_size:
            raise Refusal(f"size = {len(data)} bytes: this model's data has {model_sizes.data_size}")
        candidate = Model()
        np.asarray(candidate._data).view(np.uint8)[: model_sizes.data_size] = np.frombuffer(data, np.uint8)
        if model_invalid(candidate.m, self.message, sizeof(self.message)):
            raise Refusal(self.message.decode())
        own = np.asarray(self._data).view(np.uint8)  # the data taken, this instance's scratch kept
        own[: model_sizes.data_size] = np.asarray(candidate._data).view(np.uint8)[: model_sizes.data_size]
