#include "diagnosis.h"

#include <math.h>
#include <stdio.h>

#include "model.h"
#include "solvers.h"

int cp_rope_hint(char *buf, size_t size, int status, const cp_failure *f)
{
    if (status == CP_ROPE_RANGE)
        return snprintf(buf, size, "at t = %.9g s rope l%d's length is %.9g m, outside its range "
                        "[%g, %g] m (the scene's rope min and max): its winch (v_hoist%d) must "
                        "stop or turn before", f->at, f->rope, f->value, f->low, f->high, f->rope);
    return snprintf(buf, size, "at t = %.9g s rope l%d's tension T_rope%d is %.9g N: a rope "
                    "cannot push, and this model keeps its ropes taut, so it cannot go on", f->at,
                    f->rope, f->rope, f->value);
}

int cp_diagnose(char *buf, size_t size, int status, const cp_failure *f)
{
#ifdef CP_NELASTIC
    const int n = (CP_NDOF - CP_NELASTIC) / 2;  /* the links; the elastic ropes' v_r after */
#else
    const int n = CP_NDOF / 2;
#endif
    const int dof = f->bad_dof;
    char speed[32] = "?", link[16] = "?", joint[256], hint[768];
    if (dof >= 0 && dof < 2 * n) {
        snprintf(speed, sizeof speed, "%s%d", dof < n ? "omega" : "delta", dof % n);
        snprintf(link, sizeof link, "%d", dof % n);
    }
#ifdef CP_NELASTIC
    else if (dof >= 2 * n && dof < CP_NDOF) {
        const int rope = cp_rope_link[cp_elastic_rope[dof - 2 * n]];
        snprintf(speed, sizeof speed, "v_r%d", rope);
        snprintf(link, sizeof link, "%d", rope);
    }
#endif
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
    case CP_ROPE_RANGE:
    case CP_ROPE_SLACK:
        cp_rope_hint(hint, sizeof hint, status, f);
        break;
    case CP_STIFF:
        snprintf(hint, sizeof hint, "more than max_steps = %lld internal steps were needed, each "
                 "held short by stability, not by accuracy: the scene is stiff (a mode at |lambda| "
                 "= %.3g 1/s, which keeps %s's steps below %.3g s whatever the tolerance); choose "
                 "solver = %d (radau) or %d (auto), whose steps follow accuracy alone",
                 f->max_steps, f->stiffness, f->method == CP_RK45 ? "RK45" : "DOP853",
                 f->stiffness > 0 ? cp_stiffness_bound(f->method) / f->stiffness : INFINITY,
                 CP_RADAU, CP_AUTO);
        break;
    case CP_MAX_STEP_UNRESOLVED:
        snprintf(hint, sizeof hint, "max_step = %g s is shorter than what time t = %.9g s can "
                 "resolve (%g s): raise max_step, or set it to 0 (no limit)", f->max_step,
                 f->t + f->dt, cp_min_step(f->t, f->t + f->dt));
        break;
    default: {
        int used;
        double fewest = cp_fewest_steps(f->dt, f->max_step);
        if (status == CP_TOO_MANY_STEPS && fewest > (double)f->max_steps)
            used = snprintf(hint, sizeof hint, "max_step = %g s splits this step into %.3g "
                            "internal steps, more than max_steps = %lld: raise max_step or "
                            "max_steps, or take shorter communication steps (nothing was "
                            "integrated)", f->max_step, fewest, f->max_steps);
        else if (status == CP_TOO_MANY_STEPS)
            used = snprintf(hint, sizeof hint, "more than max_steps = %lld internal steps were "
                            "needed; raise max_steps, loosen rtol = %g / atol = %g, or take "
                            "shorter communication steps", f->max_steps, f->rtol, f->atol);
        else
            used = snprintf(hint, sizeof hint, "the step size fell below what time t can "
                            "resolve; rtol = %g / atol = %g cannot be met here: loosen them",
                            f->rtol, f->atol);
        if (f->pivot_ratio < CP_NEAR_SINGULAR && used >= 0 && (size_t)used < sizeof hint)
            snprintf(hint + used, sizeof hint - used, ". The mass matrix came close to singular "
                     "on the way (pivot ratio %.2g, at %s): %s", f->pivot_ratio, speed, joint);
    }
    }
    const char *what = cp_status_message(status);
    return snprintf(buf, size, "do_step from t = %.9g s by %.3g s failed: %s. %s. The state is "
                    "kept at t = %.9g s.", f->t, f->dt, what ? what : "unknown status", hint, f->kept);
}
