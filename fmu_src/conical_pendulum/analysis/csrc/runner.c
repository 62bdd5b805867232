/* fmpy.simulate_fmu's communication loop for an FMI 2.0 Co-Simulation FMU (simulateCS,
 * without input signals), in C: the same communication points, the same calls in the same
 * order, the same rows. Any FMU: it calls the functions the host loaded from the FMU's own
 * library (analysis/runner.py hands their addresses over).
 *
 * Rows are written in numpy's packed layout of fmpy's record: time, the Reals, the Integers
 * (int32), the Booleans (one byte each). No allocation here: the host gives the buffers.
 * When the buffer is full the loop returns RUN_FULL with its progress kept in the Run, and
 * the host calls again with a larger buffer (a discarded step that does not terminate makes
 * fmpy record the same time again, so the row count is not known in advance). */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "fmi2FunctionTypes.h"

enum { RUN_DONE = 0, RUN_FULL = 1, RUN_FAILED = 2 };

/* which FMI function failed (runner.py names them in this order) */
enum { FAILED_DO_STEP, FAILED_GET_REAL, FAILED_GET_INTEGER, FAILED_GET_BOOLEAN,
       FAILED_GET_BOOLEAN_STATUS, FAILED_GET_REAL_STATUS };

typedef struct {
    fmi2DoStepTYPE *doStep;
    fmi2GetRealTYPE *getReal;
    fmi2GetIntegerTYPE *getInteger;
    fmi2GetBooleanTYPE *getBoolean;
    fmi2GetBooleanStatusTYPE *getBooleanStatus;
    fmi2GetRealStatusTYPE *getRealStatus;
    fmi2Component component;
    /* the recorded variables by type, and one row of their values */
    const fmi2ValueReference *realVrs, *integerVrs, *booleanVrs;
    size_t nReal, nInteger, nBoolean;
    fmi2Real *reals;
    fmi2Integer *integers;
    fmi2Boolean *booleans;
    /* the schedule */
    double startTime, stopTime, interval;
    int canHandleVariableStepSize;
    /* the record: capacity rows of rowSize bytes */
    char *rows;
    size_t rowSize, capacity;
    /* progress, kept between calls */
    double time;
    long long nSteps;
    size_t nRows;
    /* what failed: FAILED_* and the status it returned */
    int failedFunction, failedStatus;
} Run;

/* Python's math.isclose(a, b) with its defaults (rel_tol 1e-9, abs_tol 0) */
static int isclose(double a, double b)
{
    if (a == b) return 1;
    if (isinf(a) || isinf(b)) return 0;
    double diff = fabs(b - a);
    return diff <= fabs(1e-9 * b) || diff <= fabs(1e-9 * a);
}

static int failed(Run *run, int function, int status)
{
    run->failedFunction = function;
    run->failedStatus = status;
    return RUN_FAILED;
}

/* fmpy's Recorder.sample: getReal, getInteger, getBoolean for the types recorded; a status
 * above fmi2Warning fails the run as fmpy raises */
static int sample(Run *run)
{
    char *row = run->rows + run->nRows * run->rowSize;
    int status;
    memcpy(row, &run->time, sizeof(double));
    row += sizeof(double);
    if (run->nReal) {
        status = (int)run->getReal(run->component, run->realVrs, run->nReal, run->reals);
        if (status > fmi2Warning) return failed(run, FAILED_GET_REAL, status);
        memcpy(row, run->reals, run->nReal * sizeof(fmi2Real));
        row += run->nReal * sizeof(fmi2Real);
    }
    if (run->nInteger) {
        status = (int)run->getInteger(run->component, run->integerVrs, run->nInteger, run->integers);
        if (status > fmi2Warning) return failed(run, FAILED_GET_INTEGER, status);
        memcpy(row, run->integers, run->nInteger * sizeof(fmi2Integer));
        row += run->nInteger * sizeof(fmi2Integer);
    }
    if (run->nBoolean) {
        status = (int)run->getBoolean(run->component, run->booleanVrs, run->nBoolean, run->booleans);
        if (status > fmi2Warning) return failed(run, FAILED_GET_BOOLEAN, status);
        for (size_t k = 0; k < run->nBoolean; k++) row[k] = run->booleans[k] != fmi2False;
    }
    run->nRows++;
    return RUN_DONE;
}

/* From the start (nRows == 0: the first sample at the start time) or where the last call
 * stopped, to the stop time: RUN_DONE, RUN_FULL or RUN_FAILED. capacity is at least 1.
 * Statuses are compared as ints, as fmpy's ctypes reads them (an enum may be unsigned). */
__attribute__((visibility("default"))) int fmi2_cs_run(Run *run)
{
    if (run->nRows == 0 && sample(run) != RUN_DONE) return RUN_FAILED;
    for (;;) {
        if (run->time > run->stopTime || isclose(run->time, run->stopTime)) return RUN_DONE;
        if (run->nRows == run->capacity) return RUN_FULL;  /* an iteration records one row */
        double nextRegularPoint = run->startTime + (double)(run->nSteps + 1) * run->interval;
        double nextPoint = nextRegularPoint;
        if (nextPoint > run->stopTime && !isclose(nextPoint, run->stopTime)) {
            if (!run->canHandleVariableStepSize) return RUN_DONE;
            nextPoint = run->stopTime;
        }
        int status = (int)run->doStep(run->component, run->time, nextPoint - run->time, fmi2True);
        if (status <= fmi2Warning) {
            run->time = nextPoint;
        } else if (status == fmi2Discard) {
            fmi2Boolean terminated = fmi2False;
            status = (int)run->getBooleanStatus(run->component, fmi2Terminated, &terminated);
            if (status > fmi2Warning) return failed(run, FAILED_GET_BOOLEAN_STATUS, status);
            if (terminated) {
                fmi2Real lastSuccessfulTime = 0.0;
                status = (int)run->getRealStatus(run->component, fmi2LastSuccessfulTime, &lastSuccessfulTime);
                if (status > fmi2Warning) return failed(run, FAILED_GET_REAL_STATUS, status);
                run->time = lastSuccessfulTime;
                return sample(run);
            }
        } else {
            return failed(run, FAILED_DO_STEP, status);
        }
        if (sample(run) != RUN_DONE) return RUN_FAILED;
        if (isclose(run->time, nextRegularPoint)) run->nSteps++;
    }
}
