/* A trivial FMI 2.0 Co-Simulation FMU: N_OUTPUTS constant outputs and a doStep that does
 * nothing. What a master spends on an FMU with that many outputs, the floor the native
 * FMU is measured against (benchmarks/native_overhead.py builds it). */
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#ifndef N_OUTPUTS
#error "define N_OUTPUTS"
#endif

typedef struct {
    fmi2CallbackFunctions cb;
    double y[N_OUTPUTS];
} Trivial;

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging)
{
    (void)name, (void)type, (void)guid, (void)resources, (void)visible, (void)logging;
    Trivial *t = cb->allocateMemory(1, sizeof(Trivial));
    if (!t) return NULL;
    t->cb = *cb;
    for (int k = 0; k < N_OUTPUTS; k++) t->y[k] = k;
    return t;
}

void fmi2FreeInstance(fmi2Component c) { if (c) ((Trivial *)c)->cb.freeMemory(c); }

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[])
{
    Trivial *t = c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] >= N_OUTPUTS) return fmi2Error;
        v[k] = t->y[vr[k]];
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_prior)
{
    (void)c, (void)t, (void)h, (void)no_prior;
    return fmi2OK;
}

#define OK_FUNCTION(name, ...) fmi2Status name(__VA_ARGS__) { return fmi2OK; }
#pragma GCC diagnostic ignored "-Wunused-parameter"
OK_FUNCTION(fmi2SetDebugLogging, fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[])
OK_FUNCTION(fmi2SetupExperiment, fmi2Component c, fmi2Boolean td, fmi2Real tol, fmi2Real t0,
            fmi2Boolean sd, fmi2Real t1)
OK_FUNCTION(fmi2EnterInitializationMode, fmi2Component c)
OK_FUNCTION(fmi2ExitInitializationMode, fmi2Component c)
OK_FUNCTION(fmi2Terminate, fmi2Component c)
OK_FUNCTION(fmi2Reset, fmi2Component c)
OK_FUNCTION(fmi2SetReal, fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[])
OK_FUNCTION(fmi2GetInteger, fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[])
OK_FUNCTION(fmi2SetInteger, fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[])
OK_FUNCTION(fmi2GetBoolean, fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[])
OK_FUNCTION(fmi2SetBoolean, fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[])
OK_FUNCTION(fmi2GetString, fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[])
OK_FUNCTION(fmi2SetString, fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[])
OK_FUNCTION(fmi2GetStatus, fmi2Component c, const fmi2StatusKind s, fmi2Status *v)
OK_FUNCTION(fmi2GetRealStatus, fmi2Component c, const fmi2StatusKind s, fmi2Real *v)
OK_FUNCTION(fmi2GetIntegerStatus, fmi2Component c, const fmi2StatusKind s, fmi2Integer *v)
OK_FUNCTION(fmi2GetBooleanStatus, fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v)
OK_FUNCTION(fmi2GetStringStatus, fmi2Component c, const fmi2StatusKind s, fmi2String *v)
OK_FUNCTION(fmi2CancelStep, fmi2Component c)

#define ERROR_FUNCTION(name, ...) fmi2Status name(__VA_ARGS__) { return fmi2Error; }
ERROR_FUNCTION(fmi2GetFMUstate, fmi2Component c, fmi2FMUstate *s)
ERROR_FUNCTION(fmi2SetFMUstate, fmi2Component c, fmi2FMUstate s)
ERROR_FUNCTION(fmi2FreeFMUstate, fmi2Component c, fmi2FMUstate *s)
ERROR_FUNCTION(fmi2SerializedFMUstateSize, fmi2Component c, fmi2FMUstate s, size_t *n)
ERROR_FUNCTION(fmi2SerializeFMUstate, fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n)
ERROR_FUNCTION(fmi2DeSerializeFMUstate, fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s)
ERROR_FUNCTION(fmi2GetDirectionalDerivative, fmi2Component c, const fmi2ValueReference u[], size_t nu,
               const fmi2ValueReference k[], size_t nk, const fmi2Real dk[], fmi2Real du[])
ERROR_FUNCTION(fmi2SetRealInputDerivatives, fmi2Component c, const fmi2ValueReference vr[], size_t n,
               const fmi2Integer order[], const fmi2Real v[])
ERROR_FUNCTION(fmi2GetRealOutputDerivatives, fmi2Component c, const fmi2ValueReference vr[], size_t n,
               const fmi2Integer order[], fmi2Real v[])
