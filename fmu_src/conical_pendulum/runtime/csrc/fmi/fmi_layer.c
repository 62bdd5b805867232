/* What FMI 2.0 and FMI 3.0 share, written once (fmi_layer.h). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmi_layer.h"
#include "fmu_model.h"

#define MESSAGE_SIZE 1024

void fmi_instance_init(FmiInstance *inst, const FmiStandard *standard, int co_simulation,
                       int logging_on, void *(*allocate)(size_t, size_t),
                       void (*release)(void *), ModelData *model)
{
    memset(inst, 0, sizeof *inst);
    inst->standard = standard;
    inst->co_simulation = co_simulation;
    inst->logging = logging_on ? (1u << standard->n_log_categories) - 1 : 0;
    inst->allocate = allocate;
    inst->release = release;
    inst->model = model;
}

const char *fmi_instantiation_problem(const FmiStandard *standard, const char *instance_name,
                                      const char *token)
{
    if (!instance_name || !*instance_name) return "instanceName is empty";
    return token && strcmp(token, standard->token) == 0 ? NULL : standard->token_mismatch;
}

/* ---- messages, and the check of a call --------------------------------------------------- */

static void vlog(FmiInstance *inst, FmiStatus status, int category, const char *format,
                 va_list args)
{
    const int always = status != FMI_OK && status != FMI_DISCARD;
    if (!always && !(inst->logging >> category & 1u)) return;
    char text[4096];
    vsnprintf(text, sizeof text, format, args);
    inst->standard->emit(inst, status, inst->standard->log_categories[category], text);
}

void fmi_log(FmiInstance *inst, FmiStatus status, int category, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    vlog(inst, status, category, format, args);
    va_end(args);
}

FmiStatus fmi_error(FmiInstance *inst, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    vlog(inst, FMI_ERROR, inst->standard->log_error, format, args);
    va_end(args);
    return FMI_ERROR;
}

FmiStatus fmi_discard(FmiInstance *inst, const char *message)
{
    fmi_log(inst, FMI_DISCARD, inst->standard->log_discard, "%s", message);
    return FMI_DISCARD;
}

/* The name of a one-bit state word, "?" for any other word. */
static const char *state_name(const FmiStandard *standard, int state)
{
    for (int k = 0; k < standard->n_states; k++)
        if (state == 1 << k) return standard->state_names[k];
    return "?";
}

FmiInstance *fmi_checked(void *c, const char *function, int co_simulation, int model_exchange)
{
    FmiInstance *inst = c;
    if (!inst) return NULL;
    const FmiStandard *standard = inst->standard;
    const int cs = inst->co_simulation, state = inst->machine.state;
    const int allowed = cs ? co_simulation : model_exchange, other = cs ? model_exchange : co_simulation;
    if (state & allowed) return inst;
    const int failed = standard->step_failed && state == standard->step_failed;
    const char *why = !allowed && other ? (cs ? ": a Model Exchange function" : ": a Co-Simulation function")
                      : !allowed        ? standard->never
                      : failed          ? standard->after_failed
                                        : "";
    /* the diagnosis again, in an error that is always reported: logged at the discard only in
     * debug mode, it would otherwise never reach a host that did not ask for it */
    const int diagnosis = failed && inst->discarded[0];
    fmi_error(inst, "%s is not allowed in %s%s (%s, %s)%s%s%s", function, standard->in_state,
              state_name(standard, state), standard->name,
              cs ? standard->co_simulation_where : standard->model_exchange_where, why,
              diagnosis ? ". The step was discarded: " : "", diagnosis ? inst->discarded : "");
    return NULL;
}

int fmi_initialized(const FmiInstance *inst)
{
    return !(inst->machine.state & (inst->standard->instantiated | inst->standard->initialization));
}

int fmi_phase(const FmiInstance *inst)
{
    if (!fmi_initialized(inst)) return MODEL_BEFORE_INIT;
    return inst->machine.state & inst->standard->continuous_time ? MODEL_CONTINUOUS_TIME
                                                                 : MODEL_AT_EVENT;
}

/* ---- the functions both standards have ----------------------------------------------------- */

FmiStatus fmi_set_debug_logging(FmiInstance *inst, const char *function, int on, size_t n,
                                const char *const categories[])
{
    if (!inst) return FMI_ERROR;
    const char *const *names = inst->standard->log_categories;
    const int n_names = inst->standard->n_log_categories;
    if (n && !categories) return fmi_error(inst, "%s: categories is NULL", function);
    unsigned listed = 0;
    for (size_t k = 0; k < n; k++) {
        int found = -1;
        for (int j = 0; j < n_names && categories[k]; j++)
            if (strcmp(categories[k], names[j]) == 0) found = j;
        if (found < 0) {
            char declared[512] = "";
            for (int j = 0, used = 0; j < n_names && used < (int)sizeof declared; j++)
                used += snprintf(declared + used, sizeof declared - used, "%s%s", j ? ", " : "",
                                 names[j]);
            return fmi_error(inst, "%s: log category \"%s\" is not this FMU's (its model "
                             "description declares %s)", function,
                             categories[k] ? categories[k] : "(null)", declared);
        }
        listed |= 1u << found;
    }
    const unsigned all = (1u << n_names) - 1;
    if (!n) inst->logging = on ? all : 0;
    else inst->logging = on ? listed : inst->logging & ~listed;
    return FMI_OK;
}

FmiStatus fmi_reset(FmiInstance *inst)
{
    if (!inst) return FMI_ERROR;
    memset(&inst->machine, 0, sizeof inst->machine);  /* padding too: it is serialized */
    inst->machine.state = inst->standard->instantiated;
    inst->discarded[0] = '\0';
    model_reset(inst->model);
    return FMI_OK;
}

FmiStatus fmi_setup_experiment(FmiInstance *inst, int tolerance_defined, double tolerance,
                               double start_time, int stop_time_defined, double stop_time)
{
    if (!inst) return FMI_ERROR;
    const FmiStandard *standard = inst->standard;
    char message[MESSAGE_SIZE];
    if (tolerance_defined
        && model_tolerance_refusal(tolerance, standard->tolerance, message, sizeof message))
        return fmi_error(inst, "%s%s", standard->experiment, message);
    if (experiment_times_refusal(start_time, stop_time_defined, stop_time, message, sizeof message))
        return fmi_error(inst, "%s%s", standard->experiment, message);
    model_set_tolerance(inst->model, tolerance_defined ? tolerance : 0.0);
    model_set_stop_time(inst->model, stop_time_defined ? stop_time : INFINITY);
    inst->machine.time = inst->machine.last_successful_time = start_time;
    return FMI_OK;
}

FmiStatus fmi_enter(FmiInstance *inst, int state)
{
    if (!inst) return FMI_ERROR;
    inst->machine.state = state;
    return FMI_OK;
}

FmiStatus fmi_exit_initialization(FmiInstance *inst)
{
    if (!inst) return FMI_ERROR;
    model_initialize(inst->model);
    inst->machine.state = inst->co_simulation ? inst->standard->stepping : inst->standard->event_mode;
    return FMI_OK;
}

FmiStatus fmi_communication_point(FmiInstance *inst, const char *function, double t)
{
    if (!inst) return FMI_ERROR;
    if (fabs(t - inst->machine.time) <= 1e-9 * fmax(1.0, fabs(t))) return FMI_OK;
    return fmi_error(inst, "%s: currentCommunicationPoint = %.17g s, but the FMU is at t = %.17g s",
                     function, t, inst->machine.time);
}

/* What the model's answer for the Real vr makes of the call (message: the model's, if any). */
static FmiStatus got_real(FmiInstance *inst, const char *function, const char *type,
                          ModelStatus status, unsigned named, const char *message)
{
    switch (status) {
    case MODEL_OK: return FMI_OK;
    case MODEL_DISCARD: return fmi_discard(inst, message);
    case MODEL_REFUSED: return fmi_error(inst, "%s: %s", function, message);
    default:
        return fmi_error(inst, "%s: value reference %u is not a %s variable", function, named, type);
    }
}

FmiStatus fmi_get_real(FmiInstance *inst, const char *function, const char *type, unsigned vr,
                       unsigned named, double *value)
{
    char message[MESSAGE_SIZE];
    const ModelStatus status = model_get_real(inst->model, vr, value, inst->machine.time, message,
                                              sizeof message);
    return got_real(inst, function, type, status, named, message);
}

FmiStatus fmi_get_reals(FmiInstance *inst, const char *function, const char *type,
                        const unsigned vr[], size_t nvr, double values[])
{
    char message[MESSAGE_SIZE];
    for (size_t k = 0; k < nvr; k++) {
        const ModelStatus status = model_get_real(inst->model, vr[k], &values[k],
                                                  inst->machine.time, message, sizeof message);
        if (status != MODEL_OK) return got_real(inst, function, type, status, vr[k], message);
    }
    return FMI_OK;
}

FmiStatus fmi_check_real(FmiInstance *inst, const char *function, const char *type, unsigned vr,
                         unsigned named, double value)
{
    char message[MESSAGE_SIZE];
    switch (model_check_real(inst->model, vr, value, fmi_phase(inst), message, sizeof message)) {
    case MODEL_OK: return FMI_OK;
    case MODEL_WARNING:
        fmi_log(inst, FMI_WARNING, inst->standard->log_warning, "%s: %s", function, message);
        return FMI_WARNING;
    case MODEL_NO_VARIABLE:
        return fmi_error(inst, "%s: value reference %u is not a %s variable", function, named, type);
    default: return fmi_error(inst, "%s", message);
    }
}

FmiStatus fmi_get_integers(FmiInstance *inst, const char *function, const char *type,
                           const unsigned vr[], size_t nvr, int values[])
{
    if (!inst) return FMI_ERROR;
    if (nvr && (!vr || !values))
        return fmi_error(inst, "%s: %s", function, inst->standard->arguments_null);
    for (size_t k = 0; k < nvr; k++)
        if (model_get_integer(inst->model, vr[k], &values[k]) != MODEL_OK)
            return fmi_error(inst, "%s: value reference %u is not an %s variable", function,
                             vr[k], type);
    return FMI_OK;
}

FmiStatus fmi_set_integers(FmiInstance *inst, const char *function, const char *type,
                           const unsigned vr[], size_t nvr, const int values[])
{
    if (!inst) return FMI_ERROR;
    if (nvr && (!vr || !values))
        return fmi_error(inst, "%s: %s", function, inst->standard->arguments_null);
    char message[MESSAGE_SIZE];
    for (size_t k = 0; k < nvr; k++) {  /* all checked before any is taken */
        ModelStatus status = model_check_integer(inst->model, vr[k], values[k],
                                                 fmi_initialized(inst), message, sizeof message);
        if (status == MODEL_NO_VARIABLE)
            return fmi_error(inst, "%s: value reference %u is not an %s variable", function,
                             vr[k], type);
        if (status != MODEL_OK) return fmi_error(inst, "%s", message);
    }
    for (size_t k = 0; k < nvr; k++) model_set_integer(inst->model, vr[k], values[k]);
    return FMI_OK;
}

FmiStatus fmi_no_variables(FmiInstance *inst, const char *function, const char *type,
                           const unsigned vr[], size_t nvr)
{
    if (!inst) return FMI_ERROR;
    return nvr ? fmi_error(inst, "%s: value reference %u: this FMU has no %s variables", function,
                           vr ? vr[0] : 0, type) : FMI_OK;
}

FmiStatus fmi_derivative(FmiInstance *inst, const char *function, const char *seed_name, int adjoint,
                         const unsigned unknown[], size_t n_unknown, const unsigned known[],
                         size_t n_known, const double seed[], double sensitivity[])
{
    const unsigned *seeded = adjoint ? unknown : known, *sensed = adjoint ? known : unknown;
    const size_t n_seeded = adjoint ? n_unknown : n_known, n_sensed = adjoint ? n_known : n_unknown;
    const char *(*name)(unsigned) = inst->standard->variable_name;
    for (size_t k = 0; k < n_seeded; k++)
        if (!isfinite(seed[k]))
            return fmi_error(inst, "%s: %s of %s = %g: must be finite", function, seed_name,
                             name(seeded[k]), seed[k]);
    char message[MESSAGE_SIZE];
    switch ((adjoint ? model_adjoint_derivative : model_directional_derivative)(
        inst->model, unknown, n_unknown, known, n_known, seed, sensitivity, inst->machine.time,
        message, sizeof message)) {
    case MODEL_OK: break;
    case MODEL_DISCARD: return fmi_discard(inst, message);
    default: return fmi_error(inst, "%s: %s", function, message);
    }
    for (size_t k = 0; k < n_sensed; k++)
        if (!isfinite(sensitivity[k])) {
            fmi_log(inst, FMI_DISCARD, inst->standard->log_discard, "%s: the derivative %s%s is "
                    "not finite at t = %.9g s; check parameters and state", function,
                    adjoint ? "with respect to " : "of ", name(sensed[k]), inst->machine.time);
            return FMI_DISCARD;
        }
    return FMI_OK;
}

/* ---- input and output derivatives ------------------------------------------------------------ */

/* NULL if order is one the model gives or takes, or the message (without the function). */
static const char *order_refusal(int order, const char *what, const char *name, char *message,
                                 size_t size)
{
    if (order >= 1 && order <= MODEL_MAX_DERIVATIVE_ORDER) return NULL;
    snprintf(message, size, "order %d of %s %s: must be 1 to %d (maxOutputDerivativeOrder)",
             order, what, name, MODEL_MAX_DERIVATIVE_ORDER);
    return message;
}

FmiStatus fmi_check_input_derivative(FmiInstance *inst, const char *function, unsigned vr,
                                     unsigned named, int order, double value)
{
    const char *name = inst->standard->variable_name(vr);
    char message[MESSAGE_SIZE];
    switch (model_check_input_derivative(inst->model, vr, order, value, message, sizeof message)) {
    case MODEL_OK: break;
    case MODEL_REFUSED: return fmi_error(inst, "%s: %s", function, message);
    default:
        return fmi_error(inst, "%s: value reference %u (%s) is not a continuous input: only "
                         "inputs take derivatives", function, named, name);
    }
    if (order_refusal(order, "the derivative of", name, message, sizeof message))
        return fmi_error(inst, "%s: %s", function, message);
    if (!isfinite(value))
        return fmi_error(inst, "%s: derivative %d of %s = %g: must be finite", function, order,
                         name, value);
    return FMI_OK;
}

FmiStatus fmi_get_output_derivative(FmiInstance *inst, const char *function, unsigned vr,
                                    unsigned named, int order, double *value)
{
    const char *name = inst->standard->variable_name(vr);
    char message[MESSAGE_SIZE];
    if (order_refusal(order, "the derivative of", name, message, sizeof message))
        return fmi_error(inst, "%s: %s", function, message);
    switch (model_get_output_derivative(inst->model, vr, order, value, inst->machine.time,
                                        message, sizeof message)) {
    case MODEL_OK: break;
    case MODEL_DISCARD: return fmi_discard(inst, message);
    default:
        return fmi_error(inst, "%s: value reference %u (%s) is not a continuous output: only "
                         "they have derivatives", function, named, name);
    }
    if (isfinite(*value)) return FMI_OK;
    fmi_log(inst, FMI_DISCARD, inst->standard->log_discard, "%s: derivative %d of %s is not "
            "finite at t = %.9g s; check parameters and state", function, order, name,
            inst->machine.time);
    return FMI_DISCARD;
}

/* ---- Model Exchange ------------------------------------------------------------------------ */

FmiStatus fmi_set_time(FmiInstance *inst, const char *function, double time)
{
    if (!inst) return FMI_ERROR;
    if (!isfinite(time)) return fmi_error(inst, "%s: time = %g must be finite", function, time);
    inst->machine.time = time;  /* the contract's models are autonomous: x' does not depend on time */
    return FMI_OK;
}

FmiStatus fmi_completed_integrator_step(FmiInstance *inst, const char *function,
                                        const void *enter_event_mode,
                                        const void *terminate_simulation)
{
    if (!inst) return FMI_ERROR;
    if (!enter_event_mode || !terminate_simulation)
        return fmi_error(inst, "%s: a pointer is NULL", function);
    inst->machine.last_successful_time = inst->machine.time;
    return FMI_OK;
}

/* Whether an array of the continuous states (x, x', their nominals) is one. */
static FmiStatus states_call(FmiInstance *inst, const char *function, const void *x, size_t nx)
{
    if (!inst) return FMI_ERROR;
    if (!x) return fmi_error(inst, "%s: the array is NULL", function);
    if (nx != (size_t)model_sizes.n_state)
        return fmi_error(inst, "%s: %s = %zu, but this FMU has %d continuous states", function,
                         inst->standard->n_states_argument, nx, model_sizes.n_state);
    return FMI_OK;
}

FmiStatus fmi_set_continuous_states(FmiInstance *inst, const char *function, const double x[],
                                    size_t nx)
{
    if (states_call(inst, function, x, nx)) return FMI_ERROR;
    char message[MESSAGE_SIZE];
    if (model_set_states(inst->model, x, message, sizeof message))
        return fmi_error(inst, "%s: %s", function, message);
    return FMI_OK;
}

FmiStatus fmi_get_continuous_states(FmiInstance *inst, const char *function, double x[], size_t nx)
{
    if (states_call(inst, function, x, nx)) return FMI_ERROR;
    model_get_states(inst->model, x);
    return FMI_OK;
}

FmiStatus fmi_get_derivatives(FmiInstance *inst, const char *function, double dx[], size_t nx)
{
    if (states_call(inst, function, dx, nx)) return FMI_ERROR;
    char message[MESSAGE_SIZE];
    if (model_get_derivatives(inst->model, dx, inst->machine.time, message, sizeof message)
        != MODEL_OK)
        return fmi_discard(inst, message);
    return FMI_OK;
}

FmiStatus fmi_get_nominals(FmiInstance *inst, const char *function, double x_nominal[], size_t nx)
{
    if (states_call(inst, function, x_nominal, nx)) return FMI_ERROR;
    model_get_nominals(inst->model, x_nominal);
    return FMI_OK;
}

FmiStatus fmi_get_event_indicators(FmiInstance *inst, const char *function, double z[], size_t ni)
{
    if (!inst) return FMI_ERROR;
    if (ni != (size_t)model_sizes.n_event_indicator)
        return fmi_error(inst, "%s: %s = %zu, but the number of event indicators is %d",
                         function, inst->standard->n_indicators_argument, ni,
                         model_sizes.n_event_indicator);
    if (!ni) return FMI_OK;  /* z may be NULL: nothing to fill */
    if (!z) return fmi_error(inst, "%s: eventIndicators is NULL", function);
    model_get_event_indicators(inst->model, z);
    return FMI_OK;
}

int fmi_event_update(FmiInstance *inst)
{
    model_event_update(inst->model);
    return model_states_jumped(inst->model);
}

/* ---- FMU states ----------------------------------------------------------------------------- */

typedef struct {
    FmiMachine machine;
    double model[];  /* a ModelData; double: its alignment (fmu_model.h) */
} Saved;

#define SAVED_SIZE (sizeof(Saved) + model_sizes.data_size)

/* The serialized header's size: magic, size, the token with its '\0', to an unsigned's
 * alignment. */
static size_t header_size(const char *token)
{
    const size_t size = 2 * sizeof(unsigned) + strlen(token) + 1;
    return (size + sizeof(unsigned) - 1) / sizeof(unsigned) * sizeof(unsigned);
}

#define HEADER_SIZE(inst) header_size((inst)->standard->token)

static void header_write(unsigned char *out, unsigned magic, unsigned size, const char *token)
{
    memset(out, 0, header_size(token));
    memcpy(out, &magic, sizeof magic);
    memcpy(out + sizeof magic, &size, sizeof size);
    memcpy(out + 2 * sizeof(unsigned), token, strlen(token) + 1);
}

static int header_matches(const unsigned char *in, unsigned magic, unsigned size, const char *token)
{
    unsigned read_magic, read_size;
    memcpy(&read_magic, in, sizeof read_magic);
    memcpy(&read_size, in + sizeof read_magic, sizeof read_size);
    return read_magic == magic && read_size == size
           && memcmp(in + 2 * sizeof(unsigned), token, strlen(token) + 1) == 0;
}

/* NULL if s can be the state of inst, or what is wrong with it, naming the field and its
 * value: its machine state is one state of the interface's state machine, the model's data
 * passes model_invalid, and the times are finite. */
static const char *invalid_state(const FmiInstance *inst, const Saved *s, char *message,
                                 size_t size)
{
    const unsigned states = (unsigned)(inst->co_simulation ? inst->standard->co_simulation_states
                                                           : inst->standard->model_exchange_states);
    const unsigned bits = (unsigned)s->machine.state;
    if (!(bits & states) || (bits & (bits - 1))) {  /* none of them, or more than one bit */
        snprintf(message, size, "instance state = %d: not one state a%s instance can be in",
                 s->machine.state, inst->co_simulation ? " Co-Simulation" : " Model Exchange");
        return message;
    }
    if (model_invalid((const ModelData *)s->model, message, size)) return message;
    const struct { const char *name; double value; } times[] = {
        {"time", s->machine.time}, {"last_successful_time", s->machine.last_successful_time}};
    for (size_t k = 0; k < sizeof times / sizeof times[0]; k++)
        if (!isfinite(times[k].value)) {  /* %g writes nan, inf, -inf as Python's repr does */
            snprintf(message, size, "%s = %g: must be finite", times[k].name, times[k].value);
            return message;
        }
    return NULL;
}

FmiStatus fmi_get_fmu_state(FmiInstance *inst, const char *function, void **state)
{
    if (!inst) return FMI_ERROR;
    if (!state) return fmi_error(inst, "%s: %s is NULL", function, inst->standard->fmu_state);
    Saved *copy = *state ? *state : inst->allocate(1, SAVED_SIZE);
    if (!copy) return fmi_error(inst, "%s: out of memory", function);
    copy->machine = inst->machine;
    memcpy(copy->model, inst->model, model_sizes.data_size);
    *state = copy;
    return FMI_OK;
}

FmiStatus fmi_set_fmu_state(FmiInstance *inst, const char *function, const void *state)
{
    if (!inst) return FMI_ERROR;
    if (!state) return fmi_error(inst, "%s: %s is NULL", function, inst->standard->fmu_state);
    const Saved *saved = state;
    char message[MESSAGE_SIZE];
    if (invalid_state(inst, saved, message, sizeof message))
        return fmi_error(inst, "%s: the state's %s", function, message);
    inst->machine = saved->machine;
    memcpy(inst->model, saved->model, model_sizes.data_size);
    inst->discarded[0] = '\0';
    return FMI_OK;
}

FmiStatus fmi_free_fmu_state(FmiInstance *inst, const char *function, void **state)
{
    if (!inst) return FMI_ERROR;
    if (!state) return fmi_error(inst, "%s: %s is NULL", function, inst->standard->fmu_state);
    if (*state) inst->release(*state);
    *state = NULL;
    return FMI_OK;
}

FmiStatus fmi_serialized_size(FmiInstance *inst, const char *function, const void *state,
                              size_t *size)
{
    if (!inst) return FMI_ERROR;
    if (!state || !size) return fmi_error(inst, "%s: a pointer is NULL", function);
    *size = HEADER_SIZE(inst) + SAVED_SIZE;
    return FMI_OK;
}

FmiStatus fmi_serialize(FmiInstance *inst, const char *function, const void *state,
                        unsigned char bytes[], size_t size)
{
    if (!inst) return FMI_ERROR;
    if (!state || !bytes) return fmi_error(inst, "%s: a pointer is NULL", function);
    if (size < HEADER_SIZE(inst) + SAVED_SIZE)
        return fmi_error(inst, "%s: %zu bytes are too few; %s says how many", function, size,
                         inst->standard->serialized_size);
    header_write(bytes, inst->standard->state_magic, (unsigned)SAVED_SIZE, inst->standard->token);
    memcpy(bytes + HEADER_SIZE(inst), state, SAVED_SIZE);
    return FMI_OK;
}

FmiStatus fmi_deserialize(FmiInstance *inst, const char *function, const unsigned char bytes[],
                          size_t size, void **state)
{
    if (!inst) return FMI_ERROR;
    if (!bytes || !state) return fmi_error(inst, "%s: a pointer is NULL", function);
    if (size != HEADER_SIZE(inst) + SAVED_SIZE)
        return fmi_error(inst, "%s: %zu bytes are not a state of this FMU", function, size);
    if (!header_matches(bytes, inst->standard->state_magic, (unsigned)SAVED_SIZE,
                        inst->standard->token))
        return fmi_error(inst, "%s: the bytes are not a state of this FMU (another model, build "
                         "or version)", function);
    /* Checked in a copy of its own (the bytes need not be aligned), taken only if it passes. */
    Saved *copy = inst->allocate(1, SAVED_SIZE);
    if (!copy) return fmi_error(inst, "%s: out of memory", function);
    memcpy(copy, bytes + HEADER_SIZE(inst), SAVED_SIZE);
    char message[MESSAGE_SIZE];
    if (invalid_state(inst, copy, message, sizeof message)) {
        inst->release(copy);
        return fmi_error(inst, "%s: the state's %s", function, message);
    }
    if (*state) {  /* the caller's state, reused */
        memcpy(*state, copy, SAVED_SIZE);
        inst->release(copy);
    } else {
        *state = copy;
    }
    return FMI_OK;
}
