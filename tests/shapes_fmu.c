/* A small FMI 2.0 Co-Simulation FMU of another shape than the pendulum's, for the compiled
 * runner's and the sweep's tests (shapes.py builds it): Real, Integer and Boolean outputs,
 * and steps that fail, or crash the process, on request.
 *
 * Reals: 0 x (output: x += gain h (1 + t) per step), 1 h (output: the last step size),
 * 2 gain (parameter, refused when negative), 3 fail_at (parameter: the first step reaching
 * past it fails as `mode` says), 4 nan_at (parameter: from there x is NaN).
 * Integers: 0 count (output: steps taken), 1 mode (parameter: 0 never fail, 1 discard and
 * terminate, 2 discard `repeats` times then go on, 3 fmi2Error, 4 write through a null
 * pointer: SIGSEGV, as a buggy FMU crashes its host, 5 never return: a stuck FMU, waiting
 * for a signal without using the CPU), 2 repeats (parameter).
 * Booleans: 0 above (output: x > 0.5). */
#define _POSIX_C_SOURCE 200809L /* pause() */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "fmi2Functions.h"

typedef struct {
    fmi2CallbackFunctions cb;
    fmi2String name;
    double reals[5];
    int integers[3];
    int failures, terminated;
    double lastSuccessfulTime;
    volatile double *nowhere; /* NULL: mode 4 writes through it */
} Shapes;

enum { X, H, GAIN, FAIL_AT, NAN_AT };
enum { COUNT, MODE, REPEATS };

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging)
{
    (void)type, (void)guid, (void)resources, (void)visible, (void)logging;
    Shapes *s = cb->allocateMemory(1, sizeof(Shapes));
    if (!s) return NULL;
    s->cb = *cb;
    s->name = name;
    s->reals[GAIN] = 1.0;
    s->reals[FAIL_AT] = 1e300;
    s->reals[NAN_AT] = 1e300;
    s->integers[REPEATS] = 1;
    s->nowhere = NULL;
    return s;
}

void fmi2FreeInstance(fmi2Component c) { ((Shapes *)c)->cb.freeMemory(c); }

/* the message as the format, as fmpy's Python logger takes it (it does not format) */
static void say(Shapes *s, fmi2Status status, const char *message)
{
    s->cb.logger(s->cb.componentEnvironment, s->name, status, "logStatusError", message);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[])
{
    Shapes *s = c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] < GAIN || vr[k] > NAN_AT) return fmi2Error;
        if (vr[k] == GAIN && v[k] < 0) {
            char message[64];
            snprintf(message, sizeof message, "gain = %g: must not be negative", v[k]);
            say(s, fmi2Error, message);
            return fmi2Error;
        }
        s->reals[vr[k]] = v[k];
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[])
{
    for (size_t k = 0; k < n; k++) {
        if (vr[k] < MODE || vr[k] > REPEATS) return fmi2Error;
        ((Shapes *)c)->integers[vr[k]] = v[k];
    }
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[])
{
    for (size_t k = 0; k < n; k++) {
        if (vr[k] > NAN_AT) return fmi2Error;
        v[k] = ((Shapes *)c)->reals[vr[k]];
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[])
{
    for (size_t k = 0; k < n; k++) {
        if (vr[k] > REPEATS) return fmi2Error;
        v[k] = ((Shapes *)c)->integers[vr[k]];
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[])
{
    for (size_t k = 0; k < n; k++) {
        if (vr[k] != 0) return fmi2Error;
        v[k] = ((Shapes *)c)->reals[X] > 0.5 ? 7 : fmi2False; /* any non-zero is true */
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noPrior)
{
    (void)noPrior;
    Shapes *s = c;
    int mode = s->integers[MODE];
    if (mode == 4 && t + h > s->reals[FAIL_AT]) *s->nowhere = t;
    if (mode == 5 && t + h > s->reals[FAIL_AT])
        for (;;) pause();
    if (mode && mode < 4 && t + h > s->reals[FAIL_AT] && s->failures < (mode == 2 ? s->integers[REPEATS] : 1)) {
        char message[96];
        snprintf(message, sizeof message, "step from t = %g s by %g s refused", t, h);
        s->failures++;
        s->terminated = mode == 1;
        s->lastSuccessfulTime = t;
        say(s, mode == 3 ? fmi2Error : fmi2Discard, message);
        return mode == 3 ? fmi2Error : fmi2Discard;
    }
    s->reals[X] = t + h >= s->reals[NAN_AT] ? NAN : s->reals[X] + s->reals[GAIN] * h * (1 + t);
    s->reals[H] = h;
    s->integers[COUNT]++;
    return fmi2OK;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean *v)
{
    if (kind != fmi2Terminated) return fmi2Discard;
    *v = ((Shapes *)c)->terminated;
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real *v)
{
    if (kind != fmi2LastSuccessfulTime) return fmi2Discard;
    *v = ((Shapes *)c)->lastSuccessfulTime;
    return fmi2OK;
}

#define OK_FUNCTION(name, ...) fmi2Status name(__VA_ARGS__) { return fmi2OK; }
#define ERROR_FUNCTION(name, ...) fmi2Status name(__VA_ARGS__) { return fmi2Error; }
#pragma GCC diagnostic ignored "-Wunused-parameter"
OK_FUNCTION(fmi2SetDebugLogging, fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[])
OK_FUNCTION(fmi2SetupExperiment, fmi2Component c, fmi2Boolean td, fmi2Real tol, fmi2Real t0,
            fmi2Boolean sd, fmi2Real t1)
OK_FUNCTION(fmi2EnterInitializationMode, fmi2Component c)
OK_FUNCTION(fmi2ExitInitializationMode, fmi2Component c)
OK_FUNCTION(fmi2Terminate, fmi2Component c)
OK_FUNCTION(fmi2CancelStep, fmi2Component c)
ERROR_FUNCTION(fmi2Reset, fmi2Component c)
ERROR_FUNCTION(fmi2SetBoolean, fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[])
ERROR_FUNCTION(fmi2GetString, fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[])
ERROR_FUNCTION(fmi2SetString, fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[])
ERROR_FUNCTION(fmi2GetStatus, fmi2Component c, const fmi2StatusKind s, fmi2Status *v)
ERROR_FUNCTION(fmi2GetIntegerStatus, fmi2Component c, const fmi2StatusKind s, fmi2Integer *v)
ERROR_FUNCTION(fmi2GetStringStatus, fmi2Component c, const fmi2StatusKind s, fmi2String *v)
ERROR_FUNCTION(fmi2GetFMUstate, fmi2Component c, fmi2FMUstate *s)
ERROR_FUNCTION(fmi2SetFMUstate, fmi2Component c, fmi2FMUstate s)
ERROR_FUNCTION(fmi2FreeFMUstate, fmi2Component c, fmi2FMUstate *s)
ERROR_FUNCTION(fmi2SerializedFMUstateSize, fmi2Component c, fmi2FMUstate s, size_t *n)
ERROR_FUNCTION(fmi2SerializeFMUstate, fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n)
ERROR_FUNCTION(fmi2DeSerializeFMUstate, fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s)
ERROR_FUNCTION(fmi2GetDirectionalDerivative, fmi2Component c, const fmi2ValueReference u[], size_t nu,
               const fmi2ValueReference z[], size_t nz, const fmi2Real du[], fmi2Real dz[])
ERROR_FUNCTION(fmi2SetRealInputDerivatives, fmi2Component c, const fmi2ValueReference vr[], size_t n,
               const fmi2Integer order[], const fmi2Real v[])
ERROR_FUNCTION(fmi2GetRealOutputDerivatives, fmi2Component c, const fmi2ValueReference vr[], size_t n,
               const fmi2Integer order[], fmi2Real v[])
