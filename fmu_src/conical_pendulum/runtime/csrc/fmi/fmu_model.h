/* The model contract: what a model offers the FMI layers, and all they know of it.
 *
 * The part include/model.h plays for the Modelica Reference-FMUs' generic glue. An FMI layer
 * (fmi2_glue.c: FMI 2.0's API, its state machine and FMU states) includes this header and
 * fmu_config.h, and from fmu_config.h takes only what describes the FMU as a whole: its GUID
 * (CP_GUID), its log categories (CP_LOG_*, cp_log_categories) and its variables' names by
 * value reference (cp_variable_name). It never reads the model's data, never applies a value
 * rule, never names a model quantity. A model (pendulum_model.c: the n-link conical
 * pendulum) implements these functions and knows nothing of FMI: no fmi2 type, no state
 * machine, no logger; it answers with a ModelStatus and, where something is refused or
 * cannot be computed, a message the FMI layer passes on through the host's logger. The
 * pythonfmu FMU's slave is a third caller: it holds the pendulum's model through the compiled
 * core (core.pyx's Model: its values, settings, steps and FMU states through these
 * functions), so every FMU of the package refuses and diagnoses with this code.
 *
 * Messages. Every function that can refuse or fail takes (message, size): on MODEL_REFUSED
 * or MODEL_DISCARD it writes there the whole message (NUL-terminated, cut at size bytes),
 * naming the variable, its value and the rule ("l0 = -1.0: a length must be positive"); the
 * FMI layer prefixes its function's name where it wants one. MODEL_NO_VARIABLE writes nothing:
 * "value reference 7 is not a Real variable" is the FMI layer's to say, in its standard's
 * words (FMI 3.0 says Float64). The functions named ..._refusal return NULL when the value
 * may be taken, or the message.
 *
 * Data. A model's instance data is a ModelData: opaque here, model_sizes.data_size bytes of
 * plain data (no pointers, no type aligned more strictly than a double) that the FMI layer
 * allocates, copies as a whole (FMU states) and serializes byte for byte; model_invalid
 * checks such bytes before any of them is taken. Right after them the FMI layer allocates
 * model_sizes.scratch_size bytes more, which the model keeps of its own and no FMU state holds
 * (what it can make again from the data, as the pendulum's Newton matrices, and scratch):
 * every ModelData pointer a function takes is to data_size + scratch_size bytes, which
 * model_reset initializes; copies of the data alone are states. Nothing is allocated by a
 * model.
 *
 * The FMI 3.0 layer (fmi3_glue.c) sits on the same functions: fmi3GetFloat64 and
 * fmi3SetFloat64 are model_get_real and model_check_real / model_set_real, fmi3GetInt32 and
 * fmi3SetInt32 the integer ones, fmi3EnterInitializationMode's tolerance goes through
 * model_tolerance_refusal and model_set_tolerance, fmi3ExitInitializationMode calls
 * model_initialize, fmi3DoStep calls model_do_step_early (early return when the importer
 * allows it; no event handling), fmi3GetDirectionalDerivative calls
 * model_directional_derivative, fmi3GetAdjointDerivative model_adjoint_derivative and
 * fmi3GetOutputDerivatives model_get_output_derivative (FMI 3.0 has no input derivatives).
 * What the two layers do alike on these functions (the FMU states, which copy the ModelData
 * whole, the experiment, the Model Exchange states, ...) is written once, in fmi_layer.c;
 * each layer keeps only its standard's API, types, state table and thin wrappers.
 *
 * A second model, the coupled demo's cart (cart_model.c): its struct ModelData (its held
 * Reals by value reference, F_x_order, the force in effect and the extrapolation's last
 * point) and these functions over it, with its own generated fmu_config.h (builder/models/cart.py:
 * GUID, names, value rules, the same log categories); model_sizes says 2 states. It links
 * with fmi2_glue.c and fmi3_glue.c unchanged: one more model file, not a copy of the glue.
 * What FMI 3.0 says of a model beyond this contract, its arrays and the structural parameter
 * of their dimension, fmi3_glue.c reads from the model's generated fmi3_arrays.h
 * (builder/fmi/fmi3.py): the pendulum's per-link arrays and n_links; the cart has neither.
 *
 * Events: Model Exchange's state events only. model_sizes.n_event_indicator indicators
 * (model_get_event_indicators: the pendulum's elastic ropes' taut margins; the cart has none),
 * which the host watches for sign changes; at an event it handles (NewDiscreteStates,
 * UpdateDiscreteStates) the FMI layer calls model_event_update. No time events, no step events
 * (CompletedIntegratorStep never asks for one), no events in Co-Simulation, whose steps locate
 * the ropes' switches inside the model.
 *
 * Not in the contract: Boolean and String variables (neither model has any; the FMI layer
 * refuses them). */
#ifndef CP_FMU_MODEL_H
#define CP_FMU_MODEL_H

#include <math.h>
#include <stddef.h>
#include <stdio.h>

typedef struct ModelData ModelData;  /* defined by the model only */

typedef enum {
    MODEL_OK = 0,
    MODEL_DISCARD,      /* cannot be computed here (a singular mass matrix, a failed step):
                           message says why; the data is as it was, or at the last step */
    MODEL_REFUSED,      /* a value or request refused: message says why; nothing taken */
    MODEL_WARNING,      /* a value that may be taken but is not honoured in full: message
                           says what is lost (the FMI layer logs it as a warning) */
    MODEL_NO_VARIABLE   /* the value reference is no variable of that type: no message */
} ModelStatus;

/* The model's sizes. Value references: the Reals are 0 to n_real - 1 (the state derivatives
 * after them, from vr_derivative, are Reals too, computed), the Integers n_real to
 * n_real + n_integer - 1. */
typedef struct {
    size_t data_size;        /* sizeof(ModelData) */
    size_t scratch_size;     /* bytes the model keeps after its data, out of FMU states */
    int n_real, n_integer;   /* Real and Integer variables held (the derivatives apart) */
    int n_state;             /* continuous states x, Model Exchange's nx */
    int n_event_indicator;   /* Model Exchange's event indicators (model_get_event_indicators) */
    unsigned vr_state;       /* the value reference of x[0]; x[k] is vr_state + k */
    unsigned vr_derivative;  /* the value reference of der(x[0]); der(x[k]) is vr_derivative + k */
} ModelSizes;

extern const ModelSizes model_sizes;

/* ---- start values, experiment, initialization ---- */

/* Every variable at its start value, the settings at theirs, nothing carried: what
 * instantiation and a reset give. */
void model_reset(ModelData *m);

/* NULL if tolerance may be the experiment's tolerance (FMI 2.0's fmi2SetupExperiment, FMI
 * 3.0's fmi3EnterInitializationMode), or the message refusing it, naming it name (NULL: as the
 * model names its own field, in the check of a restored state). */
const char *model_tolerance_refusal(double tolerance, const char *name, char *message, size_t size);

/* Takes the experiment's tolerance (0: none), which model_initialize applies (the pendulum:
 * to rtol, unless a value of rtol was set). */
void model_set_tolerance(ModelData *m, double tolerance);

/* NULL if the experiment's times may be taken (startTime finite; a stop time, where defined,
 * finite and not before it), or the message refusing them. Not the model's rule but every
 * caller's (both FMI layers and the pythonfmu slave), so written here once. */
static inline const char *experiment_times_refusal(double start_time, int stop_time_defined,
                                                   double stop_time, char *message, size_t size)
{
    if (!isfinite(start_time))
        snprintf(message, size, "startTime = %g: must be finite", start_time);
    else if (stop_time_defined && !(isfinite(stop_time) && stop_time >= start_time))
        snprintf(message, size, "stopTime = %g: must be finite and not before startTime = %g",
                 stop_time, start_time);
    else
        return NULL;
    return message;
}

/* Takes the experiment's stop time (INFINITY: none; else as experiment_times_refusal takes
 * it): a model whose solver steps across communication points takes no step beyond it. */
void model_set_stop_time(ModelData *m, double stop_time);

/* Leaving initialization: the experiment's tolerance applied to the model's settings, what
 * was carried forgotten, the outputs computed at the start. */
void model_initialize(ModelData *m);

/* Model Exchange's event indicators at the current values (n_event_indicator of them): the
 * pendulum's elastic ropes' taut margins, whose sign changes are their slack and snap events. */
void model_get_event_indicators(ModelData *m, double z[]);

/* An event the host handles (Model Exchange's event mode, NewDiscreteStates or
 * UpdateDiscreteStates): the discrete outputs take what the state shows there (the
 * pendulum's elastic ropes: taut, snaps, the tension). */
void model_event_update(ModelData *m);

/* ---- the variable table ---- */

/* The Real variable vr into *value: MODEL_OK; MODEL_DISCARD (message) for a calculated
 * value that cannot be had here (a state derivative where the mass matrix is singular);
 * MODEL_NO_VARIABLE. Outputs are computed when asked, if the state or a parameter changed
 * since. time only names the instant in a message. */
ModelStatus model_get_real(ModelData *m, unsigned vr, double *value, double time, char *message,
                           size_t size);

/* Where an instance is when a value is set: what it may take, and whether the state may jump
 * there. Nonzero: initialized. */
typedef enum {
    MODEL_BEFORE_INIT = 0,     /* instantiated, initialization mode: the start values */
    MODEL_AT_EVENT = 1,        /* a Co-Simulation communication point, Model Exchange's event
                                  mode: inputs and tunable parameters; the state may jump */
    MODEL_CONTINUOUS_TIME = 2  /* Model Exchange's continuous-time mode: continuous inputs only;
                                  the host integrates the state, which cannot jump */
} ModelPhase;

/* Whether value may be set into the Real variable vr in phase (a ModelPhase), without taking
 * it: MODEL_OK, MODEL_REFUSED (message: a calculated variable; a fixed one once initialized,
 * that is after initialization mode; a tunable one in continuous-time mode; or the value
 * breaks the variable's rule), MODEL_WARNING (message: a rope's winch speed changed in
 * continuous-time mode, where its rate, the rope's l'', is not known and taken as 0; said
 * once per instance), MODEL_NO_VARIABLE. An FMI layer checks every value of a call before it
 * sets any. */
ModelStatus model_check_real(const ModelData *m, unsigned vr, double value, int phase,
                             char *message, size_t size);

/* Takes a value model_check_real accepted in phase (what depends on it is computed again). At
 * MODEL_AT_EVENT a value that moves the energy at the state (a rope's winch speed, a load's
 * mass) jumps the book that holds that work, so that energy less the books stays as it was
 * (model_states_jumped then says so). */
void model_set_real(ModelData *m, unsigned vr, double value, int phase);

/* Whether a value set at an event changed the continuous states (a book's jump) since the last
 * call, which forgets it: Model Exchange's valuesOfContinuousStatesChanged. */
int model_states_jumped(ModelData *m);

/* The Integer variable vr into *value: MODEL_OK or MODEL_NO_VARIABLE. */
ModelStatus model_get_integer(const ModelData *m, unsigned vr, int *value);

/* As model_check_real, for an Integer. */
ModelStatus model_check_integer(const ModelData *m, unsigned vr, int value, int initialized,
                                char *message, size_t size);

/* Takes a value model_check_integer accepted. */
void model_set_integer(ModelData *m, unsigned vr, int value);

/* ---- Model Exchange ---- */

/* The n_state continuous states into x. */
void model_get_states(const ModelData *m, double x[]);

/* NULL and x taken (n_state values), or the message refusing it and nothing taken. */
const char *model_set_states(ModelData *m, const double x[], char *message, size_t size);

/* The states' nominal values into x_nominal (n_state values). */
void model_get_nominals(const ModelData *m, double x_nominal[]);

/* x' at the current values into dx (n_state values): MODEL_OK, or MODEL_DISCARD (message).
 * Computed once until the state or a parameter changes. */
ModelStatus model_get_derivatives(ModelData *m, double dx[], double time, char *message,
                                  size_t size);

/* ---- directional derivatives ---- */

/* sensitivity = J seed, J the Jacobian of the unknowns (value references: state derivatives
 * and outputs; a state as unknown is an output of its own value) with respect to the knowns
 * (states, inputs and Real parameters: cp_role), at the current values, in any mode; nothing
 * of m changes. MODEL_OK; MODEL_REFUSED
 * (message) for a value reference that is no unknown or no known, and nothing written;
 * MODEL_DISCARD (message) where the Jacobian cannot be had. The seed is finite (the FMI
 * layer checks it); a sensitivity may come out non-finite, and the FMI layer refuses to hand
 * it out. */
ModelStatus model_directional_derivative(ModelData *m, const unsigned unknowns[], size_t n_unknown,
                                         const unsigned knowns[], size_t n_known,
                                         const double seed[], double sensitivity[], double time,
                                         char *message, size_t size);

/* sensitivity = seed^T J (sensitivity_j = sum_i seed_i dUnknown_i/dKnown_j: n_known values,
 * seed n_unknown values), J as for model_directional_derivative, exact to rounding as it is;
 * nothing of m changes. The same refusals (MODEL_REFUSED, message: a value reference that is
 * no unknown or no known, or a seed that is not finite, and nothing written) and the same
 * MODEL_DISCARD. By complex step: one complex evaluation per known, not one reverse sweep. */
ModelStatus model_adjoint_derivative(ModelData *m, const unsigned unknowns[], size_t n_unknown,
                                     const unsigned knowns[], size_t n_known, const double seed[],
                                     double sensitivity[], double time, char *message,
                                     size_t size);

/* ---- input and output derivatives (Co-Simulation) ----
 * FMI 2.0's canInterpolateInputs with fmi2SetRealInputDerivatives, and maxOutputDerivativeOrder
 * with fmi2GetRealOutputDerivatives (FMI 3.0: fmi3GetOutputDerivatives). The FMI layer checks
 * the order (1 to MODEL_MAX_DERIVATIVE_ORDER) and that a value set is finite, and refuses a
 * derived value that is not; the model says which variables have derivatives. */

#define MODEL_MAX_DERIVATIVE_ORDER 2

/* MODEL_OK if vr is a continuous input whose derivatives may be set to value, MODEL_REFUSED
 * (message) for an input the model holds over each step whose derivative value is not 0,
 * else MODEL_NO_VARIABLE. */
ModelStatus model_check_input_derivative(const ModelData *m, unsigned vr, int order, double value,
                                         char *message, size_t size);

/* Takes the order-th time derivative of the input vr at the current time (order 1 or 2, the
 * value finite, vr accepted by model_check_input_derivative). Over the next step the input
 * follows its Taylor polynomial u + u' tau + u'' tau^2 / 2 (tau from the step's start),
 * evaluated wherever the model needs it; after the step the input's value and derivatives are
 * the polynomial's there, until the master sets others. Reset sets every derivative to 0
 * (held inputs); they are part of the ModelData, so of the FMU states. */
void model_set_input_derivative(ModelData *m, unsigned vr, int order, double value);

/* The order-th time derivative (1 or 2) of the continuous output vr at the current time, with
 * the inputs moving as their derivatives say: MODEL_OK; MODEL_NO_VARIABLE (vr is no continuous
 * output); MODEL_DISCARD (message) where it cannot be had. Exact to rounding. */
ModelStatus model_get_output_derivative(ModelData *m, unsigned vr, int order, double *value,
                                        double time, char *message, size_t size);

/* ---- co-simulation ---- */

/* One communication step from t by dt with the model's own settings and solver memory:
 * MODEL_OK, the states, outputs and statistics at t + dt; or MODEL_DISCARD, message the
 * step's diagnosis (what failed, why, what to do), the states and outputs as they were at t
 * (the statistics count the attempt). */
ModelStatus model_do_step(ModelData *m, double t, double dt, char *message, size_t size);

/* model_do_step, and with early_return_allowed (FMI 3.0's earlyReturnAllowed) a step that
 * cannot complete keeps the state and outputs at the last point the solver reached where x'
 * was computed (RK45 and DOP853: the last accepted internal step; RK4: the last completed
 * substep), or at t if there is none: MODEL_DISCARD with message the diagnosis ("The state
 * is kept at t = <there>"). *last_successful_time (when not NULL) is the time of the state on
 * return: t + dt on MODEL_OK, t on a discard without early return. */
ModelStatus model_do_step_early(ModelData *m, double t, double dt, int early_return_allowed,
                                double *last_successful_time, char *message, size_t size);

/* ---- FMU states ---- */

/* NULL if m can be a model's data, or what is wrong with it, naming the field and its value
 * (every Real keeps its variable's rule as model_check_real applies it, and so on): the check
 * of a restored FMU state, before any of it is taken. */
const char *model_invalid(const ModelData *m, char *message, size_t size);

#endif
