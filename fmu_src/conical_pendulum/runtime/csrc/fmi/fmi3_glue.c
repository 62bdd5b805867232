/* FMI 3.0 glue of the native FMU: Co-Simulation and Model Exchange, and nothing else.
 *
 * FMI 3.0's API, its state machine, its FMU states and its logging, on the same model
 * contract as fmi2_glue.c (fmu_model.h); from fmu_config.h it takes only the instantiation
 * token (CP_GUID), the log categories and the variables' names. Every entry point checks its
 * instance, its state and its arguments; a refused value is fmi3Error with the model's
 * message naming it and is not taken; a step that cannot complete is fmi3Discard with the
 * model's diagnosis; messages go through the host's logMessage callback. Nothing is allocated
 * after instantiation but what a host asks for (FMU states).
 *
 * What this FMU does not have, as its model description says: no clocks and no events (no
 * event indicators, hasEventMode="false", providesEvaluateDiscreteStates="false"), no
 * Scheduled Execution, no configuration modes (no tunable structural parameters), variables of
 * the types Float64 and Int32 only (the others are refused) and, for a model with arrays, the
 * UInt64 structural parameter of their dimension (fmi3_arrays.h, generated for every model: an
 * array's value reference stands for the model's scalars in order; a model without arrays has
 * no structural parameter and no UInt64 variable), no output derivatives, no intermediate
 * update. Early return (fmi3DoStep's earlyReturn, lastSuccessfulTime) and the adjoint
 * derivative are marked EARLY RETURN and ADJOINT below.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

#include "fmi3_arrays.h"
#include "fmi_layer.h"
#include "fmu_config.h"
#include "fmu_model.h"

/* ---- FMI 3.0's state machine ------------------------------------------------------------- */

/* Where an instance is: one bit per state. FMI 3.0's other states are never entered: start/end
 * has no instance; configurationMode and reconfigurationMode need a tunable structural
 * parameter (there is none); clockActivationMode and intermediateUpdateMode need Scheduled
 * Execution or intermediate update (not provided); eventMode in Co-Simulation needs
 * hasEventMode (false: fmi3InstantiateCoSimulation refuses eventModeUsed). A refused call takes
 * nothing and leaves the instance in its state; fmi3Fatal is never returned. A discarded step
 * leaves a Co-Simulation instance in stepMode at the step's start (lastSuccessfulTime). */
enum {
    INSTANTIATED = 1 << 0, INITIALIZATION = 1 << 1, EVENT_MODE = 1 << 2, STEP_MODE = 1 << 3,
    CONTINUOUS_TIME = 1 << 4, TERMINATED = 1 << 5
};
static const char *const state_names[] = {  /* by bit, as the standard names them */
    "Instantiated", "Initialization Mode", "Event Mode", "Step Mode", "Continuous-Time Mode",
    "Terminated"};
#define BEFORE_INIT (INSTANTIATED | INITIALIZATION)
#define CO_SIMULATION_STATES (BEFORE_INIT | STEP_MODE | TERMINATED)
#define MODEL_EXCHANGE_STATES (BEFORE_INIT | EVENT_MODE | CONTINUOUS_TIME | TERMINATED)
/* Where values are defined: initialization mode and after (the getters' rows). */
#define CS_VALUES (INITIALIZATION | STEP_MODE | TERMINATED)
#define ME_VALUES (INITIALIZATION | EVENT_MODE | CONTINUOUS_TIME | TERMINATED)
#define NO_STATE 0

/* The states each function may be called in, Co-Simulation and Model Exchange: FMI 3.0's
 * state machines (sections 3.2 and 4.2), one row per function, restricted to the states this
 * FMU enters; the instance's interface picks the column. Where the standard allows a call in
 * a state only for some variables (inputs and tunable parameters after initialization), the
 * state is in and the model checks the variable. fmi3GetVersion and the fmi3Instantiate*
 * functions take no instance; fmi3FreeInstance, fmi3Reset and fmi3FreeFMUState are allowed in
 * every state and never refused, whatever the instance holds. */
/*                                                Co-Simulation                 Model Exchange */
#define STATES_fmi3SetDebugLogging                CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi3EnterInitializationMode        INSTANTIATED,                 INSTANTIATED
#define STATES_fmi3ExitInitializationMode         INITIALIZATION,               INITIALIZATION
#define STATES_fmi3EnterEventMode                 STEP_MODE,                    CONTINUOUS_TIME
#define STATES_fmi3Terminate                      STEP_MODE,                    (EVENT_MODE | CONTINUOUS_TIME)
#define STATES_fmi3GetFloat64                     CS_VALUES,                    ME_VALUES
#define STATES_fmi3GetInt32                       CS_VALUES,                    ME_VALUES
#define STATES_fmi3GetDimension                   (CO_SIMULATION_STATES),       (MODEL_EXCHANGE_STATES)  /* a structural parameter: also before initialization */
#define STATES_fmi3GetOther                       CS_VALUES,                    ME_VALUES  /* Float32, Int8, ..., Binary */
#define STATES_fmi3SetFloat64                     (BEFORE_INIT | STEP_MODE),    (BEFORE_INIT | EVENT_MODE | CONTINUOUS_TIME)
#define STATES_fmi3SetInt32                       (BEFORE_INIT | STEP_MODE),    (BEFORE_INIT | EVENT_MODE)
#define STATES_fmi3SetOther                       (BEFORE_INIT | STEP_MODE),    (BEFORE_INIT | EVENT_MODE)
#define STATES_fmi3GetClock                       NO_STATE,                     EVENT_MODE
#define STATES_fmi3SetClock                       NO_STATE,                     EVENT_MODE
#define STATES_fmi3Intervals                      (INITIALIZATION | STEP_MODE), (INITIALIZATION | EVENT_MODE)  /* Get/SetInterval*, Get/SetShift* */
#define STATES_fmi3GetNumberOfVariableDependencies CO_SIMULATION_STATES,        MODEL_EXCHANGE_STATES
#define STATES_fmi3GetVariableDependencies        CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi3GetFMUState                    CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi3SetFMUState                    CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi3SerializedFMUStateSize         CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi3SerializeFMUState              CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi3DeserializeFMUState            CO_SIMULATION_STATES,         MODEL_EXCHANGE_STATES
#define STATES_fmi3GetDirectionalDerivative       CS_VALUES,                    ME_VALUES
#define STATES_fmi3GetAdjointDerivative           CS_VALUES,                    ME_VALUES
#define STATES_fmi3EnterConfigurationMode         (INSTANTIATED | STEP_MODE),   (INSTANTIATED | EVENT_MODE)
#define STATES_fmi3ExitConfigurationMode          NO_STATE,                     NO_STATE  /* (re)configuration mode only */
#define STATES_fmi3EvaluateDiscreteStates         NO_STATE,                     NO_STATE  /* providesEvaluateDiscreteStates is false */
#define STATES_fmi3UpdateDiscreteStates           NO_STATE,                     EVENT_MODE
/* Model Exchange only */
#define STATES_fmi3EnterContinuousTimeMode        NO_STATE,                     EVENT_MODE
#define STATES_fmi3CompletedIntegratorStep        NO_STATE,                     CONTINUOUS_TIME
#define STATES_fmi3SetTime                        NO_STATE,                     (EVENT_MODE | CONTINUOUS_TIME)
#define STATES_fmi3SetContinuousStates            NO_STATE,                     CONTINUOUS_TIME
#define STATES_fmi3GetContinuousStateDerivatives  NO_STATE,                     ME_VALUES
#define STATES_fmi3GetEventIndicators             NO_STATE,                     ME_VALUES
#define STATES_fmi3GetContinuousStates            NO_STATE,                     ME_VALUES
#define STATES_fmi3GetNominalsOfContinuousStates  NO_STATE,                     MODEL_EXCHANGE_STATES
#define STATES_fmi3GetNumberOfEventIndicators     NO_STATE,                     MODEL_EXCHANGE_STATES
#define STATES_fmi3GetNumberOfContinuousStates    NO_STATE,                     MODEL_EXCHANGE_STATES
/* Co-Simulation only */
#define STATES_fmi3EnterStepMode                  NO_STATE,                     NO_STATE  /* from eventMode: never entered */
#define STATES_fmi3GetOutputDerivatives           (STEP_MODE | TERMINATED),     NO_STATE
#define STATES_fmi3DoStep                         STEP_MODE,                    NO_STATE
#define STATES_fmi3ActivateModelPartition         NO_STATE,                     NO_STATE  /* Scheduled Execution only */

enum { CO_SIMULATION = 1, MODEL_EXCHANGE = 2 };

/* What FMI 3.0 keeps of an instance besides the model's data: where it is in the state
 * machine, its time, and the last time a step reached. */
typedef FmiMachine Machine;

/* An FMU state, as fmi3GetFMUState saves it and fmi3SerializeFMUState writes it after its
 * header: the machine, then the model's data (model_sizes.data_size bytes). */
typedef struct {
    Machine machine;
    double model[];               /* a ModelData; double: its alignment (fmu_model.h) */
} SavedState;

typedef struct {
    Machine machine;
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback logger;
    int type;                     /* CO_SIMULATION or MODEL_EXCHANGE */
    int early_return_allowed;     /* fmi3InstantiateCoSimulation's earlyReturnAllowed */
    unsigned logging;             /* bit k: log category cp_log_categories[k] is on */
    char discarded[2048];         /* the last discarded step's diagnosis */
    double model[];               /* the model's data, in the instance's allocation */
} Instance;

/* FMI 3.0's independent variable, time: its value reference follows every variable's
 * (fmi3_arrays.h, builder/fmi3.py). */
#define VR_TIME ((fmi3ValueReference)CP_VR_TIME)
#define MAX_ELEMENTS 4096  /* of one call's expanded value references (directional derivatives) */

#define ALL_CATEGORIES ((1u << CP_NLOG) - 1)
#define MODEL(inst) ((ModelData *)(inst)->model)
#define MESSAGE_SIZE 1024
#define SAVED_SIZE (sizeof(SavedState) + model_sizes.data_size)

/* A layer's message, formatted by fmi_vlog, to the host's logger. */
static void emit(void *context, int status, int category, const char *text)
{
    Instance *inst = context;
    inst->logger(inst->environment, (fmi3Status)status, cp_log_categories[category], text);
}

/* A message through the host's logMessage, in one of the model description's log categories.
 * Errors are always reported; other messages (fmi3Discard's diagnoses) only when their
 * category is on (loggingOn at instantiation, then fmi3SetDebugLogging). */
static void log_message(Instance *inst, fmi3Status status, int category, const char *format, ...)
{
    if (!inst->logger) return;
    va_list args;
    va_start(args, format);
    fmi_vlog(emit, inst, status, status != fmi3OK && status != fmi3Discard, inst->logging,
             category, format, args);
    va_end(args);
}

#define REFUSE(inst, ...) (log_message((inst), fmi3Error, CP_LOG_STATUS_ERROR, __VA_ARGS__), fmi3Error)

#define CHECKED(c, function) checked((c), #function, STATES_##function)
#define CHECKED_AS(c, function, row) checked((c), function, STATES_##row)

static Instance *checked(fmi3Instance c, const char *function, int co_simulation, int model_exchange)
{
    Instance *inst = (Instance *)c;
    if (!inst) return NULL;
    const int cs = inst->type == CO_SIMULATION;
    const int allowed = cs ? co_simulation : model_exchange;
    if (inst->machine.state & allowed) return inst;
    const char *state = fmi_state_name(inst->machine.state, state_names,
                                       (int)(sizeof state_names / sizeof state_names[0]));
    const char *why = fmi_refusal_reason(
        cs, allowed, cs ? model_exchange : co_simulation,
        ": only in a state this FMU never enters (no events, clocks or configuration)", "");
    log_message(inst, fmi3Error, CP_LOG_STATUS_ERROR, "%s is not allowed in %s (FMI 3.0, %s)%s",
                function, state, cs ? "Co-Simulation" : "Model Exchange", why);
    return NULL;
}

static void reset(Instance *inst)
{
    fmi_machine_reset(&inst->machine, INSTANTIATED);
    inst->discarded[0] = '\0';
    model_reset(MODEL(inst));
}

static fmi3Status discard(Instance *inst, const char *message)
{
    log_message(inst, fmi3Discard, CP_LOG_STATUS_DISCARD, "%s", message);
    return fmi3Discard;
}

/* ---- common functions ------------------------------------------------------------------ */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    /* As fmi2SetDebugLogging (FMI 3.0, section 2.3.1 keeps its rules): with nCategories = 0,
     * loggingOn applies to every category; with a list, loggingOn makes the listed ones the
     * categories in force and off turns the listed ones off. An unknown name is refused. */
    Instance *inst = CHECKED(c, fmi3SetDebugLogging);
    if (!inst) return fmi3Error;
    char refusal[4096];
    if (fmi_set_logging(&inst->logging, loggingOn, nCategories, categories, cp_log_categories,
                        CP_NLOG, "fmi3SetDebugLogging", refusal, sizeof refusal))
        return REFUSE(inst, "%s", refusal);
    return fmi3OK;
}

static Instance *instantiate(const char *function, int type, fmi3String instanceName,
                             fmi3String instantiationToken, fmi3Boolean loggingOn,
                             fmi3InstanceEnvironment environment, fmi3LogMessageCallback logger,
                             const char *problem)
{
    /* FMI 3.0 gives the FMU no memory callbacks: its own calloc, freed by fmi3FreeInstance. */
    Instance *inst = calloc(1, sizeof(Instance) + model_sizes.data_size);
    if (!inst) return NULL;
    inst->environment = environment;
    inst->logger = logger;
    inst->type = type;
    inst->logging = loggingOn ? ALL_CATEGORIES : 0;
    if (!problem && (!instanceName || !*instanceName)) problem = "instanceName is empty";
    if (!problem && (!instantiationToken || strcmp(instantiationToken, CP_GUID) != 0))
        problem = "instantiationToken is not this FMU's: the model description and binary do "
                  "not match";
    if (problem) {
        log_message(inst, fmi3Error, CP_LOG_STATUS_ERROR, "%s: %s", function, problem);
        free(inst);
        return NULL;
    }
    reset(inst);
    return inst;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)resourcePath, (void)visible;
    return instantiate("fmi3InstantiateModelExchange", MODEL_EXCHANGE, instanceName,
                       instantiationToken, loggingOn, instanceEnvironment, logMessage, NULL);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible,
                                         fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate)
{
    (void)resourcePath, (void)visible, (void)requiredIntermediateVariables, (void)intermediateUpdate;
    const char *problem = NULL;
    if (eventModeUsed) problem = "eventModeUsed: this FMU has no events (hasEventMode is false)";
    else if (nRequiredIntermediateVariables)
        problem = "requiredIntermediateVariables: this FMU provides no intermediate update";
    Instance *inst = instantiate("fmi3InstantiateCoSimulation", CO_SIMULATION, instanceName,
                                 instantiationToken, loggingOn, instanceEnvironment, logMessage,
                                 problem);
    if (inst) inst->early_return_allowed = earlyReturnAllowed ? 1 : 0;
    return inst;
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible;
    (void)loggingOn, (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    if (logMessage)
        logMessage(instanceEnvironment, fmi3Error, cp_log_categories[CP_LOG_STATUS_ERROR],
                   "fmi3InstantiateScheduledExecution: this FMU provides Co-Simulation and "
                   "Model Exchange only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance c)
{
    free(c);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    (void)stopTimeDefined, (void)stopTime;
    Instance *inst = CHECKED(c, fmi3EnterInitializationMode);
    if (!inst) return fmi3Error;
    char message[MESSAGE_SIZE];
    if (toleranceDefined && model_tolerance_refusal(tolerance, message, sizeof message))
        return REFUSE(inst, "fmi3EnterInitializationMode: %s", message);
    if (!isfinite(startTime))
        return REFUSE(inst, "fmi3EnterInitializationMode: startTime = %g: must be finite", startTime);
    model_set_tolerance(MODEL(inst), toleranceDefined ? tolerance : 0.0);
    inst->machine.time = inst->machine.last_successful_time = startTime;
    inst->machine.state = INITIALIZATION;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance c)
{
    Instance *inst = CHECKED(c, fmi3ExitInitializationMode);
    if (!inst) return fmi3Error;
    model_initialize(MODEL(inst));
    inst->machine.state = inst->type == CO_SIMULATION ? STEP_MODE : EVENT_MODE;
    return fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance c)
{
    Instance *inst = CHECKED(c, fmi3EnterEventMode);
    if (!inst) return fmi3Error;
    if (inst->type == CO_SIMULATION)  /* eventModeUsed is refused at instantiation */
        return REFUSE(inst, "fmi3EnterEventMode: this FMU has no event mode in Co-Simulation "
                      "(hasEventMode is false)");
    inst->machine.state = EVENT_MODE;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance c)
{
    Instance *inst = CHECKED(c, fmi3Terminate);
    if (!inst) return fmi3Error;
    inst->machine.state = TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance c)
{
    Instance *inst = (Instance *)c;  /* allowed in every state: whatever it holds, never refused */
    if (!inst) return fmi3Error;
    reset(inst);
    return fmi3OK;
}

/* ---- getting and setting values ------------------------------------------------------- */

static int initialized(const Instance *inst)
{
    return !(inst->machine.state & BEFORE_INIT);
}

/* The model contract's Reals behind an FMI 3.0 value reference: an array's members in link
 * order (fmi3_arrays.h), or the variable itself; 0 for a member other than an array's first,
 * which is no FMI 3.0 variable. */
static size_t elements(fmi3ValueReference vr, const unsigned **members)
{
    *members = NULL;
#if CP_NARRAY  /* a model without arrays has no tables of them */
    for (int a = 0; a < CP_NARRAY; a++)
        if (cp_array_vr[a] == vr) {
            *members = cp_array_members[a];
            return CP_DIMENSION;
        }
#endif
    return vr < CP_VR_TIME && cp_array_hidden[vr] ? 0 : 1;
}

#define ELEMENT(vr, members, e) ((members) ? (members)[e] : (vr))

/* How many values the value references stand for (an array: its dimension), or refused: a value
 * reference that is a hidden array member, or nValues that is not that count. */
static fmi3Status check_values(Instance *inst, const char *function, const fmi3ValueReference vr[],
                               size_t nvr, const void *values, size_t nValues)
{
    if (nvr && (!vr || !values)) return REFUSE(inst, "%s: valueReferences or values is NULL", function);
    size_t total = 0;
    for (size_t k = 0; k < nvr; k++) {
        const unsigned *members;
        const size_t n = elements(vr[k], &members);
        if (!n)
            return REFUSE(inst, "%s: value reference %u is not a variable (it is %s, an element of "
                          "an array: use the array's value reference)", function, vr[k],
                          cp_variable_name(vr[k]));
        total += n;
    }
    if (nValues != total)
        return REFUSE(inst, "%s: nValues = %zu, but the %zu value references have %zu values",
                      function, nValues, nvr, total);
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Float64 values[], size_t nValues)
{
    Instance *inst = CHECKED(c, fmi3GetFloat64);
    if (!inst) return fmi3Error;
    if (check_values(inst, "fmi3GetFloat64", vr, nvr, values, nValues)) return fmi3Error;
    char message[MESSAGE_SIZE];
    size_t j = 0;
    for (size_t k = 0; k < nvr; k++) {
        if (vr[k] == VR_TIME) {
            values[j++] = inst->machine.time;
            continue;
        }
        const unsigned *members;
        const size_t n = elements(vr[k], &members);
        for (size_t e = 0; e < n; e++, j++) {
            const unsigned u = ELEMENT(vr[k], members, e);
            switch (model_get_real(MODEL(inst), u, &values[j], inst->machine.time, message,
                                   sizeof message)) {
            case MODEL_OK: break;
            case MODEL_DISCARD: return discard(inst, message);
            case MODEL_REFUSED: return REFUSE(inst, "fmi3GetFloat64: %s", message);
            case MODEL_NO_VARIABLE:
                return REFUSE(inst, "fmi3GetFloat64: value reference %u is not a Float64 variable",
                              vr[k]);
            }
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues)
{
    Instance *inst = CHECKED(c, fmi3SetFloat64);
    if (!inst) return fmi3Error;
    if (check_values(inst, "fmi3SetFloat64", vr, nvr, values, nValues)) return fmi3Error;
    char message[MESSAGE_SIZE];
    for (size_t k = 0, j = 0; k < nvr; k++) {  /* all checked before any is taken */
        if (vr[k] == VR_TIME)
            return REFUSE(inst, "fmi3SetFloat64: time is the independent variable; it is set "
                          "by fmi3EnterInitializationMode, fmi3SetTime and fmi3DoStep");
        const unsigned *members;
        const size_t n = elements(vr[k], &members);
        for (size_t e = 0; e < n; e++, j++) {
            ModelStatus status = model_check_real(MODEL(inst), ELEMENT(vr[k], members, e), values[j],
                                                  initialized(inst), message, sizeof message);
            if (status == MODEL_NO_VARIABLE)
                return REFUSE(inst, "fmi3SetFloat64: value reference %u is not a Float64 variable",
                              vr[k]);
            if (status != MODEL_OK) return REFUSE(inst, "%s", message);
        }
    }
    for (size_t k = 0, j = 0; k < nvr; k++) {
        const unsigned *members;
        const size_t n = elements(vr[k], &members);
        for (size_t e = 0; e < n; e++, j++)
            model_set_real(MODEL(inst), ELEMENT(vr[k], members, e), values[j]);
    }
    return fmi3OK;
}

/* Int32 and UInt64: no arrays (fmi3_arrays.h's are Float64). */
static fmi3Status check_scalars(Instance *inst, const char *function, const void *vr, size_t nvr,
                                const void *values, size_t nValues)
{
    if (nvr && (!vr || !values)) return REFUSE(inst, "%s: valueReferences or values is NULL", function);
    if (nValues != nvr)
        return REFUSE(inst, "%s: nValues = %zu, but the %zu value references have %zu values",
                      function, nValues, nvr, nvr);
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Int32 values[], size_t nValues)
{
    Instance *inst = CHECKED(c, fmi3GetInt32);
    if (!inst) return fmi3Error;
    if (check_scalars(inst, "fmi3GetInt32", vr, nvr, values, nValues)) return fmi3Error;
    for (size_t k = 0; k < nvr; k++) {
        int value;
        if (model_get_integer(MODEL(inst), vr[k], &value) != MODEL_OK)
            return REFUSE(inst, "fmi3GetInt32: value reference %u is not an Int32 variable", vr[k]);
        values[k] = value;
    }
    return fmi3OK;
}

fmi3Status fmi3SetInt32(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Int32 values[], size_t nValues)
{
    Instance *inst = CHECKED(c, fmi3SetInt32);
    if (!inst) return fmi3Error;
    if (check_scalars(inst, "fmi3SetInt32", vr, nvr, values, nValues)) return fmi3Error;
    char message[MESSAGE_SIZE];
    for (size_t k = 0; k < nvr; k++) {  /* all checked before any is taken */
        ModelStatus status = model_check_integer(MODEL(inst), vr[k], values[k], initialized(inst),
                                                 message, sizeof message);
        if (status == MODEL_NO_VARIABLE)
            return REFUSE(inst, "fmi3SetInt32: value reference %u is not an Int32 variable", vr[k]);
        if (status != MODEL_OK) return REFUSE(inst, "%s", message);
    }
    for (size_t k = 0; k < nvr; k++) model_set_integer(MODEL(inst), vr[k], values[k]);
    return fmi3OK;
}

/* The other types: the model contract has none, so any value reference is refused. */
static fmi3Status no_variables(Instance *inst, const char *function, const char *type,
                               const fmi3ValueReference vr[], size_t nvr)
{
    if (!inst) return fmi3Error;
    return nvr ? REFUSE(inst, "%s: value reference %u: this FMU has no %s variables", function,
                        vr ? vr[0] : 0, type) : fmi3OK;
}

#define NO_VARIABLES(function, row, type, value_type)                                          \
    fmi3Status function(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,             \
                        value_type values[], size_t nValues)                                   \
    {                                                                                          \
        (void)values, (void)nValues;                                                           \
        return no_variables(CHECKED_AS(c, #function, row), #function, type, vr, nvr);          \
    }
NO_VARIABLES(fmi3GetFloat32, fmi3GetOther, "Float32", fmi3Float32)
NO_VARIABLES(fmi3GetInt8, fmi3GetOther, "Int8", fmi3Int8)
NO_VARIABLES(fmi3GetUInt8, fmi3GetOther, "UInt8", fmi3UInt8)
NO_VARIABLES(fmi3GetInt16, fmi3GetOther, "Int16", fmi3Int16)
NO_VARIABLES(fmi3GetUInt16, fmi3GetOther, "UInt16", fmi3UInt16)
NO_VARIABLES(fmi3GetUInt32, fmi3GetOther, "UInt32", fmi3UInt32)
NO_VARIABLES(fmi3GetInt64, fmi3GetOther, "Int64", fmi3Int64)
NO_VARIABLES(fmi3GetBoolean, fmi3GetOther, "Boolean", fmi3Boolean)
NO_VARIABLES(fmi3GetString, fmi3GetOther, "String", fmi3String)
NO_VARIABLES(fmi3SetFloat32, fmi3SetOther, "Float32", const fmi3Float32)
NO_VARIABLES(fmi3SetInt8, fmi3SetOther, "Int8", const fmi3Int8)
NO_VARIABLES(fmi3SetUInt8, fmi3SetOther, "UInt8", const fmi3UInt8)
NO_VARIABLES(fmi3SetInt16, fmi3SetOther, "Int16", const fmi3Int16)
NO_VARIABLES(fmi3SetUInt16, fmi3SetOther, "UInt16", const fmi3UInt16)
NO_VARIABLES(fmi3SetUInt32, fmi3SetOther, "UInt32", const fmi3UInt32)
NO_VARIABLES(fmi3SetInt64, fmi3SetOther, "Int64", const fmi3Int64)
NO_VARIABLES(fmi3SetBoolean, fmi3SetOther, "Boolean", const fmi3Boolean)
NO_VARIABLES(fmi3SetString, fmi3SetOther, "String", const fmi3String)

#ifdef CP_VR_DIMENSION
/* UInt64: only the structural parameter of the arrays' dimension, fixed by the build
 * (fmi3_arrays.h: its value reference, value and refusal). */
fmi3Status fmi3GetUInt64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                         fmi3UInt64 values[], size_t nValues)
{
    Instance *inst = CHECKED_AS(c, "fmi3GetUInt64", fmi3GetDimension);
    if (!inst) return fmi3Error;
    if (check_scalars(inst, "fmi3GetUInt64", vr, nvr, values, nValues)) return fmi3Error;
    for (size_t k = 0; k < nvr; k++) {
        if (vr[k] != CP_VR_DIMENSION)
            return REFUSE(inst, "fmi3GetUInt64: value reference %u is not a UInt64 variable", vr[k]);
        values[k] = CP_DIMENSION;
    }
    return fmi3OK;
}

fmi3Status fmi3SetUInt64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3UInt64 values[], size_t nValues)
{
    Instance *inst = CHECKED_AS(c, "fmi3SetUInt64", fmi3SetOther);
    if (!inst) return fmi3Error;
    if (check_scalars(inst, "fmi3SetUInt64", vr, nvr, values, nValues)) return fmi3Error;
    for (size_t k = 0; k < nvr; k++) {
        if (vr[k] != CP_VR_DIMENSION)
            return REFUSE(inst, "fmi3SetUInt64: value reference %u is not a UInt64 variable", vr[k]);
        return REFUSE(inst, CP_DIMENSION_REFUSAL, (unsigned long long)values[k]);
    }
    return fmi3OK;
}
#else  /* no structural parameter: no UInt64 variable */
NO_VARIABLES(fmi3GetUInt64, fmi3GetOther, "UInt64", fmi3UInt64)
NO_VARIABLES(fmi3SetUInt64, fmi3SetOther, "UInt64", const fmi3UInt64)
#endif

fmi3Status fmi3GetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues)
{
    (void)valueSizes, (void)values, (void)nValues;
    return no_variables(CHECKED_AS(c, "fmi3GetBinary", fmi3GetOther), "fmi3GetBinary", "Binary", vr, nvr);
}

fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues)
{
    (void)valueSizes, (void)values, (void)nValues;
    return no_variables(CHECKED_AS(c, "fmi3SetBinary", fmi3SetOther), "fmi3SetBinary", "Binary", vr, nvr);
}

/* ---- clocks: none ------------------------------------------------------------------------ */

fmi3Status fmi3GetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[])
{
    (void)values;
    return no_variables(CHECKED(c, fmi3GetClock), "fmi3GetClock", "Clock", vr, nvr);
}

fmi3Status fmi3SetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[])
{
    (void)values;
    return no_variables(CHECKED(c, fmi3SetClock), "fmi3SetClock", "Clock", vr, nvr);
}

#define NO_CLOCKS(function, unused, ...)                                                       \
    fmi3Status function(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, __VA_ARGS__) \
    {                                                                                          \
        (void)unused;                                                                          \
        return no_variables(CHECKED_AS(c, #function, fmi3Intervals), #function, "Clock", vr, nvr); \
    }
NO_CLOCKS(fmi3GetIntervalDecimal, ((void)intervals, qualifiers), fmi3Float64 intervals[],
          fmi3IntervalQualifier qualifiers[])
NO_CLOCKS(fmi3GetIntervalFraction, ((void)counters, (void)resolutions, qualifiers),
          fmi3UInt64 counters[], fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[])
NO_CLOCKS(fmi3GetShiftDecimal, shifts, fmi3Float64 shifts[])
NO_CLOCKS(fmi3GetShiftFraction, ((void)counters, resolutions), fmi3UInt64 counters[],
          fmi3UInt64 resolutions[])
NO_CLOCKS(fmi3SetIntervalDecimal, intervals, const fmi3Float64 intervals[])
NO_CLOCKS(fmi3SetIntervalFraction, ((void)counters, resolutions), const fmi3UInt64 counters[],
          const fmi3UInt64 resolutions[])
NO_CLOCKS(fmi3SetShiftDecimal, shifts, const fmi3Float64 shifts[])
NO_CLOCKS(fmi3SetShiftFraction, ((void)counters, resolutions), const fmi3UInt64 counters[],
          const fmi3UInt64 resolutions[])

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance c)
{
    CHECKED(c, fmi3EvaluateDiscreteStates);  /* providesEvaluateDiscreteStates is false: logs why */
    return fmi3Error;
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime)
{
    Instance *inst = CHECKED(c, fmi3UpdateDiscreteStates);
    if (!inst) return fmi3Error;
    if (!discreteStatesNeedUpdate || !terminateSimulation || !nominalsOfContinuousStatesChanged
        || !valuesOfContinuousStatesChanged || !nextEventTimeDefined || !nextEventTime)
        return REFUSE(inst, "fmi3UpdateDiscreteStates: a pointer is NULL");
    /* no events: nothing changes, nothing to wait for */
    *discreteStatesNeedUpdate = *terminateSimulation = *nominalsOfContinuousStatesChanged = fmi3False;
    *valuesOfContinuousStatesChanged = *nextEventTimeDefined = fmi3False;
    *nextEventTime = 0.0;
    return fmi3OK;
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance c)
{
    Instance *inst = CHECKED(c, fmi3EnterConfigurationMode);
    if (!inst) return fmi3Error;
    return REFUSE(inst, "fmi3EnterConfigurationMode: this FMU has no tunable structural parameters");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance c)
{
    CHECKED(c, fmi3ExitConfigurationMode);  /* never in (re)configuration mode: logs why */
    return fmi3Error;
}

/* ---- variable dependencies: in the model description ------------------------------------ */

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance c, fmi3ValueReference valueReference,
                                               size_t *nDependencies)
{
    (void)valueReference, (void)nDependencies;
    Instance *inst = CHECKED(c, fmi3GetNumberOfVariableDependencies);
    if (!inst) return fmi3Error;
    return REFUSE(inst, "fmi3GetNumberOfVariableDependencies: not provided "
                  "(providesPerElementDependencies is false; the ModelStructure says them)");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance c, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies)
{
    (void)dependent, (void)elementIndicesOfDependent, (void)independents;
    (void)elementIndicesOfIndependents, (void)dependencyKinds, (void)nDependencies;
    Instance *inst = CHECKED(c, fmi3GetVariableDependencies);
    if (!inst) return fmi3Error;
    return REFUSE(inst, "fmi3GetVariableDependencies: not provided "
                  "(providesPerElementDependencies is false; the ModelStructure says them)");
}

/* ---- the FMU state ---------------------------------------------------------------------- */

#define STATE_MAGIC 0x43504633u  /* "CPF3": a serialized SavedState of this build */

#define HEADER_SIZE fmi_state_header_size(CP_GUID)

static const char *invalid_state(int type, const SavedState *s, char *message, size_t size)
{
    const unsigned states = type == CO_SIMULATION ? CO_SIMULATION_STATES : MODEL_EXCHANGE_STATES;
    const unsigned bits = (unsigned)s->machine.state;
    if (!(bits & states) || (bits & (bits - 1))) {
        snprintf(message, size, "instance state = %d: not one state a%s instance can be in",
                 s->machine.state, type == CO_SIMULATION ? " Co-Simulation" : " Model Exchange");
        return message;
    }
    if (model_invalid((const ModelData *)s->model, message, size)) return message;
    const struct { const char *name; double value; } times[] = {
        {"time", s->machine.time}, {"last_successful_time", s->machine.last_successful_time}};
    for (size_t k = 0; k < sizeof times / sizeof times[0]; k++)
        if (!isfinite(times[k].value)) {
            snprintf(message, size, "%s = %g: must be finite", times[k].name, times[k].value);
            return message;
        }
    return NULL;
}

fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState *FMUState)
{
    Instance *inst = CHECKED(c, fmi3GetFMUState);
    if (!inst) return fmi3Error;
    if (!FMUState) return REFUSE(inst, "fmi3GetFMUState: FMUState is NULL");
    SavedState *copy = *FMUState ? *FMUState : calloc(1, SAVED_SIZE);
    if (!copy) return REFUSE(inst, "fmi3GetFMUState: out of memory");
    copy->machine = inst->machine;
    memcpy(copy->model, inst->model, model_sizes.data_size);
    *FMUState = copy;
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState FMUState)
{
    Instance *inst = CHECKED(c, fmi3SetFMUState);
    if (!inst) return fmi3Error;
    if (!FMUState) return REFUSE(inst, "fmi3SetFMUState: FMUState is NULL");
    char message[MESSAGE_SIZE];
    if (invalid_state(inst->type, FMUState, message, sizeof message))
        return REFUSE(inst, "fmi3SetFMUState: the state's %s", message);
    const SavedState *saved = FMUState;
    inst->machine = saved->machine;
    memcpy(inst->model, saved->model, model_sizes.data_size);
    inst->discarded[0] = '\0';
    return fmi3OK;
}

fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState *FMUState)
{
    Instance *inst = (Instance *)c;  /* allowed in every state: never refused */
    if (!inst) return fmi3Error;
    if (!FMUState) return REFUSE(inst, "fmi3FreeFMUState: FMUState is NULL");
    free(*FMUState);
    *FMUState = NULL;
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState FMUState, size_t *size)
{
    Instance *inst = CHECKED(c, fmi3SerializedFMUStateSize);
    if (!inst) return fmi3Error;
    if (!FMUState || !size) return REFUSE(inst, "fmi3SerializedFMUStateSize: a pointer is NULL");
    *size = HEADER_SIZE + SAVED_SIZE;
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size)
{
    Instance *inst = CHECKED(c, fmi3SerializeFMUState);
    if (!inst) return fmi3Error;
    if (!FMUState || !serializedState) return REFUSE(inst, "fmi3SerializeFMUState: a pointer is NULL");
    if (size < HEADER_SIZE + SAVED_SIZE)
        return REFUSE(inst, "fmi3SerializeFMUState: %zu bytes are too few; "
                      "fmi3SerializedFMUStateSize says how many", size);
    fmi_state_header_write(serializedState, STATE_MAGIC, (unsigned)SAVED_SIZE, CP_GUID);
    memcpy(serializedState + HEADER_SIZE, FMUState, SAVED_SIZE);
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState)
{
    Instance *inst = CHECKED(c, fmi3DeserializeFMUState);
    if (!inst) return fmi3Error;
    if (!serializedState || !FMUState) return REFUSE(inst, "fmi3DeserializeFMUState: a pointer is NULL");
    if (size != HEADER_SIZE + SAVED_SIZE)
        return REFUSE(inst, "fmi3DeserializeFMUState: %zu bytes are not a state of this FMU", size);
    if (!fmi_state_header_matches(serializedState, STATE_MAGIC, (unsigned)SAVED_SIZE, CP_GUID))
        return REFUSE(inst, "fmi3DeserializeFMUState: the bytes are not a state of this FMU "
                      "(another model, build or version)");
    SavedState *copy = calloc(1, SAVED_SIZE);  /* checked in a copy, taken only if it passes */
    if (!copy) return REFUSE(inst, "fmi3DeserializeFMUState: out of memory");
    memcpy(copy, serializedState + HEADER_SIZE, SAVED_SIZE);
    char message[MESSAGE_SIZE];
    if (invalid_state(inst->type, copy, message, sizeof message)) {
        free(copy);
        return REFUSE(inst, "fmi3DeserializeFMUState: the state's %s", message);
    }
    if (*FMUState) {
        memcpy(*FMUState, copy, SAVED_SIZE);
        free(copy);
    } else {
        *FMUState = copy;
    }
    return fmi3OK;
}

/* ---- partial derivatives ---------------------------------------------------------------- */

/* The contract's scalars behind value references into out (an array: its members in link
 * order, fmi3_arrays.h), *count of them; or refused, naming the function. */
static fmi3Status expand(Instance *inst, const char *function, const fmi3ValueReference refs[],
                         size_t n_refs, unsigned out[], size_t *count)
{
    *count = 0;
    for (size_t k = 0; k < n_refs; k++) {
        const unsigned *members;
        const size_t n = elements(refs[k], &members);
        if (!n)
            return REFUSE(inst, "%s: value reference %u is not a variable (it is %s, an element "
                          "of an array: use the array's value reference)", function, refs[k],
                          cp_variable_name(refs[k]));
        if (*count + n > MAX_ELEMENTS)
            return REFUSE(inst, "%s: more than %d values in one call", function, MAX_ELEMENTS);
        for (size_t e = 0; e < n; e++) out[(*count)++] = ELEMENT(refs[k], members, e);
    }
    return fmi3OK;
}

/* fmi3GetDirectionalDerivative's and (adjoint) fmi3GetAdjointDerivative's checks and call, for
 * the instance inst: the seed is on the knowns (on the unknowns if adjoint), the sensitivity on
 * the other side; arrays stand for their members (fmi3_arrays.h): the contract's scalars. */
static fmi3Status derivative(Instance *inst, const char *function, int adjoint,
                             const fmi3ValueReference unknowns[], size_t nUnknowns,
                             const fmi3ValueReference knowns[], size_t nKnowns,
                             const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                             size_t nSensitivity)
{
    const void *on_unknowns = adjoint ? (const void *)seed : sensitivity;
    const void *on_knowns = adjoint ? (const void *)sensitivity : seed;
    if ((nUnknowns && (!unknowns || !on_unknowns)) || (nKnowns && (!knowns || !on_knowns)))
        return REFUSE(inst, "%s: a pointer is NULL", function);
    unsigned unknown[MAX_ELEMENTS], known[MAX_ELEMENTS];
    size_t n_unknown, n_known;
    if (expand(inst, function, unknowns, nUnknowns, unknown, &n_unknown)
        || expand(inst, function, knowns, nKnowns, known, &n_known))
        return fmi3Error;
    const unsigned *seeded = adjoint ? unknown : known, *sensed = adjoint ? known : unknown;
    const size_t n_seeded = adjoint ? n_unknown : n_known, n_sensed = adjoint ? n_known : n_unknown;
    const char *seeded_side = adjoint ? "unknowns" : "knowns";
    if (nSeed != n_seeded || nSensitivity != n_sensed)
        return REFUSE(inst, "%s: nSeed = %zu and nSensitivity = %zu, but the %s have %zu values "
                      "and the %s %zu", function, nSeed, nSensitivity, seeded_side, n_seeded,
                      adjoint ? "knowns" : "unknowns", n_sensed);
    for (size_t k = 0; k < n_seeded; k++)
        if (!isfinite(seed[k]))
            return REFUSE(inst, "%s: seed of %s = %g: must be finite", function,
                          cp_variable_name(seeded[k]), seed[k]);
    char message[MESSAGE_SIZE];
    switch ((adjoint ? model_adjoint_derivative : model_directional_derivative)(
        MODEL(inst), unknown, n_unknown, known, n_known, seed, sensitivity, inst->machine.time,
        message, sizeof message)) {
    case MODEL_OK: break;
    case MODEL_DISCARD: return discard(inst, message);
    default: return REFUSE(inst, "%s: %s", function, message);
    }
    for (size_t k = 0; k < n_sensed; k++)
        if (!isfinite(sensitivity[k])) {
            log_message(inst, fmi3Discard, CP_LOG_STATUS_DISCARD, "%s: the derivative %s%s is "
                        "not finite at t = %.9g s; check parameters and state", function,
                        adjoint ? "with respect to " : "of ", cp_variable_name(sensed[k]),
                        inst->machine.time);
            return fmi3Discard;
        }
    return fmi3OK;
}

/* sensitivity = J seed (FMI 3.0, section 2.2.11), J the Jacobian of the unknowns with respect to
 * the knowns at the current values: model_directional_derivative. An array stands for its
 * elements: nSeed and nSensitivity count the values, as nValues does. */
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity)
{
    Instance *inst = CHECKED(c, fmi3GetDirectionalDerivative);
    if (!inst) return fmi3Error;
    return derivative(inst, "fmi3GetDirectionalDerivative", 0, unknowns, nUnknowns, knowns,
                      nKnowns, seed, nSeed, sensitivity, nSensitivity);
}

/* ADJOINT: sensitivity = seed^T J (FMI 3.0, section 2.2.11), J as for
 * fmi3GetDirectionalDerivative: model_adjoint_derivative, exact to rounding. By complex step
 * there is no reverse sweep: each known costs one complex evaluation, so a row costs what its
 * directional derivatives cost. An array stands for its elements: nSeed counts the
 * unknowns' values, nSensitivity the knowns'. Its checks are fmi3GetDirectionalDerivative's. */
fmi3Status fmi3GetAdjointDerivative(fmi3Instance c, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity)
{
    Instance *inst = CHECKED(c, fmi3GetAdjointDerivative);
    if (!inst) return fmi3Error;
    return derivative(inst, "fmi3GetAdjointDerivative", 1, unknowns, nUnknowns, knowns, nKnowns,
                      seed, nSeed, sensitivity, nSensitivity);
}

/* ---- Model Exchange ----------------------------------------------------------------------- */

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c)
{
    Instance *inst = CHECKED(c, fmi3EnterContinuousTimeMode);
    if (!inst) return fmi3Error;
    inst->machine.state = CONTINUOUS_TIME;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    Instance *inst = CHECKED(c, fmi3CompletedIntegratorStep);
    if (!inst) return fmi3Error;
    if (!enterEventMode || !terminateSimulation)
        return REFUSE(inst, "fmi3CompletedIntegratorStep: a pointer is NULL");
    *enterEventMode = *terminateSimulation = fmi3False;
    inst->machine.last_successful_time = inst->machine.time;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 time)
{
    Instance *inst = CHECKED(c, fmi3SetTime);
    if (!inst) return fmi3Error;
    if (!isfinite(time)) return REFUSE(inst, "fmi3SetTime: time = %g must be finite", time);
    inst->machine.time = time;  /* the contract's models are autonomous */
    return fmi3OK;
}

static fmi3Status check_states_call(Instance *inst, const void *x, size_t nx, const char *function)
{
    if (!x) return REFUSE(inst, "%s: the array is NULL", function);
    if (nx != (size_t)model_sizes.n_state)
        return REFUSE(inst, "%s: nContinuousStates = %zu, but this FMU has %d continuous states",
                      function, nx, model_sizes.n_state);
    return fmi3OK;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    Instance *inst = CHECKED(c, fmi3SetContinuousStates);
    if (!inst) return fmi3Error;
    if (check_states_call(inst, continuousStates, nContinuousStates, "fmi3SetContinuousStates"))
        return fmi3Error;
    char message[MESSAGE_SIZE];
    if (model_set_states(MODEL(inst), continuousStates, message, sizeof message))
        return REFUSE(inst, "fmi3SetContinuousStates: %s", message);
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 derivatives[],
                                             size_t nContinuousStates)
{
    Instance *inst = CHECKED(c, fmi3GetContinuousStateDerivatives);
    if (!inst) return fmi3Error;
    if (check_states_call(inst, derivatives, nContinuousStates, "fmi3GetContinuousStateDerivatives"))
        return fmi3Error;
    char message[MESSAGE_SIZE];
    if (model_get_derivatives(MODEL(inst), derivatives, inst->machine.time, message, sizeof message)
        != MODEL_OK)
        return discard(inst, message);
    return fmi3OK;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 eventIndicators[], size_t nEventIndicators)
{
    (void)eventIndicators;
    Instance *inst = CHECKED(c, fmi3GetEventIndicators);
    if (!inst) return fmi3Error;
    return nEventIndicators ? REFUSE(inst, "fmi3GetEventIndicators: nEventIndicators = %zu, but "
                                     "this FMU has none", nEventIndicators) : fmi3OK;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    Instance *inst = CHECKED(c, fmi3GetContinuousStates);
    if (!inst) return fmi3Error;
    if (check_states_call(inst, continuousStates, nContinuousStates, "fmi3GetContinuousStates"))
        return fmi3Error;
    model_get_states(MODEL(inst), continuousStates);
    return fmi3OK;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 nominals[],
                                             size_t nContinuousStates)
{
    Instance *inst = CHECKED(c, fmi3GetNominalsOfContinuousStates);
    if (!inst) return fmi3Error;
    if (check_states_call(inst, nominals, nContinuousStates, "fmi3GetNominalsOfContinuousStates"))
        return fmi3Error;
    model_get_nominals(MODEL(inst), nominals);
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t *nEventIndicators)
{
    Instance *inst = CHECKED(c, fmi3GetNumberOfEventIndicators);
    if (!inst) return fmi3Error;
    if (!nEventIndicators) return REFUSE(inst, "fmi3GetNumberOfEventIndicators: a pointer is NULL");
    *nEventIndicators = (size_t)model_sizes.n_event_indicator;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t *nContinuousStates)
{
    Instance *inst = CHECKED(c, fmi3GetNumberOfContinuousStates);
    if (!inst) return fmi3Error;
    if (!nContinuousStates) return REFUSE(inst, "fmi3GetNumberOfContinuousStates: a pointer is NULL");
    *nContinuousStates = (size_t)model_sizes.n_state;
    return fmi3OK;
}

/* ---- Co-Simulation ----------------------------------------------------------------------- */

fmi3Status fmi3EnterStepMode(fmi3Instance c)
{
    CHECKED(c, fmi3EnterStepMode);  /* from eventMode, which Co-Simulation never enters: logs why */
    return fmi3Error;
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                    const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues)
{
    (void)vr, (void)orders, (void)values, (void)nValues;
    Instance *inst = CHECKED(c, fmi3GetOutputDerivatives);
    if (!inst) return fmi3Error;
    return nvr ? REFUSE(inst, "fmi3GetOutputDerivatives: not provided "
                        "(maxOutputDerivativeOrder is 0)") : fmi3OK;
}

/* One communication step. EARLY RETURN: with earlyReturnAllowed (fmi3InstantiateCoSimulation),
 * a step that cannot complete but got somewhere returns early (model_do_step_early): fmi3OK,
 * earlyReturn = true, lastSuccessfulTime the last good internal step (RK45 and DOP853: the last
 * accepted one; RK4: the last completed substep where x' was computed), the state and outputs
 * there, and the diagnosis logged (logStatusDiscard); the importer goes on from there, and a
 * shorter step either completes or is discarded. A step that got nowhere, or any that cannot
 * complete without earlyReturnAllowed, is fmi3Discard with the instance as it was at t
 * (lastSuccessfulTime = t): FMI 3.0's fmi3Discard leaves the FMU in the state before the call,
 * and its earlyReturn only reports a point that was computed successfully, never the error
 * itself (fmi-standard pull request 1845). */
fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    Instance *inst = CHECKED(c, fmi3DoStep);
    if (!inst) return fmi3Error;
    if (!eventHandlingNeeded || !terminateSimulation || !earlyReturn || !lastSuccessfulTime)
        return REFUSE(inst, "fmi3DoStep: a pointer is NULL");
    const double t = currentCommunicationPoint, dt = communicationStepSize;
    if (!(fabs(t - inst->machine.time) <= 1e-9 * fmax(1.0, fabs(t))))
        return REFUSE(inst, "fmi3DoStep: currentCommunicationPoint = %.17g s, but the FMU is "
                      "at t = %.17g s", t, inst->machine.time);
    *eventHandlingNeeded = *terminateSimulation = *earlyReturn = fmi3False;
    double reached = t;
    if (model_do_step_early(MODEL(inst), t, dt, inst->early_return_allowed, &reached,
                            inst->discarded, sizeof inst->discarded) != MODEL_OK) {
        if (!(reached > t)) {
            *lastSuccessfulTime = inst->machine.last_successful_time = inst->machine.time;
            return discard(inst, inst->discarded);
        }
        log_message(inst, fmi3OK, CP_LOG_STATUS_DISCARD, "fmi3DoStep returns early: %s",
                    inst->discarded);
        *earlyReturn = fmi3True;
    }
    inst->discarded[0] = '\0';
    inst->machine.time = inst->machine.last_successful_time = reached;
    *lastSuccessfulTime = inst->machine.time;
    return fmi3OK;
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance c, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime)
{
    (void)clockReference, (void)activationTime;
    CHECKED(c, fmi3ActivateModelPartition);  /* Scheduled Execution only: logs why */
    return fmi3Error;
}
