/* Times a native FMU's output derivatives against its right-hand side, in C.
 *
 *   output_derivatives_host LIBRARY GUID INPUT DERIVATIVES OUTPUTS CALLS REPEATS
 *
 * INPUT: the value reference of one input; DERIVATIVES, OUTPUTS: comma-separated value
 * references. One Co-Simulation instance after initialization; every call is preceded by
 * fmi2SetReal of INPUT, alternating between two values (so that nothing is cached), which the
 * "set" row times alone. Operations: rhs (fmi2GetReal of the state derivatives: one right-hand
 * side), outputs (fmi2GetReal of the outputs), first (fmi2GetRealOutputDerivatives, order 1
 * of every output), first_and_second (orders 1 and 2 of every output, one call), dd_outputs
 * (fmi2GetDirectionalDerivative of the outputs along the input). Prints one line
 * "name microseconds_per_call" per operation, the median over the repeats.
 * Built by benchmarks/output_derivatives_cost.py.
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"
#include "timing_host.h"

enum { SET, RHS, OUTPUTS, FIRST, BOTH, DD_OUTPUTS, NOPS };
static const char *const names[NOPS] = {"set", "rhs", "outputs", "first", "first_and_second",
                                         "dd_outputs"};

int main(int argc, char **argv)
{
    if (argc != 8) {
        fprintf(stderr, "usage: %s LIBRARY GUID INPUT DERIVATIVES OUTPUTS CALLS REPEATS\n", argv[0]);
        return 2;
    }
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "%s\n", dlerror()); return 1; }
    static fmi2ValueReference der[MAX_VR], out[MAX_VR], out2[2 * MAX_VR];
    static fmi2Integer orders[2 * MAX_VR];
    fmi2ValueReference input = (fmi2ValueReference)strtoul(argv[3], NULL, 10);
    size_t nd = parse(argv[4], der), no = parse(argv[5], out);
    long calls = atol(argv[6]);
    int repeats = atoi(argv[7]);
    LOAD(fmi2Instantiate); LOAD(fmi2SetupExperiment); LOAD(fmi2EnterInitializationMode);
    LOAD(fmi2ExitInitializationMode); LOAD(fmi2SetReal); LOAD(fmi2GetReal);
    LOAD(fmi2GetRealOutputDerivatives); LOAD(fmi2GetDirectionalDerivative); LOAD(fmi2Terminate);
    LOAD(fmi2FreeInstance);
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("timing", fmi2CoSimulation, argv[2], "", &cb, fmi2False, fmi2False);
    if (!c) { fprintf(stderr, "instantiate failed\n"); return 1; }
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2ExitInitializationMode(c));
    for (size_t k = 0; k < no; k++) {
        out2[k] = out2[no + k] = out[k];
        orders[k] = 1;
        orders[no + k] = 2;
    }
    static double dx[MAX_VR], y[2 * MAX_VR];
    const double values[2] = {0.5, 0.25}, unit = 1.0;
    double *times = malloc(sizeof(double) * NOPS * (size_t)repeats);
    volatile double sink = 0;
    for (int r = 0; r < repeats; r++) {
        for (int op = 0; op < NOPS; op++) {
            double start = now();
            for (long i = 0; i < calls; i++) {
                CHECK(fmi2SetReal(c, &input, 1, &values[i & 1]));
                switch (op) {
                case SET: break;
                case RHS: CHECK(fmi2GetReal(c, der, nd, dx)); break;
                case OUTPUTS: CHECK(fmi2GetReal(c, out, no, y)); break;
                case FIRST: CHECK(fmi2GetRealOutputDerivatives(c, out, no, orders, y)); break;
                case BOTH: CHECK(fmi2GetRealOutputDerivatives(c, out2, 2 * no, orders, y)); break;
                case DD_OUTPUTS:
                    CHECK(fmi2GetDirectionalDerivative(c, out, no, &input, 1, &unit, y)); break;
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
