/* FMI 2.0 glue of the native FMU: Co-Simulation and Model Exchange, and nothing else.
 *
 * FMI 2.0's API, its state machine, its FMU states and its logging. The model is behind the
 * model contract (fmu_model.h: sizes, the variable table, x', the outputs, directional
 * derivatives, the co-simulation step, the check of a restored model state); from
 * fmu_config.h (generated at build time) the glue takes only the GUID, the log categories
 * and the variables' names. Every entry point checks its instance, its state and its
 * arguments; a refused value is fmi2Error with the model's message naming it and is not
 * taken; a step that cannot complete is fmi2Discard with the model's diagnosis; messages go
 * through the host's logger. Nothing is allocated after instantiation but what a host asks
 * for (FMU states).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"

#include "fmi_layer.h"
#include "fmu_config.h"
#include "fmu_model.h"

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
 * after initialization, ...), the state is in and the model checks the variable
 * (model_check_real, model_check_integer). fmi2GetTypesPlatform and fmi2GetVersion take no
 * instance. fmi2FreeInstance, fmi2Reset and fmi2FreeFMUstate are allowed in every state and
 * never refused, whatever the instance holds, so an instance can always be reset and freed:
 * they do not consult it. */
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

/* What FMI 2.0 keeps of an instance besides the model's data: where it is in the state
 * machine, its time, and the last communication point a step reached. */
typedef FmiMachine Machine;

/* An FMU state, as fmi2GetFMUstate saves it and fmi2SerializeFMUstate writes it after its
 * header: the machine, then the model's data (model_sizes.data_size bytes), plain data
 * copied as a whole. */
typedef struct {
    Machine machine;
    double model[];               /* a ModelData; double: its alignment (fmu_model.h) */
} SavedState;

typedef struct {
    Machine machine;              /* first: the state word is where the instance begins */
    fmi2CallbackFunctions cb;
    fmi2Type type;
    unsigned logging;             /* bit k: log category cp_log_categories[k] is on */
    char name[128];
    char discarded[2048];         /* the last discarded step's diagnosis, while in stepFailed */
    double model[];               /* the model's data, in the instance's allocation */
} Instance;

#define ALL_CATEGORIES ((1u << CP_NLOG) - 1)
#define MODEL(inst) ((ModelData *)(inst)->model)
#define MESSAGE_SIZE 1024
#define SAVED_SIZE (sizeof(SavedState) + model_sizes.data_size)

/* A layer's message, formatted by fmi_vlog, to the host's logger. */
static void emit(void *context, int status, int category, const char *text)
{
    Instance *inst = context;
    inst->cb.logger(inst->cb.componentEnvironment, inst->name, (fmi2Status)status,
                    cp_log_categories[category], text);
}

/* A message through the host's logger, in one of the model description's log categories
 * (CP_LOG_*, fmu_config.h). FMI 2.0, section 2.1.3: after fmi2Warning, fmi2Error and fmi2Fatal
 * "function logger was called", so those are always reported; other messages (fmi2Discard's
 * diagnoses) only in debug mode, that is when their category is on (section 2.1.5: loggingOn
 * of fmi2Instantiate, then fmi2SetDebugLogging). */
static void log_message(Instance *inst, fmi2Status status, int category, const char *format, ...)
{
    if (!inst->cb.logger) return;
    va_list args;
    va_start(args, format);
    fmi_vlog(emit, inst, status, status != fmi2OK && status != fmi2Discard, inst->logging,
             category, format, args);
    va_end(args);
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
    if (inst->machine.state & allowed) return inst;
    const char *state = fmi_state_name(inst->machine.state, state_names,
                                       (int)(sizeof state_names / sizeof state_names[0]));
    const char *why = fmi_refusal_reason(
        cs, allowed, cs ? model_exchange : co_simulation,
        ": only while a step is in progress, and fmi2DoStep never runs asynchronously here",
        inst->machine.state == STEP_FAILED
            ? "; after a discarded step fmi2SetFMUstate or fmi2Reset go back, fmi2Terminate ends"
            : "");
    /* the diagnosis again, in an error that is always reported: logged at the discard only in
     * debug mode, it would otherwise never reach a host that did not ask for it */
    const int failed = inst->machine.state == STEP_FAILED && inst->discarded[0];
    log_message(inst, fmi2Error, CP_LOG_STATUS_ERROR, "%s is not allowed in state %s (FMI 2.0, %s)%s%s%s",
                function, state, cs ? "Co-Simulation, section 4.2.4" : "Model Exchange, section 3.2.3",
                why, failed ? ". The step was discarded: " : "", failed ? inst->discarded : "");
    return NULL;
}

/* The instance as it is instantiated, and as fmi2Reset leaves it. */
static void reset(Instance *inst)
{
    fmi_machine_reset(&inst->machine, INSTANTIATED);
    inst->discarded[0] = '\0';
    model_reset(MODEL(inst));
}

/* Where the model can say only that x' or a step cannot be had: its message, logged. */
static fmi2Status discard(Instance *inst, const char *message)
{
    log_message(inst, fmi2Discard, CP_LOG_STATUS_DISCARD, "%s", message);
    return fmi2Discard;
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
    char refusal[4096];
    if (fmi_set_logging(&inst->logging, loggingOn, nCategories, categories, cp_log_categories,
                        CP_NLOG, "fmi2SetDebugLogging", refusal, sizeof refusal))
        return REFUSE(inst, "%s", refusal);
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
    Instance *inst = functions->allocateMemory(1, sizeof(Instance) + model_sizes.data_size);
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
    reset(inst);
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
    char message[MESSAGE_SIZE];
    if (toleranceDefined && model_tolerance_refusal(tolerance, message, sizeof message))
        return REFUSE(inst, "%s", message);
    if (!isfinite(startTime)) return REFUSE(inst, "startTime = %g: must be finite", startTime);
    model_set_tolerance(MODEL(inst), toleranceDefined ? tolerance : 0.0);
    inst->machine.time = inst->machine.last_successful_time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    Instance *inst = CHECKED(c, fmi2EnterInitializationMode);
    if (!inst) return fmi2Error;
    inst->machine.state = INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    Instance *inst = CHECKED(c, fmi2ExitInitializationMode);
    if (!inst) return fmi2Error;
    model_initialize(MODEL(inst));
    inst->machine.state = inst->type == fmi2CoSimulation ? STEP_COMPLETE : EVENT_MODE;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    Instance *inst = CHECKED(c, fmi2Terminate);
    if (!inst) return fmi2Error;
    inst->machine.state = TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    Instance *inst = (Instance *)c;  /* allowed in every state: whatever it holds, never refused */
    if (!inst) return fmi2Error;
    reset(inst);
    return fmi2OK;
}

/* ---- getting and setting values ------------------------------------------------------- */

/* Whether the instance is past initialization mode, where only inputs may still be set. */
static int initialized(const Instance *inst)
{
    return !(inst->machine.state & BEFORE_INIT);
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    Instance *inst = CHECKED(c, fmi2GetReal);
    if (!inst) return fmi2Error;
    if (nvr && (!vr || !value)) return REFUSE(inst, "fmi2GetReal: vr or value is NULL");
    char message[MESSAGE_SIZE];
    for (size_t k = 0; k < nvr; k++) {
        switch (model_get_real(MODEL(inst), vr[k], &value[k], inst->machine.time, message,
                               sizeof message)) {
        case MODEL_OK: break;
        case MODEL_DISCARD: return discard(inst, message);
        case MODEL_REFUSED: return REFUSE(inst, "fmi2GetReal: %s", message);
        case MODEL_NO_VARIABLE:
            return REFUSE(inst, "fmi2GetReal: value reference %u is not a Real variable", vr[k]);
        }
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    Instance *inst = CHECKED(c, fmi2SetReal);
    if (!inst) return fmi2Error;
    if (nvr && (!vr || !value)) return REFUSE(inst, "fmi2SetReal: vr or value is NULL");
    char message[MESSAGE_SIZE];
    for (size_t k = 0; k < nvr; k++) {  /* all checked before any is taken */
        ModelStatus status = model_check_real(MODEL(inst), vr[k], value[k], initialized(inst),
                                              message, sizeof message);
        if (status == MODEL_NO_VARIABLE)
            return REFUSE(inst, "fmi2SetReal: value reference %u is not a Real variable", vr[k]);
        if (status != MODEL_OK) return REFUSE(inst, "%s", message);
    }
    for (size_t k = 0; k < nvr; k++) model_set_real(MODEL(inst), vr[k], value[k]);
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    Instance *inst = CHECKED(c, fmi2GetInteger);
    if (!inst) return fmi2Error;
    if (nvr && (!vr || !value)) return REFUSE(inst, "fmi2GetInteger: vr or value is NULL");
    for (size_t k = 0; k < nvr; k++)
        if (model_get_integer(MODEL(inst), vr[k], &value[k]) != MODEL_OK)
            return REFUSE(inst, "fmi2GetInteger: value reference %u is not an Integer variable",
                          vr[k]);
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    Instance *inst = CHECKED(c, fmi2SetInteger);
    if (!inst) return fmi2Error;
    if (nvr && (!vr || !value)) return REFUSE(inst, "fmi2SetInteger: vr or value is NULL");
    char message[MESSAGE_SIZE];
    for (size_t k = 0; k < nvr; k++) {  /* all checked before any is taken */
        ModelStatus status = model_check_integer(MODEL(inst), vr[k], value[k], initialized(inst),
                                                 message, sizeof message);
        if (status == MODEL_NO_VARIABLE)
            return REFUSE(inst, "fmi2SetInteger: value reference %u is not an Integer variable",
                          vr[k]);
        if (status != MODEL_OK) return REFUSE(inst, "%s", message);
    }
    for (size_t k = 0; k < nvr; k++) model_set_integer(MODEL(inst), vr[k], value[k]);
    return fmi2OK;
}

/* Booleans and Strings: the model contract has none, so any value reference is refused. */
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

#define STATE_MAGIC 0x43504632u  /* "CPF2": a serialized SavedState of this build */

#define HEADER_SIZE fmi_state_header_size(CP_GUID)

/* NULL if s can be the state of an instance of this type, or what is wrong with it, naming
 * the field and its value: a restored state is checked as values set through the API are.
 * The instance state is one state of the type's state machine, the model's data passes
 * model_invalid, and the times are finite. */
static const char *invalid_state(fmi2Type type, const SavedState *s, char *message, size_t size)
{
    const unsigned states = type == fmi2CoSimulation ? CO_SIMULATION_STATES : MODEL_EXCHANGE_STATES;
    const unsigned bits = (unsigned)s->machine.state;
    if (!(bits & states) || (bits & (bits - 1))) {  /* none of them, or more than one bit */
        snprintf(message, size, "instance state = %d: not one state a%s instance can be in",
                 s->machine.state, type == fmi2CoSimulation ? " Co-Simulation" : " Model Exchange");
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

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    Instance *inst = CHECKED(c, fmi2GetFMUstate);
    if (!inst) return fmi2Error;
    if (!FMUstate) return REFUSE(inst, "fmi2GetFMUstate: FMUstate is NULL");
    SavedState *copy = *FMUstate ? *FMUstate : inst->cb.allocateMemory(1, SAVED_SIZE);
    if (!copy) return REFUSE(inst, "fmi2GetFMUstate: out of memory");
    copy->machine = inst->machine;
    memcpy(copy->model, inst->model, model_sizes.data_size);
    *FMUstate = copy;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    Instance *inst = CHECKED(c, fmi2SetFMUstate);
    if (!inst) return fmi2Error;
    if (!FMUstate) return REFUSE(inst, "fmi2SetFMUstate: FMUstate is NULL");
    const SavedState *saved = FMUstate;
    char message[MESSAGE_SIZE];
    if (invalid_state(inst->type, saved, message, sizeof message))
        return REFUSE(inst, "fmi2SetFMUstate: the state's %s", message);
    inst->machine = saved->machine;
    memcpy(inst->model, saved->model, model_sizes.data_size);
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
    *size = HEADER_SIZE + SAVED_SIZE;
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                 fmi2Byte serializedState[], size_t size)
{
    Instance *inst = CHECKED(c, fmi2SerializeFMUstate);
    if (!inst) return fmi2Error;
    if (!FMUstate || !serializedState) return REFUSE(inst, "fmi2SerializeFMUstate: a pointer is NULL");
    if (size < HEADER_SIZE + SAVED_SIZE)
        return REFUSE(inst, "fmi2SerializeFMUstate: %zu bytes are too few; "
                      "fmi2SerializedFMUstateSize says how many", size);
    fmi_state_header_write(serializedState, STATE_MAGIC, (unsigned)SAVED_SIZE, CP_GUID);
    memcpy(serializedState + HEADER_SIZE, FMUstate, SAVED_SIZE);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    Instance *inst = CHECKED(c, fmi2DeSerializeFMUstate);
    if (!inst) return fmi2Error;
    if (!serializedState || !FMUstate) return REFUSE(inst, "fmi2DeSerializeFMUstate: a pointer is NULL");
    if (size != HEADER_SIZE + SAVED_SIZE)
        return REFUSE(inst, "fmi2DeSerializeFMUstate: %zu bytes are not a state of this FMU", size);
    if (!fmi_state_header_matches(serializedState, STATE_MAGIC, (unsigned)SAVED_SIZE, CP_GUID))
        return REFUSE(inst, "fmi2DeSerializeFMUstate: the bytes are not a state of this FMU "
                      "(another model, build or version)");
    /* Checked in a copy of its own (the bytes need not be aligned), taken only if it passes. */
    SavedState *copy = inst->cb.allocateMemory(1, SAVED_SIZE);
    if (!copy) return REFUSE(inst, "fmi2DeSerializeFMUstate: out of memory");
    memcpy(copy, serializedState + HEADER_SIZE, SAVED_SIZE);
    char message[MESSAGE_SIZE];
    if (invalid_state(inst->type, copy, message, sizeof message)) {
        inst->cb.freeMemory(copy);
        return REFUSE(inst, "fmi2DeSerializeFMUstate: the state's %s", message);
    }
    if (*FMUstate) {  /* the caller's state, reused */
        memcpy(*FMUstate, copy, SAVED_SIZE);
        inst->cb.freeMemory(copy);
    } else {
        *FMUstate = copy;
    }
    return fmi2OK;
}

/* ---- directional derivatives -------------------------------------------------------------- */

/* dvUnknown = J dvKnown (FMI 2.0, section 2.1.9), J the Jacobian of the unknowns with respect
 * to the knowns at the current values: model_directional_derivative (exact to rounding). A
 * seed or a result that is not finite is never passed on. Nothing of the instance changes. */
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[], fmi2Real dvUnknown[])
{
    static const char *const function = "fmi2GetDirectionalDerivative";
    Instance *inst = CHECKED(c, fmi2GetDirectionalDerivative);
    if (!inst) return fmi2Error;
    if ((nUnknown && (!vUnknown_ref || !dvUnknown)) || (nKnown && (!vKnown_ref || !dvKnown)))
        return REFUSE(inst, "%s: a pointer is NULL", function);
    for (size_t k = 0; k < nKnown; k++)
        if (!isfinite(dvKnown[k]))
            return REFUSE(inst, "%s: dvKnown of %s = %g: must be finite", function,
                          cp_variable_name(vKnown_ref[k]), dvKnown[k]);
    char message[MESSAGE_SIZE];
    switch (model_directional_derivative(MODEL(inst), vUnknown_ref, nUnknown, vKnown_ref, nKnown,
                                         dvKnown, dvUnknown, inst->machine.time, message,
                                         sizeof message)) {
    case MODEL_OK: break;
    case MODEL_DISCARD: return discard(inst, message);
    default: return REFUSE(inst, "%s: %s", function, message);
    }
    for (size_t k = 0; k < nUnknown; k++)
        if (!isfinite(dvUnknown[k])) {
            log_message(inst, fmi2Discard, CP_LOG_STATUS_DISCARD, "%s: the derivative of %s is "
                        "not finite at t = %.9g s; check parameters and state", function,
                        cp_variable_name(vUnknown_ref[k]), inst->machine.time);
            return fmi2Discard;
        }
    return fmi2OK;
}

/* ---- Model Exchange ----------------------------------------------------------------------- */

fmi2Status fmi2EnterEventMode(fmi2Component c)
{
    Instance *inst = CHECKED(c, fmi2EnterEventMode);
    if (!inst) return fmi2Error;
    inst->machine.state = EVENT_MODE;
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
    inst->machine.state = CONTINUOUS_TIME;
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
    inst->machine.last_successful_time = inst->machine.time;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    Instance *inst = CHECKED(c, fmi2SetTime);
    if (!inst) return fmi2Error;
    if (!isfinite(time)) return REFUSE(inst, "fmi2SetTime: time = %g must be finite", time);
    inst->machine.time = time;  /* the contract's models are autonomous: x' does not depend on time */
    return fmi2OK;
}

static fmi2Status check_states_call(Instance *inst, const void *x, size_t nx, const char *function)
{
    if (!x) return REFUSE(inst, "%s: the array is NULL", function);
    if (nx != (size_t)model_sizes.n_state)
        return REFUSE(inst, "%s: nx = %zu, but this FMU has %d continuous states", function, nx,
                      model_sizes.n_state);
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    Instance *inst = CHECKED(c, fmi2SetContinuousStates);
    if (!inst) return fmi2Error;
    if (check_states_call(inst, x, nx, "fmi2SetContinuousStates") != fmi2OK) return fmi2Error;
    char message[MESSAGE_SIZE];
    if (model_set_states(MODEL(inst), x, message, sizeof message))
        return REFUSE(inst, "fmi2SetContinuousStates: %s", message);
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx)
{
    Instance *inst = CHECKED(c, fmi2GetDerivatives);
    if (!inst) return fmi2Error;
    if (check_states_call(inst, dx, nx, "fmi2GetDerivatives") != fmi2OK) return fmi2Error;
    char message[MESSAGE_SIZE];
    if (model_get_derivatives(MODEL(inst), dx, inst->machine.time, message, sizeof message)
        != MODEL_OK)
        return discard(inst, message);
    return fmi2OK;
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
    model_get_states(MODEL(inst), x);
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx)
{
    Instance *inst = CHECKED(c, fmi2GetNominalsOfContinuousStates);
    if (!inst) return fmi2Error;
    if (check_states_call(inst, x_nominal, nx, "fmi2GetNominalsOfContinuousStates") != fmi2OK)
        return fmi2Error;
    model_get_nominals(MODEL(inst), x_nominal);
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
    if (!(fabs(t - inst->machine.time) <= 1e-9 * fmax(1.0, fabs(t))))
        return REFUSE(inst, "fmi2DoStep: currentCommunicationPoint = %.17g s, but the FMU is "
                      "at t = %.17g s", t, inst->machine.time);
    if (model_do_step(MODEL(inst), t, dt, inst->discarded, sizeof inst->discarded) != MODEL_OK) {
        inst->machine.state = STEP_FAILED;
        return discard(inst, inst->discarded);
    }
    inst->machine.time = inst->machine.last_successful_time = t + dt;
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
    *value = inst->machine.state == STEP_FAILED ? fmi2Discard : fmi2OK;
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    Instance *inst = CHECKED(c, fmi2GetRealStatus);
    if (!inst) return fmi2Error;
    if (!value) return REFUSE(inst, "fmi2GetRealStatus: value is NULL");
    if (s != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = inst->machine.last_successful_time;
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
