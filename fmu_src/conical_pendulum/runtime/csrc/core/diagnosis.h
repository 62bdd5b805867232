/* What a user reads when a step fails: what failed, why, and what to do; for every FMU. */
#ifndef CP_DIAGNOSIS_H
#define CP_DIAGNOSIS_H

#include <stddef.h>

#include "status.h"

/* Pivot ratio below which a failure for another reason also names the near-singular joint. */
#define CP_NEAR_SINGULAR 1e-8

typedef struct {
    double t, dt;         /* the communication step that failed */
    int bad_dof;          /* cp_model.bad_dof: the generalized speed at fault, or -1 */
    double pivot_ratio;   /* cp_model.pivot_ratio over the step */
    double rtol, atol, max_step;  /* the settings the step ran with */
    long long max_steps;
    double kept;          /* the time the state is kept at: t, or where an early return stopped */
    int rope;             /* CP_ROPE_RANGE, CP_ROPE_SLACK: the rope's link */
    double at, value;     /* ... the time it was found at and its length [m] or tension [N] */
    double low, high;     /* ... its length's range [m] */
    int method;           /* CP_STIFF: the solver whose steps stability bounded */
    double stiffness;     /* ... |lambda| [1/s] its stiffness test estimated */
} cp_failure;

/* What is wrong with a rope (status CP_ROPE_RANGE or CP_ROPE_SLACK, failure's rope fields):
 * "at t = ... s rope l<i>'s length is ... m, outside its range ..." into buf, as snprintf. */
int cp_rope_hint(char *buf, size_t size, int status, const cp_failure *failure);

/* Writes "do_step from t = ... failed: <status>. <diagnosis>. The state is kept ..." into
 * buf (NUL-terminated, cut at size bytes); returns the length the whole message needs. */
int cp_diagnose(char *buf, size_t size, int status, const cp_failure *failure);

#endif
