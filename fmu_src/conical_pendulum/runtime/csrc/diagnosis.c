#include "diagnosis.h"

#include <stdio.h>

#include "model.h"

int cp_diagnose(char *buf, size_t size, int status, const cp_failure *f)
{
    const int n = CP_NDOF / 2, dof = f->bad_dof;
    char speed[32] = "?", link[16] = "?", joint[256], hint[768];
    if (dof >= 0 && dof < CP_NDOF) {
        snprintf(speed, sizeof speed, "%s%d", dof < n ? "omega" : "delta", dof % n);
        snprintf(link, sizeof link, "%d", dof % n);
    }
    snprintf(joint, sizeof joint, "link %s's two-angle joint cannot represent this orientation "
             "(it lies along its parent's x axis, alpha = +-90 degrees) or a link has too little "
             "inertia", link);
    switch (status) {
    case CP_BAD_STEP:
        snprintf(hint, sizeof hint, "a communication step must be a non-negative finite number, "
                 "not %g", f->dt);
        break;
    case CP_SINGULAR:
        snprintf(hint, sizeof hint, "the mass matrix is singular (pivot ratio %.2g, at %s): %s; "
                 "give the link inertia or start elsewhere", f->pivot_ratio, speed, joint);
        break;
    case CP_NONFINITE:
        snprintf(hint, sizeof hint, "the acceleration of %s is not finite; check parameters and "
                 "state", speed);
        break;
    default: {
        int used = status == CP_TOO_MANY_STEPS
            ? snprintf(hint, sizeof hint, "more than max_steps = %ld internal steps were needed; "
                       "raise max_steps, loosen rtol = %g / atol = %g, or take shorter "
                       "communication steps", f->max_steps, f->rtol, f->atol)
            : snprintf(hint, sizeof hint, "the step size fell below what time t can resolve; "
                       "rtol = %g / atol = %g cannot be met here: loosen them", f->rtol, f->atol);
        if (f->pivot_ratio < CP_NEAR_SINGULAR && used >= 0 && (size_t)used < sizeof hint)
            snprintf(hint + used, sizeof hint - used, ". The mass matrix came close to singular "
                     "on the way (pivot ratio %.2g, at %s): %s", f->pivot_ratio, speed, joint);
    }
    }
    const char *what = cp_status_message(status);
    return snprintf(buf, size, "do_step from t = %.9g s by %.3g s failed: %s. %s. The state is "
                    "kept at t = %.9g s.", f->t, f->dt, what ? what : "unknown status", hint, f->t);
}
