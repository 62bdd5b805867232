/* What FMI 2.0 and FMI 3.0 share, written once: the generic body of the FMI layers.
 *
 * The part src/cosimulation.c plays beside src/fmi2Functions.c and src/fmi3Functions.c in the
 * Modelica Reference-FMUs. An FMI layer (fmi2_glue.c, fmi3_glue.c) keeps its standard's API,
 * types and state table (the states each function may be called in) and the functions only its
 * standard has; for what both standards do alike (the check of an instance's state, logging,
 * SetDebugLogging, Reset, the experiment, leaving initialization, Real and Integer access by
 * scalar, directional derivatives, the Model Exchange states, derivatives, event indicators and
 * event update, the FMU states: get, set, free, serialize and the check of a restored one) its
 * entry point is a thin wrapper over a function here, which it hands its own function's name.
 *
 * Plain C on the model contract (fmu_model.h): no FMI header, no fmu_config.h. A layer
 * describes its standard once (FmiStandard: state bits and names, the words of its messages,
 * its log categories and token) and its instance begins with an FmiInstance. Status codes are
 * FMI 2.0's and FMI 3.0's alike (OK 0, Warning 1, Discard 2, Error 3), so a layer casts them.
 * The functions a wrapper hands fmi_checked's result take NULL (a call refused in its state)
 * and return FMI_ERROR for it; the helpers (fmi_log, fmi_error, fmi_discard, fmi_get_real,
 * fmi_check_real, fmi_derivative, fmi_event_update) need an instance. Nothing is allocated but
 * an instance's FMU states, with the allocator the layer gives. */
#ifndef FMI_LAYER_H
#define FMI_LAYER_H

#include <stddef.h>

#include "fmu_model.h"

typedef enum { FMI_OK = 0, FMI_WARNING = 1, FMI_DISCARD = 2, FMI_ERROR = 3 } FmiStatus;

/* Where an instance is in its standard's state machine (one bit per state), its time, and
 * the last time a step reached; plain data, saved and serialized as a whole. */
typedef struct {
    int state;
    double time;
    double last_successful_time;
} FmiMachine;

typedef struct FmiInstance FmiInstance;

/* What a layer says of its standard: the states the shared functions move an instance
 * between, and the words its messages use. One const object per layer. */
typedef struct {
    const char *name;                     /* "FMI 2.0" */
    const char *const *state_names;       /* by bit, as the standard names its states */
    int n_states;
    int co_simulation_states;             /* every state a Co-Simulation instance enters */
    int model_exchange_states;            /* and a Model Exchange one */
    int instantiated, initialization;
    int stepping;                         /* a Co-Simulation instance after initialization */
    int event_mode;                       /* a Model Exchange one */
    int continuous_time;                  /* Model Exchange's continuous-time mode */
    int step_failed;                      /* after a discarded step (0: none) */
    /* checked's message: "<function> is not allowed in <in_state><name> (<standard>,
     * <where>)<why>"; never: why for a function allowed in no state this FMU enters;
     * after_failed: why, in step_failed. */
    const char *in_state, *co_simulation_where, *model_exchange_where, *never, *after_failed;
    const char *experiment;               /* the prefix of the experiment's refusals */
    const char *tolerance;                /* how they name the tolerance */
    const char *arguments_null;           /* "vr or value is NULL" */
    const char *n_states_argument;        /* "nx" */
    const char *n_indicators_argument;    /* "ni" */
    const char *fmu_state;                /* the FMU state's argument: "FMUstate" */
    const char *serialized_size;          /* the function that says a serialized state's size */
    unsigned state_magic;                 /* the first bytes of a serialized state */
    const char *token;                    /* the model description's GUID or token (CP_GUID) */
    const char *token_mismatch;           /* instantiation's refusal of another token */
    const char *const *log_categories;    /* cp_log_categories, CP_NLOG of them */
    int n_log_categories;
    int log_error, log_discard, log_warning;  /* CP_LOG_STATUS_ERROR, _DISCARD, _WARNING */
    const char *(*variable_name)(unsigned vr);  /* cp_variable_name: a scalar's name */
    /* A formatted message to the host's logger of inst (the layer's instance), if it has one. */
    void (*emit)(FmiInstance *inst, FmiStatus status, const char *category, const char *text);
} FmiStandard;

/* What the shared body keeps of an instance: the first member of each layer's instance,
 * whose allocation then holds the model's data (model). */
struct FmiInstance {
    FmiMachine machine;
    const FmiStandard *standard;
    int co_simulation;                    /* else Model Exchange */
    int early_return_allowed;             /* FMI 3.0's earlyReturnAllowed; 0 in FMI 2.0 */
    unsigned logging;                     /* bit k: log category k is on */
    void *(*allocate)(size_t n, size_t size);  /* zeroed memory for FMU states */
    void (*release)(void *memory);
    ModelData *model;
    char discarded[2048];                 /* the last discarded step's diagnosis */
};

/* inst's shared part before its first reset: zeroed, padding too; logging all categories or
 * none. The layer then checks its instantiation's arguments (fmi_instantiation_problem) and
 * resets it. */
void fmi_instance_init(FmiInstance *inst, const FmiStandard *standard, int co_simulation,
                       int logging_on, void *(*allocate)(size_t, size_t),
                       void (*release)(void *), ModelData *model);

/* NULL if an instance may be made of these arguments, or why not, naming the argument. */
const char *fmi_instantiation_problem(const FmiStandard *standard, const char *instance_name,
                                      const char *token);

/* ---- messages, and the check of a call --------------------------------------------------- */

/* A message through the host's logger in category (an index of standard->log_categories):
 * warnings and errors always (FMI 2.0, section 2.1.3; FMI 3.0 alike), others (a discard's
 * diagnosis) only when category is on (loggingOn, then SetDebugLogging). */
void fmi_log(FmiInstance *inst, FmiStatus status, int category, const char *format, ...);

/* An error: logged in the error category; returns FMI_ERROR. */
FmiStatus fmi_error(FmiInstance *inst, const char *format, ...);

/* A discard: the model's message logged in the discard category; returns FMI_DISCARD. */
FmiStatus fmi_discard(FmiInstance *inst, const char *message);

/* The instance c if its standard allows function in its state (co_simulation and
 * model_exchange: the function's row of the layer's state table, in the instance's column);
 * otherwise NULL, logging why, naming the state. */
FmiInstance *fmi_checked(void *c, const char *function, int co_simulation, int model_exchange);

/* Whether the instance is past initialization mode, where only inputs may still be set. */
int fmi_initialized(const FmiInstance *inst);

/* Where the instance is for a value set (fmu_model.h's ModelPhase): before initialization;
 * Model Exchange's continuous-time mode; else at an event (a Co-Simulation communication
 * point, Model Exchange's event mode). */
int fmi_phase(const FmiInstance *inst);

/* ---- the functions both standards have ----------------------------------------------------- */

/* SetDebugLogging (FMI 2.0, section 2.1.5; FMI 3.0, section 2.3.1): with n = 0, on applies to
 * every category; with a list, on makes the listed ones the categories in force, off turns
 * the listed ones off and leaves the others. A name the model description does not declare is
 * refused, naming it, and the categories in force stay as they were. */
FmiStatus fmi_set_debug_logging(FmiInstance *inst, const char *function, int on, size_t n,
                                const char *const categories[]);

/* The instance as it is instantiated and as Reset leaves it (never refused: inst may be in
 * any state). */
FmiStatus fmi_reset(FmiInstance *inst);

/* The experiment (FMI 2.0's fmi2SetupExperiment, FMI 3.0's fmi3EnterInitializationMode): the
 * tolerance, if defined, refused as the model refuses it, the start time, and the stop time,
 * if defined, refused unless finite and not before the start. */
FmiStatus fmi_setup_experiment(FmiInstance *inst, int tolerance_defined, double tolerance,
                               double start_time, int stop_time_defined, double stop_time);

/* The instance into state (EnterInitializationMode, Terminate, EnterEventMode, ...). */
FmiStatus fmi_enter(FmiInstance *inst, int state);

/* Leaving initialization: the model initialized, a Co-Simulation instance stepping, a Model
 * Exchange one in event mode. */
FmiStatus fmi_exit_initialization(FmiInstance *inst);

/* Whether a Co-Simulation step may start at t (DoStep's currentCommunicationPoint): where the
 * instance is, to 1e-9 relative; refused otherwise, naming both times. */
FmiStatus fmi_communication_point(FmiInstance *inst, const char *function, double t);

/* The Real (FMI 3.0: Float64, type) variable vr into *value, or refused (FMI_ERROR) or
 * discarded (FMI_DISCARD) as the model says; named: the value reference a refusal names (an
 * FMI 3.0 array's for its element). */
FmiStatus fmi_get_real(FmiInstance *inst, const char *function, const char *type, unsigned vr,
                       unsigned named, double *value);

/* fmi_get_real for each of vr[0..nvr) into values, stopping at the first not FMI_OK: one call
 * for a whole row (FMI 2.0's fmi2GetReal), as a host reading every output at every
 * communication point calls it. */
FmiStatus fmi_get_reals(FmiInstance *inst, const char *function, const char *type,
                        const unsigned vr[], size_t nvr, double values[]);

/* Whether value may be set into the Real variable vr (model_check_real, in fmi_phase), without
 * taking it: FMI_OK; FMI_WARNING, logged, where it is taken but not honoured in full; or
 * refused (FMI_ERROR). */
FmiStatus fmi_check_real(FmiInstance *inst, const char *function, const char *type, unsigned vr,
                         unsigned named, double value);

/* Integer (FMI 2.0) and Int32 (FMI 3.0) variables: type names them in messages; all values
 * of a set checked before any is taken. */
FmiStatus fmi_get_integers(FmiInstance *inst, const char *function, const char *type,
                           const unsigned vr[], size_t nvr, int values[]);
FmiStatus fmi_set_integers(FmiInstance *inst, const char *function, const char *type,
                           const unsigned vr[], size_t nvr, const int values[]);

/* A type the model contract has none of: any value reference refused. */
FmiStatus fmi_no_variables(FmiInstance *inst, const char *function, const char *type,
                           const unsigned vr[], size_t nvr);

/* A directional derivative, sensitivity = J seed, or with adjoint seed^T J (FMI 3.0's adjoint),
 * J the Jacobian of the unknowns (n_unknown scalars, the standard's arrays expanded) with
 * respect to the knowns at the current values: the seed refused unless finite (seed names it:
 * "dvKnown", "seed"), the model's derivative, and a sensitivity that is not finite never
 * passed on (FMI_DISCARD). Nothing of the instance changes. */
FmiStatus fmi_derivative(FmiInstance *inst, const char *function, const char *seed_name, int adjoint,
                         const unsigned unknown[], size_t n_unknown, const unsigned known[],
                         size_t n_known, const double seed[], double sensitivity[]);

/* ---- input and output derivatives (Co-Simulation) ------------------------------------------ */

/* Whether value may be the order-th time derivative of the Real input vr (a continuous input,
 * order 1 to MODEL_MAX_DERIVATIVE_ORDER, value finite), without taking it: FMI_OK, or refused
 * naming named's variable. A layer checks every value of a call before it sets any
 * (model_set_input_derivative). */
FmiStatus fmi_check_input_derivative(FmiInstance *inst, const char *function, unsigned vr,
                                     unsigned named, int order, double value);

/* The order-th time derivative of the continuous output vr into *value: refused (a value
 * reference that is no continuous output, an order out of range), discarded where it cannot be
 * had or is not finite. */
FmiStatus fmi_get_output_derivative(FmiInstance *inst, const char *function, unsigned vr,
                                    unsigned named, int order, double *value);

/* ---- Model Exchange ------------------------------------------------------------------------ */

FmiStatus fmi_set_time(FmiInstance *inst, const char *function, double time);
/* CompletedIntegratorStep: refused if either output pointer (enterEventMode,
 * terminateSimulation) is NULL; the layer writes false into both on FMI_OK (no step events:
 * the host finds the state events from the event indicators). */
FmiStatus fmi_completed_integrator_step(FmiInstance *inst, const char *function,
                                        const void *enter_event_mode,
                                        const void *terminate_simulation);
FmiStatus fmi_set_continuous_states(FmiInstance *inst, const char *function, const double x[],
                                    size_t nx);
FmiStatus fmi_get_continuous_states(FmiInstance *inst, const char *function, double x[], size_t nx);
FmiStatus fmi_get_derivatives(FmiInstance *inst, const char *function, double dx[], size_t nx);
FmiStatus fmi_get_nominals(FmiInstance *inst, const char *function, double x_nominal[], size_t nx);
/* The event indicators (model_get_event_indicators: an elastic rope's taut margin, whose sign
 * change is its slack or snap event) into z: refused unless ni is model_sizes.n_event_indicator
 * (naming both) and, for ni > 0, z is an array. */
FmiStatus fmi_get_event_indicators(FmiInstance *inst, const char *function, double z[], size_t ni);
/* An event the host handles (FMI 2.0's NewDiscreteStates, FMI 3.0's UpdateDiscreteStates):
 * the model's discrete outputs updated (model_event_update); whether a value set in event mode
 * jumped the continuous states (valuesOfContinuousStatesChanged). Nothing needs another
 * iteration. */
int fmi_event_update(FmiInstance *inst);

/* ---- FMU states ------------------------------------------------------------------------------
 * An FMU state is the machine and then the model's data (model_sizes.data_size bytes), plain
 * data copied as a whole; serialized, it follows a header: the standard's magic, its size, and
 * the token (its '\0' included) of the build that wrote it, padded to an unsigned's alignment.
 * A restored state is checked as values set through the API are (its machine state one of
 * the interface's, model_invalid, finite times) before any of it is taken. */

FmiStatus fmi_get_fmu_state(FmiInstance *inst, const char *function, void **state);
FmiStatus fmi_set_fmu_state(FmiInstance *inst, const char *function, const void *state);
/* Never refused: inst may be in any state. */
FmiStatus fmi_free_fmu_state(FmiInstance *inst, const char *function, void **state);
FmiStatus fmi_serialized_size(FmiInstance *inst, const char *function, const void *state,
                              size_t *size);
FmiStatus fmi_serialize(FmiInstance *inst, const char *function, const void *state,
                        unsigned char bytes[], size_t size);
FmiStatus fmi_deserialize(FmiInstance *inst, const char *function, const unsigned char bytes[],
                          size_t size, void **state);

#endif
