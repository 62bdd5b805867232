/* FMI 2.0 glue of the native FMU: Co-Simulation (the core's solvers) and Model Exchange.
 *
 * Generic: it knows the model only through model.h (sizes), dynamics.h (x' and the
 * outputs), solvers.h and fmu_config.h (generated at build time: value references,
 * start values, names and the value rules of runtime/rules.py). Every entry point checks
 * its instance, its state and its value references; a refused value is fmi2Error with a
 * message naming it and is not taken; a step that cannot complete is fmi2Discard with the
 * diagnosis every FMU of this package gives; messages go through the host's logger.
 * Nothing is allocated after instantiation but what a host asks for (FMU states).
 * Directional derivatives come from directional.c: the model's C again, complex-step.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#include "cosim.h"
#include "diagnosis.h"
#include "directional.h"
#include "dynamics.h"
#include "fmu_config.h"
#include "solvers.h"

/* ---- FMI 2.0's state machine ------------------------------------------------------------- */

/* Where an instance is: one bit per state. The standard's other states are never entered:
 * start/end has no instance; stepInProgress and stepCanceled need an asynchronous fmi2DoStep
 * (it never returns fmi2Pending); error and fatal: a refused call takes nothing and leaves the
 * instance in its state, and fmi2Fatal is never returned. */
enum {
    INSTANTIATED = 1 << 0, INITIALIZATION = 1 << 1, STEP_COMPLETE = 1 << 2,
    STEP_FAILED = 1 << 3, EVENT_MODE = 1 << 4, CONTINUOUS_TIME = 1 << 5, TERMINATED = 1 << 6
};
static const char *const state_names[] = {  /* by bit, as the standard's tables name them */
    "instantiated", "initializationMode", "stepComplete", "stepFailed", "eventMode",
    "continuousTimeMode", "terminated"};
#define BEFORE_INIT (INSTANTIATED | INITIALIZATION)
/* The states an instance of each type can be in. */
#define CO_SIMULATION_STATES (BEFORE_INIT | STEP_COMPLETE | STEP_FAILED | TERMINATED)
#define MODEL_EXCHANGE_STATES (BEFORE_INIT | EVENT_MODE | CONTINUOUS_TIME | TERMINATED)
/* Where values are defined: initialization mode and after (the getters' rows). */
#define CS_VALUES (INITIALIZATION | STEP_COMPLETE | STEP_FAILED | TERMINATED)
#define ME_VALUES (INITIALIZATION | EVENT_MODE | CONTINUOUS_TIME | TERMINATED)
#define NO_STATE 0

/* The states each function may be called in, Co-Simulation and Model Exchange: FMI 2.0's
 * tables (sections 4.2.4 and 3.2.3, as the 2.0.x releases print them), one row per function;
 * the instance's type picks the column. Where the standard allows a call in a state only for
 * some variables (its numbered conditions: fmi2SetReal of inputs and tunable parameters
 * after initialization, ...), the state is in and the function checks the variable
 * (not_settable). fmi2GetTypesPlatform and fmi2GetVersion take no instance. fmi2FreeInstance,
 * fmi2Reset and fmi2FreeFMUstate are allowed in every state and never refused, whatever the
 * instance holds, so an instance can always be reset and freed: they do not consult it. */
/*                                               Co-Simulation                 Model Exchange */
#define STATES_fmi2SetDebugLogging               CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi2FreeInstance                  CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi2SetupExperiment               INSTANTIATED,                 INSTANTIATED
#define STATES_fmi2EnterInitializationMode       INSTANTIATED,                 INSTANTIATED
#define STATES_fmi2ExitInitializationMode        INITIALIZATION,               INITIALIZATION
#define STATES_fmi2Terminate                     (STEP_COMPLETE | STEP_FAILED), (EVENT_MODE | CONTINUOUS_TIME)
#define STATES_fmi2Reset                         CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi2GetReal                       CS_VALUES,                    ME_VALUES
#define STATES_fmi2GetInteger                    CS_VALUES,                    ME_VALUES
#define STATES_fmi2GetBoolean                    CS_VALUES,                    ME_VALUES
#define STATES_fmi2GetString                     CS_VALUES,                    ME_VALUES
#define STATES_fmi2SetReal                       (BEFORE_INIT | STEP_COMPLETE), (BEFORE_INIT | EVENT_MODE | CONTINUOUS_TIME)
#define STATES_fmi2SetInteger                    (BEFORE_INIT | STEP_COMPLETE), (BEFORE_INIT | EVENT_MODE)
#define STATES_fmi2SetBoolean                    (BEFORE_INIT | STEP_COMPLETE), (BEFORE_INIT | EVENT_MODE)
#define STATES_fmi2SetString                     (BEFORE_INIT | STEP_COMPLETE), (BEFORE_INIT | EVENT_MODE)
#define STATES_fmi2GetFMUstate                   CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi2SetFMUstate                   CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi2FreeFMUstate                  CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi2SerializedFMUstateSize        CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi2SerializeFMUstate             CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi2DeSerializeFMUstate           CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi2GetDirectionalDerivative      CS_VALUES,                    ME_VALUES
/* Model Exchange only */
#define STATES_fmi2EnterEventMode                NO_STATE,                     (EVENT_MODE | CONTINUOUS_TIME)
#define STATES_fmi2NewDiscreteStates             NO_STATE,                     EVENT_MODE
#define STATES_fmi2EnterContinuousTimeMode       NO_STATE,                     EVENT_MODE
#define STATES_fmi2CompletedIntegratorStep       NO_STATE,                     CONTINUOUS_TIME
#define STATES_fmi2SetTime                       NO_STATE,                     CONTINUOUS_TIME  /* eventMode: a pure discrete-time FMU's only */
#define STATES_fmi2SetContinuousStates           NO_STATE,                     CONTINUOUS_TIME
#define STATES_fmi2GetEventIndicators            NO_STATE,                     ME_VALUES
#define STATES_fmi2GetContinuousStates           NO_STATE,                     ME_VALUES
#define STATES_fmi2GetDerivatives                NO_STATE,                     ME_VALUES
#define STATES_fmi2GetNominalsOfContinuousStates NO_STATE,                     MODEL_EXCHANGE_STATES
/* Co-Simulation only */
#define STATES_fmi2SetRealInputDerivatives       (BEFORE_INIT | STEP_COMPLETE), NO_STATE
#define STATES_fmi2GetRealOutputDerivatives      (STEP_COMPLETE | STEP_FAILED | TERMINATED), NO_STATE
#define STATES_fmi2DoStep                        STEP_COMPLETE,                NO_STATE
#define STATES_fmi2CancelStep                    NO_STATE,                     NO_STATE  /* stepInProgress only */
#define STATES_fmi2GetStatus                     (STEP_COMPLETE | STEP_FAILED | TERMINATED), NO_STATE
#define STATES_fmi2GetRealStatus                 (STEP_COMPLETE | STEP_FAILED | TERMINATED), NO_STATE
#define STATES_fmi2GetIntegerStatus              (STEP_COMPLETE | STEP_FAILED | TERMINATED), NO_STATE
#define STATES_fmi2GetBooleanStatus              (STEP_COMPLETE | STEP_FAILED | TERMINATED), NO_STATE
#define STATES_fmi2GetStringStatus               (STEP_COMPLETE | STEP_FAILED | TERMINATED), NO_STATE

/* Everything fmi2GetFMUstate saves: plain data, copied as a whole. */
typedef struct {
    int state;
    double time;
    double r[CP_NREAL];           /* Real variables by value reference (fmu_config.h) */
    fmi2Integer solver, max_steps;
    double tolerance;             /* from fmi2SetupExperiment; replaces rtol when > 0 */
    double h;                     /* the solvers' proposed step, carried between steps */
    int fsal;                     /* work holds x' at x */
    double work[CP_STEP_WORK_SIZE];
    double dx[CP_NSTATE];         /* Model Exchange: x' at (time, x) when dx_valid */
    int dx_valid, outputs_valid;
    double last_successful_time;
} Values;

typedef struct {
    Values v;
    fmi2CallbackFunctions cb;
    fmi2Type type;
    unsigned logging;             /* bit k: log category cp_log_categories[k] is on */
    char name[128];
    char discarded[2048];         /* the last discarded step's diagnosis, while in stepFailed */
} Instance;

#define ALL_CATEGORIES ((1u << CP_NLOG) - 1)

#define X(inst) ((inst)->v.r + CP_VR_STATE)
#define Y(inst) ((inst)->v.r + CP_VR_OUTPUT)
#define STATS(inst) ((inst)->v.r + CP_VR_STATISTICS)

/* A message through the host's logger, in one of the model description's log categories
 * (CP_LOG_*, fmu_config.h). FMI 2.0, section 2.1.3: after fmi2Warning, fmi2Error and fmi2Fatal
 * "function logger was called", so those are always reported; other messages (fmi2Discard's
 * diagnoses) only in debug mode, that is when their category is on (section 2.1.5: loggingOn
 * of fmi2Instantiate, then fmi2SetDebugLogging). */
static void log_message(Instance *inst, fmi2Status status, int category, const char *format, ...)
{
    if (!inst->cb.logger) return;
    if ((status == fmi2OK || status == fmi2Discard) && !(inst->logging >> category & 1u)) return;
    char text[4096];
    va_list args;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    inst->cb.logger(inst->cb.componentEnvironment, inst->name, status, cp_log_categories[category],
                    text);
}

#define REFUSE(inst, ...) (log_message((inst), fmi2Error, CP_LOG_STATUS_ERROR, __VA_ARGS__), fmi2Error)

/* The instance behind c if FMI 2.0 allows the function in its state (the table above, in the
 * column of the instance's type); logs that it does not otherwise, naming the state. */
#define CHECKED(c, function) checked((c), #function, STATES_##function)

static Instance *checked(fmi2Component c, const char *function, int co_simulation,
                         int model_exchange)
{
    Instance *inst = (Instance *)c;
    if (!inst) return NULL;
    const int cs = inst->type == fmi2CoSimulation;
    const int allowed = cs ? co_simulation : model_exchange;
    if (inst->v.state & allowed) return inst;
    const char *state = "?";
    for (int k = 0; k < (int)(sizeof state_names / sizeof state_names[0]); k++)
        if (inst->v.state == 1 << k) state = state_names[k];
    const char *why = "";
    if (!allowed && (cs ? model_exchange : co_simulation))
        why = cs ? ": a Model Exchange function" : ": a Co-Simulation function";
    else if (!allowed)
        why = ": only while a step is in progress, and fmi2DoStep never runs asynchronously here";
    else if (inst->v.state == STEP_FAILED)
        why = "; after a discarded step fmi2SetFMUstate or fmi2Reset go back, fmi2Terminate ends";
    /* the diagnosis again, in an error that is always reported: logged at the discard only in
     * debug mode, it would otherwise never reach a host that did not ask for it */
    const int failed = inst->v.state == STEP_FAILED && inst->discarded[0];
    log_message(inst, fmi2Error, CP_LOG_STATUS_ERROR, "%s is not allowed in state %s (FMI 2.0, %s)%s%s%s",
                function, state, cs ? "Co-Simulation, section 4.2.4" : "Model Exchange, section 3.2.3",
                why, failed ? ". The step was discarded: " : "", failed ? inst->discarded : "");
    return NULL;
}

/* A double as Python's repr writes it, so that messages read as the pythonfmu FMU's do. */
static void python_repr(char *buf, size_t size, double value)
{
    if (isnan(value)) { snprintf(buf, size, "nan"); return; }
    if (isinf(value)) { snprintf(buf, size, value > 0 ? "inf" : "-inf"); return; }
    int digits = 1;
    for (; digits < 17; digits++) {
        snprintf(buf, size, "%.*e", digits - 1, value);
        if (strtod(buf, NULL) == value) break;
    }
    snprintf(buf, size, "%.*e", digits - 1, value);  /* e.g. 1.5e-05, as Python writes it */
    int exponent = atoi(strchr(buf, 'e') + 1);
    if (exponent >= -4 && exponent < 16) {  /* Python writes these positionally */
        int decimals = digits - 1 - exponent;
        snprintf(buf, size, "%.*f", decimals < 1 ? 1 : decimals, value);
    }
}

/* NULL if value keeps the rule, or the message refusing it (shown: the value as written). */
static const char *refusal(const char *name, const char *shown, double value, const cp_rule *rule,
                           const char *what, char *message, size_t size)
{
    if (!isfinite(value)) {
        snprintf(message, size, "%s = %s: must be finite", name, shown);
        return message;
    }
    int holds = (rule->low_open ? value > rule->low : value >= rule->low) && value < rule->high
                && (!rule->whole || value == floor(value));
    if (holds) return NULL;
    snprintf(message, size, "%s = %s: %s%s%s", name, shown, what, *what ? " " : "", rule->refusal);
    return message;
}

static const char *real_refusal(const char *name, double value, const cp_rule *rule,
                                const char *what, char *message, size_t size)
{
    char shown[40];
    python_repr(shown, sizeof shown, value);
    return refusal(name, shown, value, rule, what, message, size);
}

/* NULL if an Integer setting (solver or max_steps) may take value, or the message refusing it. */
static const char *integer_refusal(fmi2ValueReference vr, fmi2Integer value, char *message,
                                   size_t size)
{
    const cp_rule *rule = &cp_rules[vr == CP_VR_SOLVER ? CP_SOLVER_RULE : CP_MAX_STEPS_RULE];
    char shown[16];
    snprintf(shown, sizeof shown, "%d", (int)value);  /* a count reads as one: 7, not 7.0 */
    return refusal(cp_variable_name(vr), shown, value, rule, "", message, size);
}

static void invalidate(Instance *inst)
{
    inst->v.fsal = 0;
    inst->v.dx_valid = 0;
    inst->v.outputs_valid = 0;
}

static void update_outputs(Instance *inst)
{
    if (!inst->v.outputs_valid && CP_NOUTPUT) cp_eval_outputs(X(inst), inst->v.r, Y(inst));
    inst->v.outputs_valid = 1;
}

static void reset_values(Instance *inst)
{
    memset(&inst->v, 0, sizeof inst->v);
    memcpy(inst->v.r, cp_real_start, sizeof cp_real_start);
    inst->v.solver = CP_SOLVER_START;
    inst->v.max_steps = CP_MAX_STEPS_START;
    inst->v.state = INSTANTIATED;
    inst->discarded[0] = '\0';
}

/* ---- common functions ------------------------------------------------------------------ */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    /* FMI 2.0, section 2.1.5: with nCategories = 0, loggingOn applies to every category; with
     * a list, loggingOn makes the listed ones the categories in force, and logging off turns
     * the listed ones off and leaves the others. A name the model description does not declare
     * is refused, naming it, and the categories in force stay as they were. */
    Instance *inst = CHECKED(c, fmi2SetDebugLogging);
    if (!inst) return fmi2Error;
    if (nCategories && !categories) return REFUSE(inst, "fmi2SetDebugLogging: categories is NULL");
    unsigned listed = 0;
    for (size_t k = 0; k < nCategories; k++) {
        int found = -1;
        for (int j = 0; j < CP_NLOG && categories[k]; j++)
            if (strcmp(categories[k], cp_log_categories[j]) == 0) found = j;
        if (found < 0) {
            char declared[512] = "";
            for (int j = 0, n = 0; j < CP_NLOG && n < (int)sizeof declared; j++)
                n += snprintf(declared + n, sizeof declared - n, "%s%s", j ? ", " : "",
                              cp_log_categories[j]);
            return REFUSE(inst, "fmi2SetDebugLogging: log category \"%s\" is not this FMU's "
                          "(its model description declares %s)",
                          categories[k] ? categories[k] : "(null)", declared);
        }
        listed |= 1u << found;
    }
    if (!nCategories) inst->logging = loggingOn ? ALL_CATEGORIES : 0;
    else inst->logging = loggingOn ? listed : inst->logging & ~listed;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    (void)fmuResourceLocation;
    (void)visible;
    if (!functions || !functions->allocateMemory || !functions->freeMemory) return NULL;
    Instance *inst = functions->allocateMemory(1, sizeof(Instance));
    if (!inst) return NULL;
    inst->cb = *functions;
    inst->type = fmuType;
    inst->logging = loggingOn ? ALL_CATEGORIES : 0;
    snprintf(inst->name, sizeof inst->name, "%s", instanceName ? instanceName : "?");
    const char *problem = NULL;
    if (!instanceName || !*instanceName) problem = "instanceName is empty";
    else if (!fmuGUID || strcmp(fmuGUID, CP_GUID) != 0)
        problem = "fmuGUID is not this FMU's: the model description and binary do not match";
    else if (fmuType != fmi2ModelExchange && fmuType != fmi2CoSimulation)
        problem = "fmuType is neither fmi2ModelExchange nor fmi2CoSimulation";
    if (problem) {
        log_message(inst, fmi2Error, CP_LOG_STATUS_ERROR, "fmi2Instantiate: %s", problem);
        functions->freeMemory(inst);
        return NULL;
    }
    reset_values(inst);
    return inst;
}

void fmi2FreeInstance(fmi2Component c)
{
    Instance *inst = (Instance *)c;
    if (inst) inst->cb.freeMemory(inst);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    (void)stopTimeDefined;
    (void)stopTime;
    Instance *inst = CHECKED(c, fmi2SetupExperiment);
    if (!inst) return fmi2Error;
    char message[256];
    if (toleranceDefined && real_refusal("tolerance (from setupExperiment)", tolerance,
                                    &cp_rules[cp_real_rule[CP_VR_RTOL]],
                                    cp_real_what[CP_VR_RTOL], message, sizeof message))
        return REFUSE(inst, "%s", message);
    if (!isfinite(startTime)) return REFUSE(inst, "startTime = %g: must be finite", startTime);
    inst->v.tolerance = toleranceDefined ? tolerance : 0.0;
    inst->v.time = inst->v.last_successful_time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    Instance *inst = CHECKED(c, fmi2EnterInitializationMode);
    if (!inst) return fmi2Error;
    inst->v.state = INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    Instance *inst = CHECKED(c, fmi2ExitInitializationMode);
    if (!inst) return fmi2Error;
    if (inst->v.tolerance > 0) inst->v.r[CP_VR_RTOL] = inst->v.tolerance;
    invalidate(inst);
    update_outputs(inst);
    inst->v.state = inst->type == fmi2CoSimulation ? STEP_COMPLETE : EVENT_MODE;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    Instance *inst = CHECKED(c, fmi2Terminate);
    if (!inst) return fmi2Error;
    inst->v.state = TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    Instance *inst = (Instance *)c;  /* allowed in every state: whatever it holds, never refused */
    if (!inst) return fmi2Error;
    reset_values(inst);
    return fmi2OK;
}

/* ---- getting and setting values ------------------------------------------------------- */

static int is_derivative(fmi2ValueReference vr)
{
    return vr >= CP_VR_DERIVATIVE && vr < CP_VR_DERIVATIVE + CP_NSTATE;
}

/* fmi2Discard, logged: x' cannot be had at the instance's state (status from cp_rhs or from
 * its complex-step copy, with the weakest generalized speed and pivot ratio it found). */
static fmi2Status no_derivatives(Instance *inst, int status, int bad_dof, double pivot_ratio)
{
    log_message(inst, fmi2Discard, CP_LOG_STATUS_DISCARD, "derivatives at t = %.9g s: %s at "
                "generalized speed %d (pivot ratio %.2g); check parameters and state",
                inst->v.time, cp_status_message(status), bad_dof, pivot_ratio);
    return fmi2Discard;
}

static fmi2Status derivatives(Instance *inst)
{
    if (inst->v.dx_valid) return fmi2OK;
    cp_model model = {inst->v.r, 1.0, -1};
    int status = cp_rhs(&model, X(inst), inst->v.dx);
    if (status != CP_OK) return no_derivatives(inst, status, model.bad_dof, model.pivot_ratio);
    inst->v.dx_valid = 1;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    Instance *inst = CHECKED(c, fmi2GetReal);
    if (!inst) return fmi2Error;
    if (nvr && (!vr || !value)) return REFUSE(inst, "fmi2GetReal: vr or value is NULL");
    for (size_t k = 0; k < nvr; k++) {
        if (vr[k] < CP_NREAL) {
            if (vr[k] >= CP_VR_OUTPUT && vr[k] < CP_VR_STATISTICS) update_outputs(inst);
            value[k] = inst->v.r[vr[k]];
        } else if (is_derivative(vr[k])) {
            fmi2Status status = derivatives(inst);
            if (status != fmi2OK) return status;
            value[k] = inst->v.dx[vr[k] - CP_VR_DERIVATIVE];
        } else {
            return REFUSE(inst, "fmi2GetReal: value reference %u is not a Real variable", vr[k]);
        }
    }
    return fmi2OK;
}

/* NULL if the variable may be set in the instance's state, or why not: the standard's
 * conditions on the variable in the states where the table lets fmi2SetReal in. */
static const char *not_settable(const Instance *inst, fmi2ValueReference vr, char *message,
                                size_t size)
{
    int input = vr >= CP_VR_INPUT && vr < CP_VR_STATE;
    int calculated = (vr >= CP_VR_OUTPUT && vr < CP_VR_SETTINGS) || is_derivative(vr);
    if (calculated) snprintf(message, size, CP_CALCULATED_MESSAGE, cp_variable_name(vr));
    else if (!input && !(inst->v.state & BEFORE_INIT))
        snprintf(message, size, CP_FIXED_MESSAGE, cp_variable_name(vr));
    else return NULL;
    return message;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    Instance *inst = CHECKED(c, fmi2SetReal);
    if (!inst) return fmi2Error;
    if (nvr && (!vr || !value)) return REFUSE(inst, "fmi2SetReal: vr or value is NULL");
    char message[512];
    for (size_t k = 0; k < nvr; k++) {  /* all checked before any is taken */
        if (vr[k] >= CP_NREAL && !is_derivative(vr[k]))
            return REFUSE(inst, "fmi2SetReal: value reference %u is not a Real variable", vr[k]);
        if (not_settable(inst, vr[k], message, sizeof message)
            || real_refusal(cp_variable_name(vr[k]), value[k], &cp_rules[cp_real_rule[vr[k]]],
                       cp_real_what[vr[k]], message, sizeof message))
            return REFUSE(inst, "%s", message);
    }
    for (size_t k = 0; k < nvr; k++) {
        if (inst->v.r[vr[k]] != value[k]) invalidate(inst);
        inst->v.r[vr[k]] = value[k];
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    Instance *inst = CHECKED(c, fmi2GetInteger);
    if (!inst) return fmi2Error;
    if (nvr && (!vr || !value)) return REFUSE(inst, "fmi2GetInteger: vr or value is NULL");
    for (size_t k = 0; k < nvr; k++) {
        if (vr[k] == CP_VR_SOLVER) value[k] = inst->v.solver;
        else if (vr[k] == CP_VR_MAX_STEPS) value[k] = inst->v.max_steps;
        else return REFUSE(inst, "fmi2GetInteger: value reference %u is not an Integer variable",
                           vr[k]);
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    Instance *inst = CHECKED(c, fmi2SetInteger);
    if (!inst) return fmi2Error;
    if (nvr && (!vr || !value)) return REFUSE(inst, "fmi2SetInteger: vr or value is NULL");
    char message[512];
    for (size_t k = 0; k < nvr; k++) {
        if (vr[k] != CP_VR_SOLVER && vr[k] != CP_VR_MAX_STEPS)
            return REFUSE(inst, "fmi2SetInteger: value reference %u is not an Integer variable",
                          vr[k]);
        if (!(inst->v.state & BEFORE_INIT)) {
            snprintf(message, sizeof message, CP_FIXED_MESSAGE, cp_variable_name(vr[k]));
            return REFUSE(inst, "%s", message);
        }
        if (integer_refusal(vr[k], value[k], message, sizeof message))
            return REFUSE(inst, "%s", message);
    }
    for (size_t k = 0; k < nvr; k++)
        *(vr[k] == CP_VR_SOLVER ? &inst->v.solver : &inst->v.max_steps) = value[k];
    return fmi2OK;
}

/* Booleans and Strings: this FMU has none, so any value reference is refused. */
static fmi2Status no_variables(Instance *inst, const char *function, const char *type,
                               const fmi2ValueReference vr[], size_t nvr)
{
    if (!inst) return fmi2Error;
    return nvr ? REFUSE(inst, "%s: value reference %u: this FMU has no %s variables", function,
                        vr ? vr[0] : 0, type) : fmi2OK;
}

#define NO_VARIABLES(function, type, value_type)                                              \
    fmi2Status function(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,            \
                        value_type value[])                                                   \
    {                                                                                          \
        (void)value;                                                                           \
        return no_variables(CHECKED(c, function), #function, type, vr, nvr);                   \
    }
NO_VARIABLES(fmi2GetBoolean, "Boolean", fmi2Boolean)
NO_VARIABLES(fmi2SetBoolean, "Boolean", const fmi2Boolean)
NO_VARIABLES(fmi2GetString, "String", fmi2String)
NO_VARIABLES(fmi2SetString, "String", const fmi2String)

/* ---- the FMU state ---------------------------------------------------------------------- */

#define STATE_MAGIC 0x43504631u  /* "CPF1": a serialized Values of this build */

typedef struct {
    unsigned magic;
    unsigned size;
    char guid[sizeof CP_GUID];
} StateHeader;

/* NULL if v can be the values of an instance of this type, or what is wrong with it, naming
 * the field and its value: a restored state is checked as values set through the API are.
 * The instance state is one state of the type's state machine; every Real keeps its
 * variable's rule as fmi2SetReal applies it (the outputs where they are valid), and the
 * statistics are counts; solver and max_steps keep theirs as fmi2SetInteger applies them,
 * the tolerance is 0 (none) or keeps fmi2SetupExperiment's; the carried step is finite and
 * not negative, the flags are 0 or 1, the carried derivatives are finite where they are
 * valid, and the times are finite. */
static const char *invalid_values(fmi2Type type, const Values *v, char *message, size_t size)
{
    const unsigned states = type == fmi2CoSimulation ? CO_SIMULATION_STATES : MODEL_EXCHANGE_STATES;
    const unsigned bits = (unsigned)v->state;
    if (!(bits & states) || (bits & (bits - 1))) {  /* none of them, or more than one bit */
        snprintf(message, size, "instance state = %d: not one state a%s instance can be in",
                 v->state, type == fmi2CoSimulation ? " Co-Simulation" : " Model Exchange");
        return message;
    }
    const struct { const char *name; int value; } flags[] = {
        {"fsal", v->fsal}, {"dx_valid", v->dx_valid}, {"outputs_valid", v->outputs_valid}};
    for (size_t k = 0; k < sizeof flags / sizeof flags[0]; k++)
        if (flags[k].value != 0 && flags[k].value != 1) {
            snprintf(message, size, "%s = %d: must be 0 or 1", flags[k].name, flags[k].value);
            return message;
        }
    for (int vr = 0; vr < CP_NREAL; vr++) {
        if (vr >= CP_VR_OUTPUT && vr < CP_VR_STATISTICS && !v->outputs_valid) continue;
        if (real_refusal(cp_variable_name(vr), v->r[vr], &cp_rules[cp_real_rule[vr]],
                         cp_real_what[vr], message, size))
            return message;
    }
    if (integer_refusal(CP_VR_SOLVER, v->solver, message, size)
        || integer_refusal(CP_VR_MAX_STEPS, v->max_steps, message, size))
        return message;
    if (v->tolerance != 0.0 && real_refusal("tolerance (from setupExperiment)", v->tolerance,
                                            &cp_rules[cp_real_rule[CP_VR_RTOL]],
                                            cp_real_what[CP_VR_RTOL], message, size))
        return message;
    if (real_refusal("h", v->h, &cp_rules[CP_STEP_RULE], CP_STEP_WHAT, message, size)
        || real_refusal("time", v->time, &cp_rules[CP_FINITE_RULE], "", message, size)
        || real_refusal("last_successful_time", v->last_successful_time,
                        &cp_rules[CP_FINITE_RULE], "", message, size))
        return message;
    char name[160];
    for (int k = 0; k < CP_NSTATE; k++) {
        snprintf(name, sizeof name, "carried %s", cp_variable_name(CP_VR_DERIVATIVE + k));
        if ((v->fsal && real_refusal(name, v->work[k], &cp_rules[CP_FINITE_RULE], "", message, size))
            || (v->dx_valid && real_refusal(cp_variable_name(CP_VR_DERIVATIVE + k), v->dx[k],
                                            &cp_rules[CP_FINITE_RULE], "", message, size)))
            return message;
    }
    return NULL;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    Instance *inst = CHECKED(c, fmi2GetFMUstate);
    if (!inst) return fmi2Error;
    if (!FMUstate) return REFUSE(inst, "fmi2GetFMUstate: FMUstate is NULL");
    Values *copy = *FMUstate ? *FMUstate : inst->cb.allocateMemory(1, sizeof(Values));
    if (!copy) return REFUSE(inst, "fmi2GetFMUstate: out of memory");
    *copy = inst->v;
    *FMUstate = copy;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    Instance *inst = CHECKED(c, fmi2SetFMUstate);
    if (!inst) return fmi2Error;
    if (!FMUstate) return REFUSE(inst, "fmi2SetFMUstate: FMUstate is NULL");
    char message[512];
    if (invalid_values(inst->type, FMUstate, message, sizeof message))
        return REFUSE(inst, "fmi2SetFMUstate: the state's %s", message);
    inst->v = *(const Values *)FMUstate;
    inst->discarded[0] = '\0';
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    Instance *inst = (Instance *)c;  /* allowed in every state: whatever it holds, never refused */
    if (!inst) return fmi2Error;
    if (!FMUstate) return REFUSE(inst, "fmi2FreeFMUstate: FMUstate is NULL");
    if (*FMUstate) inst->cb.freeMemory(*FMUstate);
    *FMUstate = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    Instance *inst = CHECKED(c, fmi2SerializedFMUstateSize);
    if (!inst) return fmi2Error;
    if (!FMUstate || !size) return REFUSE(inst, "fmi2SerializedFMUstateSize: a pointer is NULL");
    *size = sizeof(StateHeader) + sizeof(Values);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                 fmi2Byte serializedState[], size_t size)
{
    Instance *inst = CHECKED(c, fmi2SerializeFMUstate);
    if (!inst) return fmi2Error;
    if (!FMUstate || !serializedState) return REFUSE(inst, "fmi2SerializeFMUstate: a pointer is NULL");
    if (size < sizeof(StateHeader) + sizeof(Values))
        return REFUSE(inst, "fmi2SerializeFMUstate: %zu bytes are too few; "
                      "fmi2SerializedFMUstateSize says how many", size);
    StateHeader header = {STATE_MAGIC, (unsigned)sizeof(Values), CP_GUID};
    memcpy(serializedState, &header, sizeof header);
    memcpy(serializedState + sizeof header, FMUstate, sizeof(Values));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    Instance *inst = CHECKED(c, fmi2DeSerializeFMUstate);
    if (!inst) return fmi2Error;
    if (!serializedState || !FMUstate) return REFUSE(inst, "fmi2DeSerializeFMUstate: a pointer is NULL");
    StateHeader header;
    if (size != sizeof header + sizeof(Values))
        return REFUSE(inst, "fmi2DeSerializeFMUstate: %zu bytes are not a state of this FMU", size);
    memcpy(&header, serializedState, sizeof header);
    if (header.magic != STATE_MAGIC || header.size != sizeof(Values)
        || memcmp(header.guid, CP_GUID, sizeof CP_GUID) != 0)
        return REFUSE(inst, "fmi2DeSerializeFMUstate: the bytes are not a state of this FMU "
                      "(another model, build or version)");
    /* Checked in a copy of its own (the bytes need not be aligned), taken only if it passes. */
    Values *copy = inst->cb.allocateMemory(1, sizeof(Values));
    if (!copy) return REFUSE(inst, "fmi2DeSerializeFMUstate: out of memory");
    memcpy(copy, serializedState + sizeof header, sizeof(Values));
    char message[512];
    if (invalid_values(inst->type, copy, message, sizeof message)) {
        inst->cb.freeMemory(copy);
        return REFUSE(inst, "fmi2DeSerializeFMUstate: the state's %s", message);
    }
    if (*FMUstate) {  /* the caller's state, reused */
        memcpy(*FMUstate, copy, sizeof(Values));
        inst->cb.freeMemory(copy);
    } else {
        *FMUstate = copy;
    }
    return fmi2OK;
}

/* ---- directional derivatives -------------------------------------------------------------- */

/* dvUnknown = J dvKnown (FMI 2.0, section 2.1.9), J the Jacobian of the unknowns (state
 * derivatives and outputs) with respect to the knowns (states and inputs) at the current
 * values, from directional.c: the model's own C evaluated in complex arithmetic, exact to
 * rounding. A state as unknown is an output of its own value; the statistics depend on
 * nothing (ModelStructure). Nothing of the instance changes. */
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[], fmi2Real dvUnknown[])
{
    static const char *const function = "fmi2GetDirectionalDerivative";
    Instance *inst = CHECKED(c, fmi2GetDirectionalDerivative);
    if (!inst) return fmi2Error;
    if ((nUnknown && (!vUnknown_ref || !dvUnknown)) || (nKnown && (!vKnown_ref || !dvKnown)))
        return REFUSE(inst, "%s: a pointer is NULL", function);
    double dx_seed[CP_NSTATE] = {0}, dp_seed[CP_NPARAM] = {0};
    for (size_t k = 0; k < nKnown; k++) {
        const fmi2ValueReference vr = vKnown_ref[k];
        if (vr < CP_VR_INPUT || vr >= CP_VR_STATE + CP_NSTATE)
            return REFUSE(inst, "%s: value reference %u (%s) as a known: only states and "
                          "inputs are", function, vr, cp_variable_name(vr));
        if (!isfinite(dvKnown[k]))
            return REFUSE(inst, "%s: dvKnown of %s = %g: must be finite", function,
                          cp_variable_name(vr), dvKnown[k]);
        if (vr < CP_VR_STATE) dp_seed[vr] += dvKnown[k];  /* the inputs end p (fmu_config.h) */
        else dx_seed[vr - CP_VR_STATE] += dvKnown[k];
    }
    int want_derivatives = 0, want_outputs = 0;
    for (size_t k = 0; k < nUnknown; k++) {
        const fmi2ValueReference vr = vUnknown_ref[k];
        if (is_derivative(vr)) want_derivatives = 1;
        else if (vr >= CP_VR_OUTPUT && vr < CP_VR_STATISTICS) want_outputs = 1;
        else if (vr < CP_VR_STATE || vr >= CP_VR_SETTINGS)
            return REFUSE(inst, "%s: value reference %u (%s) as an unknown: only outputs and "
                          "state derivatives are", function, vr, cp_variable_name(vr));
    }
    double d_derivatives[CP_NSTATE], d_outputs[CP_NOUTPUT + 1];
    if (want_derivatives || want_outputs) {
        double pivot_ratio;
        int bad_dof;
        int status = cp_directional(X(inst), inst->v.r, dx_seed, dp_seed,
                                    want_derivatives ? d_derivatives : NULL,
                                    want_outputs ? d_outputs : NULL, &pivot_ratio, &bad_dof);
        if (status != CP_OK) return no_derivatives(inst, status, bad_dof, pivot_ratio);
    }
    for (size_t k = 0; k < nUnknown; k++) {
        const fmi2ValueReference vr = vUnknown_ref[k];
        double value = 0.0;  /* a statistic */
        if (is_derivative(vr)) value = d_derivatives[vr - CP_VR_DERIVATIVE];
        else if (vr >= CP_VR_OUTPUT && vr < CP_VR_STATISTICS) value = d_outputs[vr - CP_VR_OUTPUT];
        else if (vr < CP_VR_OUTPUT) value = dx_seed[vr - CP_VR_STATE];
        if (!isfinite(value)) {
            log_message(inst, fmi2Discard, CP_LOG_STATUS_DISCARD, "%s: the derivative of %s is "
                        "not finite at t = %.9g s; check parameters and state", function,
                        cp_variable_name(vr), inst->v.time);
            return fmi2Discard;
        }
        dvUnknown[k] = value;
    }
    return fmi2OK;
}

/* ---- Model Exchange ----------------------------------------------------------------------- */

fmi2Status fmi2EnterEventMode(fmi2Component c)
{
    Instance *inst = CHECKED(c, fmi2EnterEventMode);
    if (!inst) return fmi2Error;
    inst->v.state = EVENT_MODE;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo)
{
    Instance *inst = CHECKED(c, fmi2NewDiscreteStates);
    if (!inst) return fmi2Error;
    if (!eventInfo) return REFUSE(inst, "fmi2NewDiscreteStates: eventInfo is NULL");
    memset(eventInfo, 0, sizeof *eventInfo);  /* no events: nothing changes, nothing to wait for */
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c)
{
    Instance *inst = CHECKED(c, fmi2EnterContinuousTimeMode);
    if (!inst) return fmi2Error;
    inst->v.state = CONTINUOUS_TIME;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    Instance *inst = CHECKED(c, fmi2CompletedIntegratorStep);
    if (!inst) return fmi2Error;
    if (!enterEventMode || !terminateSimulation)
        return REFUSE(inst, "fmi2CompletedIntegratorStep: a pointer is NULL");
    *enterEventMode = *terminateSimulation = fmi2False;
    inst->v.last_successful_time = inst->v.time;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    Instance *inst = CHECKED(c, fmi2SetTime);
    if (!inst) return fmi2Error;
    if (!isfinite(time)) return REFUSE(inst, "fmi2SetTime: time = %g must be finite", time);
    inst->v.time = time;  /* the model is autonomous: x' does not depend on time */
    return fmi2OK;
}

static fmi2Status check_states_call(Instance *inst, const void *x, size_t nx, const char *function)
{
    if (!x) return REFUSE(inst, "%s: the array is NULL", function);
    if (nx != CP_NSTATE) return REFUSE(inst, "%s: nx = %zu, but this FMU has %d continuous "
                                       "states", function, nx, CP_NSTATE);
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    Instance *inst = CHECKED(c, fmi2SetContinuousStates);
    if (!inst) return fmi2Error;
    if (check_states_call(inst, x, nx, "fmi2SetContinuousStates") != fmi2OK) return fmi2Error;
    for (size_t k = 0; k < nx; k++)
        if (!isfinite(x[k]))
            return REFUSE(inst, "fmi2SetContinuousStates: %s = %g: must be finite",
                          cp_variable_name(CP_VR_STATE + k), x[k]);
    memcpy(X(inst), x, nx * sizeof x[0]);
    invalidate(inst);
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx)
{
    Instance *inst = CHECKED(c, fmi2GetDerivatives);
    if (!inst) return fmi2Error;
    if (check_states_call(inst, dx, nx, "fmi2GetDerivatives") != fmi2OK) return fmi2Error;
    fmi2Status status = derivatives(inst);
    if (status == fmi2OK) memcpy(dx, inst->v.dx, nx * sizeof dx[0]);
    return status;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni)
{
    (void)eventIndicators;
    Instance *inst = CHECKED(c, fmi2GetEventIndicators);
    if (!inst) return fmi2Error;
    return ni ? REFUSE(inst, "fmi2GetEventIndicators: ni = %zu, but this FMU has none", ni) : fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    Instance *inst = CHECKED(c, fmi2GetContinuousStates);
    if (!inst) return fmi2Error;
    if (check_states_call(inst, x, nx, "fmi2GetContinuousStates") != fmi2OK) return fmi2Error;
    memcpy(x, X(inst), nx * sizeof x[0]);
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx)
{
    Instance *inst = CHECKED(c, fmi2GetNominalsOfContinuousStates);
    if (!inst) return fmi2Error;
    if (check_states_call(inst, x_nominal, nx, "fmi2GetNominalsOfContinuousStates") != fmi2OK)
        return fmi2Error;
    for (size_t k = 0; k < nx; k++) x_nominal[k] = 1.0;  /* angles and rates: order one */
    return fmi2OK;
}

/* ---- Co-Simulation ----------------------------------------------------------------------- */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr, (void)order, (void)value;
    Instance *inst = CHECKED(c, fmi2SetRealInputDerivatives);
    if (!inst) return fmi2Error;
    return nvr ? REFUSE(inst, "fmi2SetRealInputDerivatives: inputs are held constant over a "
                        "step (canInterpolateInputs is false)") : fmi2OK;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr, (void)order, (void)value;
    Instance *inst = CHECKED(c, fmi2GetRealOutputDerivatives);
    if (!inst) return fmi2Error;
    return nvr ? REFUSE(inst, "fmi2GetRealOutputDerivatives: not provided "
                        "(MaxOutputDerivativeOrder is 0)") : fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    Instance *inst = CHECKED(c, fmi2DoStep);
    if (!inst) return fmi2Error;
    const double t = currentCommunicationPoint, dt = communicationStepSize;
    if (!(fabs(t - inst->v.time) <= 1e-9 * fmax(1.0, fabs(t))))
        return REFUSE(inst, "fmi2DoStep: currentCommunicationPoint = %.17g s, but the FMU is "
                      "at t = %.17g s", t, inst->v.time);
    const cp_settings settings = {inst->v.solver, inst->v.r[CP_VR_RTOL], inst->v.r[CP_VR_ATOL],
                                  inst->v.r[CP_VR_MAX_STEP], inst->v.max_steps};
    cp_failure failure;
    int status = cp_cosim_step(&settings, inst->v.r, X(inst), Y(inst), t, dt, &inst->v.h,
                               inst->v.work, &inst->v.fsal, STATS(inst), &failure);
    inst->v.outputs_valid = status == CP_OK;  /* on failure, those at t are computed again */
    if (status != CP_OK) {
        cp_diagnose(inst->discarded, sizeof inst->discarded, status, &failure);
        log_message(inst, fmi2Discard, CP_LOG_STATUS_DISCARD, "%s", inst->discarded);
        inst->v.state = STEP_FAILED;
        return fmi2Discard;
    }
    inst->v.time = inst->v.last_successful_time = t + dt;
    inst->v.dx_valid = 0;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    CHECKED(c, fmi2CancelStep);  /* allowed in no state this FMU enters: logs why */
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    Instance *inst = CHECKED(c, fmi2GetStatus);
    if (!inst) return fmi2Error;
    if (!value) return REFUSE(inst, "fmi2GetStatus: value is NULL");
    if (s != fmi2DoStepStatus) return fmi2Discard;
    *value = inst->v.state == STEP_FAILED ? fmi2Discard : fmi2OK;
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    Instance *inst = CHECKED(c, fmi2GetRealStatus);
    if (!inst) return fmi2Error;
    if (!value) return REFUSE(inst, "fmi2GetRealStatus: value is NULL");
    if (s != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = inst->v.last_successful_time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s, (void)value;
    return CHECKED(c, fmi2GetIntegerStatus) ? fmi2Discard : fmi2Error;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    Instance *inst = CHECKED(c, fmi2GetBooleanStatus);
    if (!inst) return fmi2Error;
    if (!value) return REFUSE(inst, "fmi2GetBooleanStatus: value is NULL");
    if (s != fmi2Terminated) return fmi2Discard;
    *value = fmi2False;  /* the model never asks to stop */
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s, (void)value;
    return CHECKED(c, fmi2GetStringStatus) ? fmi2Discard : fmi2Error;
}
