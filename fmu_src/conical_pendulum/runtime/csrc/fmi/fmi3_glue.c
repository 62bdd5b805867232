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
 * What this FMU does not have, as its model description says: no clocks, no events in
 * Co-Simulation (hasEventMode="false"; Model Exchange's state events are the model's event
 * indicators, an elastic rope's taut margin), providesEvaluateDiscreteStates="false", no
 * Scheduled Execution, no configuration modes (no tunable structural parameters), variables of
 * the types Float64, Int32 and Enumeration (as Int64) only (the others are refused) and, for a model with arrays, the
 * UInt64 structural parameter of their dimension (fmi3_arrays.h, generated for every model: an
 * array's value reference stands for the model's scalars in order; a model without arrays has
 * no structural parameter and no UInt64 variable), no output derivatives, no intermediate
 * update. Early return (fmi3DoStep's earlyReturn, lastSuccessfulTime) and the adjoint
 * derivative are marked EARLY RETURN and ADJOINT below.
 */
#include <limits.h>
#include <stdlib.h>

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

/* What the shared body (fmi_layer.c) says in FMI 3.0's words. */
static void emit(FmiInstance *fmi, FmiStatus status, const char *category, const char *text);
static const FmiStandard standard = {
    .name = "FMI 3.0",
    .state_names = state_names,
    .n_states = (int)(sizeof state_names / sizeof state_names[0]),
    .co_simulation_states = CO_SIMULATION_STATES,
    .model_exchange_states = MODEL_EXCHANGE_STATES,
    .instantiated = INSTANTIATED,
    .initialization = INITIALIZATION,
    .stepping = STEP_MODE,
    .event_mode = EVENT_MODE,
    .continuous_time = CONTINUOUS_TIME,
    .step_failed = 0,  /* a discarded step leaves the instance in Step Mode */
    .in_state = "",
    .co_simulation_where = "Co-Simulation",
    .model_exchange_where = "Model Exchange",
    .never = ": only in a state this FMU never enters (no events, clocks or configuration)",
    .after_failed = "",
    .experiment = "fmi3EnterInitializationMode: ",
    .tolerance = "tolerance",
    .arguments_null = "valueReferences or values is NULL",
    .n_states_argument = "nContinuousStates",
    .n_indicators_argument = "nEventIndicators",
    .fmu_state = "FMUState",
    .serialized_size = "fmi3SerializedFMUStateSize",
    .state_magic = 0x43504633u,  /* "CPF3": a serialized FMU state of this build */
    .token = CP_GUID,
    .token_mismatch = "instantiationToken is not this FMU's: the model description and binary "
                      "do not match",
    .log_categories = cp_log_categories,
    .n_log_categories = CP_NLOG,
    .log_error = CP_LOG_STATUS_ERROR,
    .log_discard = CP_LOG_STATUS_DISCARD,
    .log_warning = CP_LOG_STATUS_WARNING,
    .variable_name = cp_variable_name,
    .emit = emit,
};

/* An instance: the shared body's part, the host's environment and logMessage, then the
 * model's data. */
typedef struct {
    FmiInstance fmi;              /* first: the machine, the state word first of all */
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback logger;
    double model[];               /* a ModelData; double: its alignment (fmu_model.h) */
} Instance;

/* A message to the host's logMessage (fmi_log decides what is reported). */
static void emit(FmiInstance *fmi, FmiStatus status, const char *category, const char *text)
{
    const Instance *inst = (const Instance *)fmi;
    if (inst->logger) inst->logger(inst->environment, (fmi3Status)status, category, text);
}

/* FMI 3.0's independent variable, time: its value reference follows every variable's
 * (fmi3_arrays.h, builder/fmi/fmi3.py). */
#define VR_TIME ((fmi3ValueReference)CP_VR_TIME)
#define MAX_ELEMENTS 4096  /* of one call's expanded value references (directional derivatives) */

#define MESSAGE_SIZE 1024
#define REFUSE(inst, ...) ((fmi3Status)fmi_error((inst), __VA_ARGS__))

#define CHECKED(c, function) fmi_checked((c), #function, STATES_##function)
#define CHECKED_AS(c, function, row) fmi_checked((c), function, STATES_##row)

/* ---- common functions ------------------------------------------------------------------ */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    return (fmi3Status)fmi_set_debug_logging(CHECKED(c, fmi3SetDebugLogging), "fmi3SetDebugLogging",
                                             loggingOn, nCategories, categories);
}
static Instance *instantiate(const char *function, int co_simulation, fmi3String instanceName,
                             fmi3String instantiationToken, fmi3Boolean loggingOn,
                             fmi3InstanceEnvironment environment, fmi3LogMessageCallback logger,
                             const char *problem)
{
    /* FMI 3.0 gives the FMU no memory callbacks: its own calloc, freed by fmi3FreeInstance. */
    Instance *inst = calloc(1, sizeof(Instance) + model_sizes.data_size + model_sizes.scratch_size);
    if (!inst) return NULL;
    fmi_instance_init(&inst->fmi, &standard, co_simulation, loggingOn, calloc, free,
                      (ModelData *)inst->model);
    inst->environment = environment;
    inst->logger = logger;
    if (!problem) problem = fmi_instantiation_problem(&standard, instanceName, instantiationToken);
    if (problem) {
        fmi_error(&inst->fmi, "%s: %s", function, problem);
        free(inst);
        return NULL;
    }
    fmi_reset(&inst->fmi);
    return inst;
}
fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)resourcePath, (void)visible;
    return instantiate("fmi3InstantiateModelExchange", 0, instanceName,
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
    Instance *inst = instantiate("fmi3InstantiateCoSimulation", 1, instanceName,
                                 instantiationToken, loggingOn, instanceEnvironment, logMessage,
                                 problem);
    if (inst) inst->fmi.early_return_allowed = earlyReturnAllowed ? 1 : 0;
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
    FmiInstance *inst = CHECKED(c, fmi3EnterInitializationMode);
    if (fmi_setup_experiment(inst, toleranceDefined, tolerance, startTime, stopTimeDefined,
                             stopTime))
        return fmi3Error;
    return (fmi3Status)fmi_enter(inst, INITIALIZATION);
}
fmi3Status fmi3ExitInitializationMode(fmi3Instance c)
{
    return (fmi3Status)fmi_exit_initialization(CHECKED(c, fmi3ExitInitializationMode));
}
fmi3Status fmi3EnterEventMode(fmi3Instance c)
{
    FmiInstance *inst = CHECKED(c, fmi3EnterEventMode);
    if (!inst) return fmi3Error;
    if (inst->co_simulation)  /* eventModeUsed is refused at instantiation */
        return REFUSE(inst, "fmi3EnterEventMode: this FMU has no event mode in Co-Simulation "
                      "(hasEventMode is false)");
    inst->machine.state = EVENT_MODE;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance c)
{
    return (fmi3Status)fmi_enter(CHECKED(c, fmi3Terminate), TERMINATED);
}
fmi3Status fmi3Reset(fmi3Instance c)
{
    return (fmi3Status)fmi_reset(c);  /* allowed in every state: whatever it holds, never refused */
}
/* ---- getting and setting values ------------------------------------------------------- */

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
static fmi3Status check_values(FmiInstance *inst, const char *function, const fmi3ValueReference vr[],
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
    FmiInstance *inst = CHECKED(c, fmi3GetFloat64);
    if (!inst) return fmi3Error;
    if (check_values(inst, "fmi3GetFloat64", vr, nvr, values, nValues)) return fmi3Error;
    size_t j = 0;
    for (size_t k = 0; k < nvr; k++) {
        if (vr[k] == VR_TIME) {
            values[j++] = inst->machine.time;
            continue;
        }
        const unsigned *members;
        const size_t n = elements(vr[k], &members);
        for (size_t e = 0; e < n; e++, j++) {
            const FmiStatus status = fmi_get_real(inst, "fmi3GetFloat64", "Float64",
                                                  ELEMENT(vr[k], members, e), vr[k], &values[j]);
            if (status != FMI_OK) return (fmi3Status)status;
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues)
{
    FmiInstance *inst = CHECKED(c, fmi3SetFloat64);
    if (!inst) return fmi3Error;
    if (check_values(inst, "fmi3SetFloat64", vr, nvr, values, nValues)) return fmi3Error;
    FmiStatus status = FMI_OK;
    for (size_t k = 0, j = 0; k < nvr; k++) {  /* all checked before any is taken */
        if (vr[k] == VR_TIME)
            return REFUSE(inst, "fmi3SetFloat64: time is the independent variable; it is set "
                          "by fmi3EnterInitializationMode, fmi3SetTime and fmi3DoStep");
        const unsigned *members;
        const size_t n = elements(vr[k], &members);
        for (size_t e = 0; e < n; e++, j++) {
            const FmiStatus checked = fmi_check_real(inst, "fmi3SetFloat64", "Float64",
                                                     ELEMENT(vr[k], members, e), vr[k], values[j]);
            if (checked == FMI_ERROR) return fmi3Error;
            if (checked > status) status = checked;  /* a warning: taken, and said */
        }
    }
    for (size_t k = 0, j = 0; k < nvr; k++) {
        const unsigned *members;
        const size_t n = elements(vr[k], &members);
        for (size_t e = 0; e < n; e++, j++)
            model_set_real(inst->model, ELEMENT(vr[k], members, e), values[j], fmi_phase(inst));
    }
    return (fmi3Status)status;
}

/* Int32 and UInt64: no arrays (fmi3_arrays.h's are Float64). */
static fmi3Status check_scalars(FmiInstance *inst, const char *function, const void *vr, size_t nvr,
                                const void *values, size_t nValues)
{
    if (!inst) return fmi3Error;
    if (nvr && (!vr || !values)) return REFUSE(inst, "%s: valueReferences or values is NULL", function);
    if (nValues != nvr)
        return REFUSE(inst, "%s: nValues = %zu, but the %zu value references have %zu values",
                      function, nValues, nvr, nvr);
    return fmi3OK;
}

/* The model contract's integers are FMI 3.0's Int32 variables and its enumerations, which FMI
 * 3.0 gets and sets as Int64 (fmi3_arrays.h's cp_enumeration): each only by its own type. */
static fmi3Status check_kind(FmiInstance *inst, const char *function, const char *type,
                             const fmi3ValueReference vr[], size_t nvr, int enumeration)
{
    for (size_t k = 0; k < nvr; k++)
        if ((vr[k] < CP_VR_TIME ? cp_enumeration[vr[k]] : 0) != enumeration)
            return REFUSE(inst, "%s: value reference %u is not an %s variable", function, vr[k], type);
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Int32 values[], size_t nValues)
{
    FmiInstance *inst = CHECKED(c, fmi3GetInt32);
    if (check_scalars(inst, "fmi3GetInt32", vr, nvr, values, nValues)) return fmi3Error;
    if (check_kind(inst, "fmi3GetInt32", "Int32", vr, nvr, 0)) return fmi3Error;
    return (fmi3Status)fmi_get_integers(inst, "fmi3GetInt32", "Int32", vr, nvr, values);
}
fmi3Status fmi3SetInt32(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Int32 values[], size_t nValues)
{
    FmiInstance *inst = CHECKED(c, fmi3SetInt32);
    if (check_scalars(inst, "fmi3SetInt32", vr, nvr, values, nValues)) return fmi3Error;
    if (check_kind(inst, "fmi3SetInt32", "Int32", vr, nvr, 0)) return fmi3Error;
    return (fmi3Status)fmi_set_integers(inst, "fmi3SetInt32", "Int32", vr, nvr, values);
}
fmi3Status fmi3GetInt64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Int64 values[], size_t nValues)
{
    FmiInstance *inst = CHECKED_AS(c, "fmi3GetInt64", fmi3GetInt32);
    if (check_scalars(inst, "fmi3GetInt64", vr, nvr, values, nValues)) return fmi3Error;
    if (check_kind(inst, "fmi3GetInt64", "Int64", vr, nvr, 1)) return fmi3Error;
    for (size_t k = 0; k < nvr; k++) {
        int value;
        if (fmi_get_integers(inst, "fmi3GetInt64", "Int64", &vr[k], 1, &value)) return fmi3Error;
        values[k] = value;
    }
    return fmi3OK;
}
fmi3Status fmi3SetInt64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Int64 values[], size_t nValues)
{
    FmiInstance *inst = CHECKED_AS(c, "fmi3SetInt64", fmi3SetInt32);
    if (check_scalars(inst, "fmi3SetInt64", vr, nvr, values, nValues)) return fmi3Error;
    if (check_kind(inst, "fmi3SetInt64", "Int64", vr, nvr, 1)) return fmi3Error;
    char message[MESSAGE_SIZE];
    for (size_t k = 0; k < nvr; k++) {  /* all checked before any is taken, as fmi_set_integers */
        const int value = values[k] < INT_MIN ? INT_MIN : values[k] > INT_MAX ? INT_MAX : (int)values[k];
        if (value != values[k])  /* beyond the model's int: out of every enumeration's range */
            return REFUSE(inst, "fmi3SetInt64: %s = %lld: out of range", cp_variable_name(vr[k]),
                          (long long)values[k]);
        if (model_check_integer(inst->model, vr[k], value, fmi_initialized(inst), message,
                                sizeof message) != MODEL_OK)
            return REFUSE(inst, "%s", message);
    }
    for (size_t k = 0; k < nvr; k++) {
        const int value = (int)values[k];
        if (fmi_set_integers(inst, "fmi3SetInt64", "Int64", &vr[k], 1, &value)) return fmi3Error;
    }
    return fmi3OK;
}
/* The other types: the model contract has none, so any value reference is refused. */
#define NO_VARIABLES(function, row, type, value_type)                                          \
    fmi3Status function(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,             \
                        value_type values[], size_t nValues)                                   \
    {                                                                                          \
        (void)values, (void)nValues;                                                           \
        return (fmi3Status)fmi_no_variables(CHECKED_AS(c, #function, row), #function, type, vr, nvr);          \
    }
NO_VARIABLES(fmi3GetFloat32, fmi3GetOther, "Float32", fmi3Float32)
NO_VARIABLES(fmi3GetInt8, fmi3GetOther, "Int8", fmi3Int8)
NO_VARIABLES(fmi3GetUInt8, fmi3GetOther, "UInt8", fmi3UInt8)
NO_VARIABLES(fmi3GetInt16, fmi3GetOther, "Int16", fmi3Int16)
NO_VARIABLES(fmi3GetUInt16, fmi3GetOther, "UInt16", fmi3UInt16)
NO_VARIABLES(fmi3GetUInt32, fmi3GetOther, "UInt32", fmi3UInt32)
NO_VARIABLES(fmi3GetBoolean, fmi3GetOther, "Boolean", fmi3Boolean)
NO_VARIABLES(fmi3GetString, fmi3GetOther, "String", fmi3String)
NO_VARIABLES(fmi3SetFloat32, fmi3SetOther, "Float32", const fmi3Float32)
NO_VARIABLES(fmi3SetInt8, fmi3SetOther, "Int8", const fmi3Int8)
NO_VARIABLES(fmi3SetUInt8, fmi3SetOther, "UInt8", const fmi3UInt8)
NO_VARIABLES(fmi3SetInt16, fmi3SetOther, "Int16", const fmi3Int16)
NO_VARIABLES(fmi3SetUInt16, fmi3SetOther, "UInt16", const fmi3UInt16)
NO_VARIABLES(fmi3SetUInt32, fmi3SetOther, "UInt32", const fmi3UInt32)
NO_VARIABLES(fmi3SetBoolean, fmi3SetOther, "Boolean", const fmi3Boolean)
NO_VARIABLES(fmi3SetString, fmi3SetOther, "String", const fmi3String)

#ifdef CP_VR_DIMENSION
/* UInt64: only the structural parameter of the arrays' dimension, fixed by the build
 * (fmi3_arrays.h: its value reference, value and refusal). */
fmi3Status fmi3GetUInt64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                         fmi3UInt64 values[], size_t nValues)
{
    FmiInstance *inst = CHECKED_AS(c, "fmi3GetUInt64", fmi3GetDimension);
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
    FmiInstance *inst = CHECKED_AS(c, "fmi3SetUInt64", fmi3SetOther);
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
    return (fmi3Status)fmi_no_variables(CHECKED_AS(c, "fmi3GetBinary", fmi3GetOther), "fmi3GetBinary", "Binary", vr, nvr);
}

fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues)
{
    (void)valueSizes, (void)values, (void)nValues;
    return (fmi3Status)fmi_no_variables(CHECKED_AS(c, "fmi3SetBinary", fmi3SetOther), "fmi3SetBinary", "Binary", vr, nvr);
}

/* ---- clocks: none ------------------------------------------------------------------------ */

fmi3Status fmi3GetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[])
{
    (void)values;
    return (fmi3Status)fmi_no_variables(CHECKED(c, fmi3GetClock), "fmi3GetClock", "Clock", vr, nvr);
}

fmi3Status fmi3SetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[])
{
    (void)values;
    return (fmi3Status)fmi_no_variables(CHECKED(c, fmi3SetClock), "fmi3SetClock", "Clock", vr, nvr);
}

#define NO_CLOCKS(function, unused, ...)                                                       \
    fmi3Status function(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, __VA_ARGS__) \
    {                                                                                          \
        (void)unused;                                                                          \
        return (fmi3Status)fmi_no_variables(CHECKED_AS(c, #function, fmi3Intervals), #function, "Clock", vr, nvr); \
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
    FmiInstance *inst = CHECKED(c, fmi3UpdateDiscreteStates);
    if (!inst) return fmi3Error;
    if (!discreteStatesNeedUpdate || !terminateSimulation || !nominalsOfContinuousStatesChanged
        || !valuesOfContinuousStatesChanged || !nextEventTimeDefined || !nextEventTime)
        return REFUSE(inst, "fmi3UpdateDiscreteStates: a pointer is NULL");
    /* no iteration, no time event: nothing to wait for; a value set in event mode may have
     * jumped a book (a rope's winch, a load's mass) */
    *discreteStatesNeedUpdate = *terminateSimulation = *nominalsOfContinuousStatesChanged = fmi3False;
    *valuesOfContinuousStatesChanged = fmi_event_update(inst) ? fmi3True : fmi3False;
    *nextEventTimeDefined = fmi3False;
    *nextEventTime = 0.0;
    return fmi3OK;
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance c)
{
    FmiInstance *inst = CHECKED(c, fmi3EnterConfigurationMode);
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
    FmiInstance *inst = CHECKED(c, fmi3GetNumberOfVariableDependencies);
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
    FmiInstance *inst = CHECKED(c, fmi3GetVariableDependencies);
    if (!inst) return fmi3Error;
    return REFUSE(inst, "fmi3GetVariableDependencies: not provided "
                  "(providesPerElementDependencies is false; the ModelStructure says them)");
}

/* ---- the FMU state: fmi_layer.c's, in FMI 3.0's names ----------------------------------- */

fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState *FMUState)
{
    return (fmi3Status)fmi_get_fmu_state(CHECKED(c, fmi3GetFMUState), "fmi3GetFMUState", FMUState);
}

fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState FMUState)
{
    return (fmi3Status)fmi_set_fmu_state(CHECKED(c, fmi3SetFMUState), "fmi3SetFMUState", FMUState);
}

fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState *FMUState)
{
    /* allowed in every state: whatever the instance holds, never refused */
    return (fmi3Status)fmi_free_fmu_state(c, "fmi3FreeFMUState", FMUState);
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState FMUState, size_t *size)
{
    return (fmi3Status)fmi_serialized_size(CHECKED(c, fmi3SerializedFMUStateSize),
                                           "fmi3SerializedFMUStateSize", FMUState, size);
}

fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size)
{
    return (fmi3Status)fmi_serialize(CHECKED(c, fmi3SerializeFMUState), "fmi3SerializeFMUState",
                                     FMUState, serializedState, size);
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState)
{
    return (fmi3Status)fmi_deserialize(CHECKED(c, fmi3DeserializeFMUState),
                                       "fmi3DeserializeFMUState", serializedState, size, FMUState);
}

/* ---- partial derivatives ---------------------------------------------------------------- */

/* The contract's scalars behind value references into out (an array: its members in link
 * order, fmi3_arrays.h), *count of them; or refused, naming the function. */
static fmi3Status expand(FmiInstance *inst, const char *function, const fmi3ValueReference refs[],
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
static fmi3Status derivative(FmiInstance *inst, const char *function, int adjoint,
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
    const size_t n_seeded = adjoint ? n_unknown : n_known, n_sensed = adjoint ? n_known : n_unknown;
    if (nSeed != n_seeded || nSensitivity != n_sensed)
        return REFUSE(inst, "%s: nSeed = %zu and nSensitivity = %zu, but the %s have %zu values "
                      "and the %s %zu", function, nSeed, nSensitivity, adjoint ? "unknowns" : "knowns",
                      n_seeded, adjoint ? "knowns" : "unknowns", n_sensed);
    return (fmi3Status)fmi_derivative(inst, function, "seed", adjoint, unknown, n_unknown, known,
                                      n_known, seed, sensitivity);
}

/* sensitivity = J seed (FMI 3.0, section 2.2.11), J the Jacobian of the unknowns with respect to
 * the knowns at the current values: model_directional_derivative. An array stands for its
 * elements: nSeed and nSensitivity count the values, as nValues does. */
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity)
{
    FmiInstance *inst = CHECKED(c, fmi3GetDirectionalDerivative);
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
    FmiInstance *inst = CHECKED(c, fmi3GetAdjointDerivative);
    if (!inst) return fmi3Error;
    return derivative(inst, "fmi3GetAdjointDerivative", 1, unknowns, nUnknowns, knowns, nKnowns,
                      seed, nSeed, sensitivity, nSensitivity);
}

/* ---- Model Exchange ----------------------------------------------------------------------- */

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c)
{
    return (fmi3Status)fmi_enter(CHECKED(c, fmi3EnterContinuousTimeMode), CONTINUOUS_TIME);
}
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    const FmiStatus status = fmi_completed_integrator_step(
        CHECKED(c, fmi3CompletedIntegratorStep), "fmi3CompletedIntegratorStep", enterEventMode,
        terminateSimulation);
    if (status == FMI_OK) *enterEventMode = *terminateSimulation = fmi3False;
    return (fmi3Status)status;
}

fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 time)
{
    return (fmi3Status)fmi_set_time(CHECKED(c, fmi3SetTime), "fmi3SetTime", time);
}
fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    return (fmi3Status)fmi_set_continuous_states(CHECKED(c, fmi3SetContinuousStates),
                                                 "fmi3SetContinuousStates", continuousStates,
                                                 nContinuousStates);
}
fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 derivatives[],
                                             size_t nContinuousStates)
{
    return (fmi3Status)fmi_get_derivatives(CHECKED(c, fmi3GetContinuousStateDerivatives),
                                           "fmi3GetContinuousStateDerivatives", derivatives,
                                           nContinuousStates);
}
fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 eventIndicators[], size_t nEventIndicators)
{
    return (fmi3Status)fmi_get_event_indicators(CHECKED(c, fmi3GetEventIndicators),
                                                "fmi3GetEventIndicators", eventIndicators,
                                                nEventIndicators);
}
fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    return (fmi3Status)fmi_get_continuous_states(CHECKED(c, fmi3GetContinuousStates),
                                                 "fmi3GetContinuousStates", continuousStates,
                                                 nContinuousStates);
}
fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 nominals[],
                                             size_t nContinuousStates)
{
    return (fmi3Status)fmi_get_nominals(CHECKED(c, fmi3GetNominalsOfContinuousStates),
                                        "fmi3GetNominalsOfContinuousStates", nominals,
                                        nContinuousStates);
}
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t *nEventIndicators)
{
    FmiInstance *inst = CHECKED(c, fmi3GetNumberOfEventIndicators);
    if (!inst) return fmi3Error;
    if (!nEventIndicators) return REFUSE(inst, "fmi3GetNumberOfEventIndicators: a pointer is NULL");
    *nEventIndicators = (size_t)model_sizes.n_event_indicator;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t *nContinuousStates)
{
    FmiInstance *inst = CHECKED(c, fmi3GetNumberOfContinuousStates);
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
    FmiInstance *inst = CHECKED(c, fmi3GetOutputDerivatives);
    if (!inst) return fmi3Error;
    if (nvr && !orders) return REFUSE(inst, "fmi3GetOutputDerivatives: orders is NULL");
    if (check_values(inst, "fmi3GetOutputDerivatives", vr, nvr, values, nValues)) return fmi3Error;
    for (size_t k = 0, j = 0; k < nvr; k++) {
        const unsigned *members;
        const size_t n = elements(vr[k], &members);
        for (size_t e = 0; e < n; e++, j++) {
            const FmiStatus status = fmi_get_output_derivative(
                inst, "fmi3GetOutputDerivatives", ELEMENT(vr[k], members, e), vr[k], orders[k],
                &values[j]);
            if (status != FMI_OK) return (fmi3Status)status;
        }
    }
    return fmi3OK;
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
    FmiInstance *inst = CHECKED(c, fmi3DoStep);
    if (!inst) return fmi3Error;
    if (!eventHandlingNeeded || !terminateSimulation || !earlyReturn || !lastSuccessfulTime)
        return REFUSE(inst, "fmi3DoStep: a pointer is NULL");
    const double t = currentCommunicationPoint, dt = communicationStepSize;
    if (fmi_communication_point(inst, "fmi3DoStep", t)) return fmi3Error;
    *eventHandlingNeeded = *terminateSimulation = *earlyReturn = fmi3False;
    double reached = t;
    if (model_do_step_early(inst->model, t, dt, inst->early_return_allowed, &reached,
                            inst->discarded, sizeof inst->discarded) != MODEL_OK) {
        if (!(reached > t)) {
            *lastSuccessfulTime = inst->machine.last_successful_time = inst->machine.time;
            return (fmi3Status)fmi_discard(inst, inst->discarded);
        }
        fmi_log(inst, FMI_OK, CP_LOG_STATUS_DISCARD, "fmi3DoStep returns early: %s",
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
