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

/* What the shared body (fmi_layer.c) says in FMI 2.0's words. */
static void emit(FmiInstance *fmi, FmiStatus status, const char *category, const char *text);
static const FmiStandard standard = {
    .name = "FMI 2.0",
    .state_names = state_names,
    .n_states = (int)(sizeof state_names / sizeof state_names[0]),
    .co_simulation_states = CO_SIMULATION_STATES,
    .model_exchange_states = MODEL_EXCHANGE_STATES,
    .instantiated = INSTANTIATED,
    .initialization = INITIALIZATION,
    .stepping = STEP_COMPLETE,
    .event_mode = EVENT_MODE,
    .continuous_time = CONTINUOUS_TIME,
    .step_failed = STEP_FAILED,
    .in_state = "state ",
    .co_simulation_where = "Co-Simulation, section 4.2.4",
    .model_exchange_where = "Model Exchange, section 3.2.3",
    .never = ": only while a step is in progress, and fmi2DoStep never runs asynchronously here",
    .after_failed = "; after a discarded step fmi2SetFMUstate or fmi2Reset go back, fmi2Terminate ends",
    .experiment = "",
    .tolerance = "tolerance (from setupExperiment)",
    .arguments_null = "vr or value is NULL",
    .n_states_argument = "nx",
    .n_indicators_argument = "ni",
    .fmu_state = "FMUstate",
    .serialized_size = "fmi2SerializedFMUstateSize",
    .state_magic = 0x43504632u,  /* "CPF2": a serialized FMU state of this build */
    .token = CP_GUID,
    .token_mismatch = "fmuGUID is not this FMU's: the model description and binary do not match",
    .log_categories = cp_log_categories,
    .n_log_categories = CP_NLOG,
    .log_error = CP_LOG_STATUS_ERROR,
    .log_discard = CP_LOG_STATUS_DISCARD,
    .log_warning = CP_LOG_STATUS_WARNING,
    .variable_name = cp_variable_name,
    .emit = emit,
};

/* An instance: the shared body's part, the host's callbacks and the instance's name, then the
 * model's data. */
typedef struct {
    FmiInstance fmi;              /* first: the machine, the state word first of all */
    fmi2CallbackFunctions cb;
    char name[128];
    double model[];               /* a ModelData; double: its alignment (fmu_model.h) */
} Instance;

/* A message to the host's logger (FMI 2.0, section 2.1.3; fmi_log decides what is reported). */
static void emit(FmiInstance *fmi, FmiStatus status, const char *category, const char *text)
{
    const Instance *inst = (const Instance *)fmi;
    if (inst->cb.logger)
        inst->cb.logger(inst->cb.componentEnvironment, inst->name, (fmi2Status)status, category, text);
}

#define MESSAGE_SIZE 1024
#define REFUSE(inst, ...) ((fmi2Status)fmi_error((inst), __VA_ARGS__))

/* The instance behind c if FMI 2.0 allows the function in its state (the table above, in the
 * column of the instance's type); logs that it does not otherwise, naming the state. */
#define CHECKED(c, function) fmi_checked((c), #function, STATES_##function)

/* ---- common functions ------------------------------------------------------------------ */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    return (fmi2Status)fmi_set_debug_logging(CHECKED(c, fmi2SetDebugLogging), "fmi2SetDebugLogging",
                                             loggingOn, nCategories, categories);
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    (void)fmuResourceLocation;
    (void)visible;
    if (!functions || !functions->allocateMemory || !functions->freeMemory) return NULL;
    Instance *inst = functions->allocateMemory(
        1, sizeof(Instance) + model_sizes.data_size + model_sizes.scratch_size);
    if (!inst) return NULL;
    fmi_instance_init(&inst->fmi, &standard, fmuType == fmi2CoSimulation, loggingOn,
                      functions->allocateMemory, functions->freeMemory, (ModelData *)inst->model);
    inst->cb = *functions;
    snprintf(inst->name, sizeof inst->name, "%s", instanceName ? instanceName : "?");
    const char *problem = fmi_instantiation_problem(&standard, instanceName, fmuGUID);
    if (!problem && fmuType != fmi2ModelExchange && fmuType != fmi2CoSimulation)
        problem = "fmuType is neither fmi2ModelExchange nor fmi2CoSimulation";
    if (problem) {
        fmi_error(&inst->fmi, "fmi2Instantiate: %s", problem);
        functions->freeMemory(inst);
        return NULL;
    }
    fmi_reset(&inst->fmi);
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
    return (fmi2Status)fmi_setup_experiment(CHECKED(c, fmi2SetupExperiment), toleranceDefined,
                                            tolerance, startTime, stopTimeDefined, stopTime);
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    return (fmi2Status)fmi_enter(CHECKED(c, fmi2EnterInitializationMode), INITIALIZATION);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    return (fmi2Status)fmi_exit_initialization(CHECKED(c, fmi2ExitInitializationMode));
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    return (fmi2Status)fmi_enter(CHECKED(c, fmi2Terminate), TERMINATED);
}

fmi2Status fmi2Reset(fmi2Component c)
{
    return (fmi2Status)fmi_reset(c);  /* allowed in every state: whatever it holds, never refused */
}

/* ---- getting and setting values ------------------------------------------------------- */

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    FmiInstance *inst = CHECKED(c, fmi2GetReal);
    if (!inst) return fmi2Error;
    if (nvr && (!vr || !value)) return REFUSE(inst, "fmi2GetReal: vr or value is NULL");
    return (fmi2Status)fmi_get_reals(inst, "fmi2GetReal", "Real", vr, nvr, value);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    FmiInstance *inst = CHECKED(c, fmi2SetReal);
    if (!inst) return fmi2Error;
    if (nvr && (!vr || !value)) return REFUSE(inst, "fmi2SetReal: vr or value is NULL");
    FmiStatus status = FMI_OK;
    for (size_t k = 0; k < nvr; k++) {  /* all checked before any is taken */
        const FmiStatus checked = fmi_check_real(inst, "fmi2SetReal", "Real", vr[k], vr[k], value[k]);
        if (checked == FMI_ERROR) return fmi2Error;
        if (checked > status) status = checked;  /* a warning: taken, and said */
    }
    for (size_t k = 0; k < nvr; k++) model_set_real(inst->model, vr[k], value[k], fmi_phase(inst));
    return (fmi2Status)status;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    return (fmi2Status)fmi_get_integers(CHECKED(c, fmi2GetInteger), "fmi2GetInteger", "Integer",
                                        vr, nvr, value);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    return (fmi2Status)fmi_set_integers(CHECKED(c, fmi2SetInteger), "fmi2SetInteger", "Integer",
                                        vr, nvr, value);
}

/* Booleans and Strings: the model contract has none, so any value reference is refused. */
#define NO_VARIABLES(function, type, value_type)                                              \
    fmi2Status function(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,            \
                        value_type value[])                                                   \
    {                                                                                          \
        (void)value;                                                                           \
        return (fmi2Status)fmi_no_variables(CHECKED(c, function), #function, type, vr, nvr);   \
    }
NO_VARIABLES(fmi2GetBoolean, "Boolean", fmi2Boolean)
NO_VARIABLES(fmi2SetBoolean, "Boolean", const fmi2Boolean)
NO_VARIABLES(fmi2GetString, "String", fmi2String)
NO_VARIABLES(fmi2SetString, "String", const fmi2String)

/* ---- the FMU state: fmi_layer.c's, in FMI 2.0's names ----------------------------------- */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    return (fmi2Status)fmi_get_fmu_state(CHECKED(c, fmi2GetFMUstate), "fmi2GetFMUstate", FMUstate);
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    return (fmi2Status)fmi_set_fmu_state(CHECKED(c, fmi2SetFMUstate), "fmi2SetFMUstate", FMUstate);
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    /* allowed in every state: whatever the instance holds, never refused */
    return (fmi2Status)fmi_free_fmu_state(c, "fmi2FreeFMUstate", FMUstate);
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    return (fmi2Status)fmi_serialized_size(CHECKED(c, fmi2SerializedFMUstateSize),
                                           "fmi2SerializedFMUstateSize", FMUstate, size);
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                 fmi2Byte serializedState[], size_t size)
{
    return (fmi2Status)fmi_serialize(CHECKED(c, fmi2SerializeFMUstate), "fmi2SerializeFMUstate",
                                     FMUstate, (unsigned char *)serializedState, size);
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    return (fmi2Status)fmi_deserialize(CHECKED(c, fmi2DeSerializeFMUstate),
                                       "fmi2DeSerializeFMUstate",
                                       (const unsigned char *)serializedState, size, FMUstate);
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
    FmiInstance *inst = CHECKED(c, fmi2GetDirectionalDerivative);
    if (!inst) return fmi2Error;
    if ((nUnknown && (!vUnknown_ref || !dvUnknown)) || (nKnown && (!vKnown_ref || !dvKnown)))
        return REFUSE(inst, "%s: a pointer is NULL", function);
    return (fmi2Status)fmi_derivative(inst, function, "dvKnown", 0, vUnknown_ref, nUnknown,
                                      vKnown_ref, nKnown, dvKnown, dvUnknown);
}

/* ---- Model Exchange ----------------------------------------------------------------------- */

fmi2Status fmi2EnterEventMode(fmi2Component c)
{
    return (fmi2Status)fmi_enter(CHECKED(c, fmi2EnterEventMode), EVENT_MODE);
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo)
{
    FmiInstance *inst = CHECKED(c, fmi2NewDiscreteStates);
    if (!inst) return fmi2Error;
    if (!eventInfo) return REFUSE(inst, "fmi2NewDiscreteStates: eventInfo is NULL");
    memset(eventInfo, 0, sizeof *eventInfo);  /* no iteration, no time event: nothing to wait for */
    /* a value set in event mode may have jumped a book (a rope's winch, a load's mass) */
    eventInfo->valuesOfContinuousStatesChanged = fmi_event_update(inst) ? fmi2True : fmi2False;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c)
{
    return (fmi2Status)fmi_enter(CHECKED(c, fmi2EnterContinuousTimeMode), CONTINUOUS_TIME);
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    const FmiStatus status = fmi_completed_integrator_step(
        CHECKED(c, fmi2CompletedIntegratorStep), "fmi2CompletedIntegratorStep", enterEventMode,
        terminateSimulation);
    if (status == FMI_OK) *enterEventMode = *terminateSimulation = fmi2False;
    return (fmi2Status)status;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    return (fmi2Status)fmi_set_time(CHECKED(c, fmi2SetTime), "fmi2SetTime", time);
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    return (fmi2Status)fmi_set_continuous_states(CHECKED(c, fmi2SetContinuousStates),
                                                 "fmi2SetContinuousStates", x, nx);
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx)
{
    return (fmi2Status)fmi_get_derivatives(CHECKED(c, fmi2GetDerivatives), "fmi2GetDerivatives",
                                           dx, nx);
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni)
{
    return (fmi2Status)fmi_get_event_indicators(CHECKED(c, fmi2GetEventIndicators),
                                                "fmi2GetEventIndicators", eventIndicators, ni);
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    return (fmi2Status)fmi_get_continuous_states(CHECKED(c, fmi2GetContinuousStates),
                                                 "fmi2GetContinuousStates", x, nx);
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx)
{
    return (fmi2Status)fmi_get_nominals(CHECKED(c, fmi2GetNominalsOfContinuousStates),
                                        "fmi2GetNominalsOfContinuousStates", x_nominal, nx);
}

/* ---- Co-Simulation ----------------------------------------------------------------------- */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    FmiInstance *inst = CHECKED(c, fmi2SetRealInputDerivatives);
    if (!inst) return fmi2Error;
    if (nvr && (!vr || !order || !value))
        return REFUSE(inst, "fmi2SetRealInputDerivatives: vr, order or value is NULL");
    for (size_t k = 0; k < nvr; k++)  /* all checked before any is taken */
        if (fmi_check_input_derivative(inst, "fmi2SetRealInputDerivatives", vr[k], vr[k], order[k],
                                       value[k]))
            return fmi2Error;
    for (size_t k = 0; k < nvr; k++) model_set_input_derivative(inst->model, vr[k], order[k], value[k]);
    return fmi2OK;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    FmiInstance *inst = CHECKED(c, fmi2GetRealOutputDerivatives);
    if (!inst) return fmi2Error;
    if (nvr && (!vr || !order || !value))
        return REFUSE(inst, "fmi2GetRealOutputDerivatives: vr, order or value is NULL");
    for (size_t k = 0; k < nvr; k++) {
        const FmiStatus status = fmi_get_output_derivative(inst, "fmi2GetRealOutputDerivatives",
                                                           vr[k], vr[k], order[k], &value[k]);
        if (status != FMI_OK) return (fmi2Status)status;
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    FmiInstance *inst = CHECKED(c, fmi2DoStep);
    const double t = currentCommunicationPoint, dt = communicationStepSize;
    if (fmi_communication_point(inst, "fmi2DoStep", t)) return fmi2Error;
    if (model_do_step(inst->model, t, dt, inst->discarded, sizeof inst->discarded) != MODEL_OK) {
        inst->machine.state = STEP_FAILED;
        return (fmi2Status)fmi_discard(inst, inst->discarded);
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
    FmiInstance *inst = CHECKED(c, fmi2GetStatus);
    if (!inst) return fmi2Error;
    if (!value) return REFUSE(inst, "fmi2GetStatus: value is NULL");
    if (s != fmi2DoStepStatus) return fmi2Discard;
    *value = inst->machine.state == STEP_FAILED ? fmi2Discard : fmi2OK;
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    FmiInstance *inst = CHECKED(c, fmi2GetRealStatus);
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
    FmiInstance *inst = CHECKED(c, fmi2GetBooleanStatus);
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
