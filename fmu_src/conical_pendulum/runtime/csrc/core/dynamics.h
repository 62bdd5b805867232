/* The model's right-hand side x' = f(x, p): in the expanded formulation the generated mass
 * matrix and forcing solved by dense LU, in the recursive one the articulated-body
 * algorithm (chain.c). */
#ifndef CP_DYNAMICS_H
#define CP_DYNAMICS_H

#include "model.h"
#include "status.h"

/* Pivot ratio below which M counts as singular: smallest over largest |pivot| of the LU
 * (expanded), or of a joint's 2x2 articulated inertia (recursive). */
#define CP_SINGULAR_RATIO 1e-13

/* The core's p: the parameters and inputs (CP_NPARAM, the FMU's first variables), then each
 * rope's l'' (Scene.ropes' order), then each elastic rope's tension and taut stretch, which
 * cp_rope_law computes from the state: no variable holds them. */
#ifdef CP_NROPE
#define CP_NHOIST_ACC CP_NROPE  /* the entries a caller gives after the parameters and inputs */
#else
#define CP_NHOIST_ACC 0
#endif
#if defined(CP_NELASTIC)
#define CP_PSIZE (CP_NPARAM + CP_NROPE + 3 * CP_NELASTIC)
#elif defined(CP_NROPE)
#define CP_PSIZE (CP_NPARAM + CP_NROPE)
#else
#define CP_PSIZE CP_NPARAM
#endif

/* Every value computed from x and p is a cp_real (real.h, included by model.h): double
 * here, double complex in directional.c's complex-step copy of this code. */
typedef struct {
    const cp_real *p;      /* the core's p (CP_PSIZE values): the parameters and inputs, in the
                              order of the scene's core parameter names, then each rope's l'' */
    double pivot_ratio;    /* smallest over largest |pivot| of the LUs since the caller set it
                              to 1: a cheap inverse condition estimate */
    int bad_dof;           /* generalized speed (column of M) of that smallest pivot, or of a
                              non-finite acceleration */
} cp_model;

/* x = (q, u, the books, the ropes' lengths), q the angles alpha, beta and the elastic ropes'
 * reaches r, u = q'; dx = (u, M^-1 F, the books' rates, the winches' speeds). ctx is a cp_model;
 * its p's elastic ropes' entries are not read (cp_rope_law fills a copy). */
int cp_rhs(void *ctx, const cp_real *x, cp_real *dx);

/* Each elastic rope's law at the state x into p's entries for it (the core's p, CP_PSIZE
 * values): its tension T = EA s / l + c s' while the rope is taut (stretch s = r - l > 0)
 * and pulls, else 0 (a rope cannot push, even stretched while it recoils faster than its
 * damping lets it pull), c = 2 zeta sqrt(EA / l m) with m the mass hanging from it; its
 * taut stretch max(s, 0), whose elastic energy the equations count; and its taut margin,
 * EA s / l + c min(s', 0), continuous in the state and > 0 exactly where the rope is taut:
 * the function whose roots are its slack and snap events. Nothing without elastic ropes. Not
 * analytic at the switches: its branches look at real parts (real.h). */
void cp_rope_law(const cp_real *x, cp_real *p);

/* Each elastic rope's tension's time derivative T' at the state x with x' = dx (p: the core's
 * p with the law filled by cp_rope_law, l'' among it): 0 while slack. Where the tension peaks
 * inside a step, T' changes sign (cosim.c's watch). */
void cp_rope_tension_rates(const cp_real *x, const cp_real *dx, const cp_real *p, cp_real *rates);

#if CP_RECURSIVE
/* cp_rhs of the recursive formulation (chain.c). */
int cp_chain_rhs(cp_model *model, const cp_real *x, cp_real *dx);
#if CP_PIVOT_INDEX >= 0
/* cp_chain_rhs, and the chain's apparent mass at the pivot, M_app in F_pivot = F_free -
 * M_app a_pivot (3x3, row-major): the linear block of the articulated inertia the support
 * sees through joint 0. */
int cp_chain_rates_and_apparent_mass(cp_model *model, const cp_real *x, cp_real *dx, cp_real M[9]);
#endif
#endif

/* The scene's outputs at x, p the core's p (cp_model). Those needing accelerations (the pivot
   force) get them from cp_rhs, and are NaN where the mass matrix is singular. */
void cp_eval_outputs(const cp_real *x, const cp_real *p, cp_real *y);

#endif
