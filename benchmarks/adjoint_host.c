/* Times the model contract's adjoint (model_adjoint_derivative) against its directional
 * derivatives (model_directional_derivative) for a few rows of the Jacobian, in C.
 *
 *   adjoint_host STATES INPUTS ROWS CALLS REPEATS
 *
 * STATES, INPUTS, ROWS: comma-separated value references ("-" for none); the knowns are the
 * states and the inputs, the rows unknowns (outputs or state derivatives). Compiled with a
 * native FMU's model sources (all but its FMI glue) by benchmarks/adjoint_cost.py. One
 * ModelData at a fixed state (angles and rates 0.3 sin(k + 1), inputs 0.5). Each operation is
 * timed over CALLS calls, REPEATS times, the operations interleaved; prints per operation one
 * line "name microseconds_per_call", the median over the repeats:
 *   rhs          model_set_states and model_get_derivatives (one right-hand side)
 *   set          model_set_states alone
 *   outputs      model_set_states and model_get_real of the first row (every output computed)
 *   adjoint      one adjoint per row, over every known (ROWS calls)
 *   directional  one directional derivative per known, of every row at once (knowns calls)
 *   directional_per_row  one directional derivative per known and row (ROWS x knowns calls)
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmu_model.h"
#include "timing_host.h"

#define MESSAGE 2048

enum { RHS, SET, OUTPUTS, ADJOINT, DIRECTIONAL, PER_ROW, N_OPERATION };
static const char *const names[N_OPERATION] = {"rhs", "set", "outputs", "adjoint", "directional",
                                               "directional_per_row"};

static unsigned knowns[MAX_VR], rows[MAX_VR];
static size_t n_known, n_state, n_row;
static double x[MAX_VR], sink;
static char message[MESSAGE];

static int run(ModelData *m, int operation)
{
    double out[MAX_VR], one = 1.0;
    switch (operation) {
    case RHS:
        if (model_set_states(m, x, message, MESSAGE)) return 1;
        if (model_get_derivatives(m, out, 0.0, message, MESSAGE) != MODEL_OK) return 1;
        break;
    case SET:
        if (model_set_states(m, x, message, MESSAGE)) return 1;
        break;
    case OUTPUTS:
        if (model_set_states(m, x, message, MESSAGE)) return 1;
        if (model_get_real(m, rows[0], out, 0.0, message, MESSAGE) != MODEL_OK) return 1;
        break;
    case ADJOINT:
        for (size_t i = 0; i < n_row; i++)
            if (model_adjoint_derivative(m, rows + i, 1, knowns, n_known, &one, out, 0.0, message,
                                         MESSAGE) != MODEL_OK)
                return 1;
        break;
    case DIRECTIONAL:
        for (size_t j = 0; j < n_known; j++)
            if (model_directional_derivative(m, rows, n_row, knowns + j, 1, &one, out, 0.0,
                                             message, MESSAGE) != MODEL_OK)
                return 1;
        break;
    case PER_ROW:
        for (size_t i = 0; i < n_row; i++)
            for (size_t j = 0; j < n_known; j++)
                if (model_directional_derivative(m, rows + i, 1, knowns + j, 1, &one, out, 0.0,
                                                 message, MESSAGE) != MODEL_OK)
                    return 1;
        break;
    }
    sink += out[0];
    return 0;
}

int main(int argc, char **argv)
{
    if (argc != 6) {
        fprintf(stderr, "usage: adjoint_host STATES INPUTS ROWS CALLS REPEATS\n");
        return 2;
    }
    unsigned inputs[MAX_VR];
    n_state = parse(argv[1], knowns);
    size_t n_input = parse(argv[2], inputs);
    n_row = parse(argv[3], rows);
    long calls = atol(argv[4]), repeats = atol(argv[5]);
    n_known = n_state + n_input;
    memcpy(knowns + n_state, inputs, n_input * sizeof inputs[0]);
    ModelData *m = calloc(1, model_sizes.data_size + model_sizes.scratch_size);
    if (!m) return 1;
    model_reset(m);
    for (size_t k = 0; k < n_input; k++) model_set_real(m, inputs[k], 0.5);
    model_initialize(m);
    for (size_t k = 0; k < n_state; k++) x[k] = 0.3 * sin(k + 1.0);
    double *times = calloc((size_t)repeats * N_OPERATION, sizeof(double));
    for (long r = 0; r < repeats; r++)
        for (int op = 0; op < N_OPERATION; op++) {
            long n = op <= OUTPUTS ? calls * (long)n_known : calls;
            double start = now();
            for (long c = 0; c < n; c++)
                if (run(m, op)) {
                    fprintf(stderr, "%s failed: %s\n", names[op], message);
                    return 1;
                }
            times[op * repeats + r] = (now() - start) / n * 1e6;
        }
    for (int op = 0; op < N_OPERATION; op++) {
        qsort(times + op * repeats, repeats, sizeof(double), compare);
        printf("%s %.6g\n", names[op], times[op * repeats + repeats / 2]);
    }
    free(times);
    free(m);
    return sink == 12345.678;  /* keeps the results alive */
}
