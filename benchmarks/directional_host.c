/* Times a native FMU's right-hand side against its directional derivatives, in C.
 *
 *   directional_host LIBRARY GUID STATES INPUTS DERIVATIVES OUTPUTS CALLS REPEATS
 *
 * STATES, INPUTS, DERIVATIVES, OUTPUTS: comma-separated value references ("-" for none).
 * One Model Exchange instance in continuous-time mode at a fixed state (angles and rates
 * 0.3 sin(k + 1), inputs 0.5). Each operation is timed over CALLS calls, REPEATS times,
 * the operations interleaved; every call is preceded by fmi2SetContinuousStates (so that
 * nothing is cached), which the "set" row times alone. Prints, per operation, one line
 * "name microseconds_per_call" with the median over the repeats.
 * Built by benchmarks/directional_cost.py.
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"
#include "timing_host.h"

enum { SET, RHS, OUTPUTS, DD_DERIVATIVES, DD_OUTPUTS, DD_BOTH, JACOBIAN, NOPS };
static const char *const names[NOPS] = {"set", "rhs", "outputs", "dd_derivatives", "dd_outputs",
                                         "dd_derivatives_and_outputs", "jacobian_states"};

int main(int argc, char **argv)
{
    if (argc != 9) {
        fprintf(stderr, "usage: %s LIBRARY GUID STATES INPUTS DERIVATIVES OUTPUTS CALLS REPEATS\n", argv[0]);
        return 2;
    }
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "%s\n", dlerror()); return 1; }
    static fmi2ValueReference states[MAX_VR], inputs[MAX_VR], der[MAX_VR], out[MAX_VR],
        both[2 * MAX_VR], known[2 * MAX_VR];
    size_t ns = parse(argv[3], states), ni = parse(argv[4], inputs), nd = parse(argv[5], der),
           no = parse(argv[6], out);
    long calls = atol(argv[7]);
    int repeats = atoi(argv[8]);
    LOAD(fmi2Instantiate); LOAD(fmi2SetupExperiment); LOAD(fmi2EnterInitializationMode);
    LOAD(fmi2ExitInitializationMode); LOAD(fmi2EnterContinuousTimeMode); LOAD(fmi2SetReal);
    LOAD(fmi2SetContinuousStates); LOAD(fmi2GetDerivatives); LOAD(fmi2GetReal);
    LOAD(fmi2GetDirectionalDerivative); LOAD(fmi2Terminate); LOAD(fmi2FreeInstance);
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("timing", fmi2ModelExchange, argv[2], "", &cb, fmi2False, fmi2False);
    if (!c) { fprintf(stderr, "instantiate failed\n"); return 1; }
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2ExitInitializationMode(c));
    CHECK(fmi2EnterContinuousTimeMode(c));
    static double x[MAX_VR], dx[MAX_VR], y[2 * MAX_VR], a[MAX_VR], seed[2 * MAX_VR];
    for (size_t k = 0; k < ns; k++) x[k] = 0.3 * sin((double)k + 1);
    for (size_t k = 0; k < ni; k++) a[k] = 0.5;
    if (ni) CHECK(fmi2SetReal(c, inputs, ni, a));
    for (size_t k = 0; k < ns; k++) known[k] = states[k];
    for (size_t k = 0; k < ni; k++) known[ns + k] = inputs[k];
    for (size_t k = 0; k < ns + ni; k++) seed[k] = cos(0.7 * (double)k + 0.2);  /* one direction */
    memcpy(both, der, nd * sizeof der[0]);
    memcpy(both + nd, out, no * sizeof out[0]);
    const double unit = 1.0;
    double *times = malloc(sizeof(double) * NOPS * (size_t)repeats);
    volatile double sink = 0;
    for (int r = 0; r < repeats; r++) {
        for (int op = 0; op < NOPS; op++) {
            double start = now();
            for (long i = 0; i < calls; i++) {
                CHECK(fmi2SetContinuousStates(c, x, ns));
                switch (op) {
                case SET: break;
                case RHS: CHECK(fmi2GetDerivatives(c, dx, ns)); break;
                case OUTPUTS: CHECK(fmi2GetReal(c, out, no, y)); break;
                case DD_DERIVATIVES:
                    CHECK(fmi2GetDirectionalDerivative(c, der, nd, known, ns + ni, seed, dx)); break;
                case DD_OUTPUTS:
                    CHECK(fmi2GetDirectionalDerivative(c, out, no, known, ns + ni, seed, y)); break;
                case DD_BOTH:
                    CHECK(fmi2GetDirectionalDerivative(c, both, nd + no, known, ns + ni, seed, y)); break;
                case JACOBIAN:  /* d(derivatives)/d(states), column by column */
                    for (size_t k = 0; k < ns; k++)
                        CHECK(fmi2GetDirectionalDerivative(c, der, nd, &states[k], 1, &unit, dx));
                    break;
                }
                sink += dx[0] + y[0];
            }
            times[op * repeats + r] = (now() - start) / (double)calls;
        }
    }
    for (int op = 0; op < NOPS; op++) {
        qsort(times + op * repeats, (size_t)repeats, sizeof(double), compare);
        printf("%s %.6g\n", names[op], 1e6 * times[op * repeats + repeats / 2]);
    }
    fmi2Terminate(c);
    fmi2FreeInstance(c);
    free(times);
    dlclose(lib);
    return sink == 12345.678;  /* keeps the loop's results alive */
}
