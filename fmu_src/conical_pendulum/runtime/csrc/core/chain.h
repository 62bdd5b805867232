/* The recursive formulation: the chain's dynamics by Featherstone's articulated-body
 * algorithm, in loops over the links, for long chains.
 *
 * The generated model.h says which bodies each link carries (cp_links: indices into p,
 * -1 where a body is absent), which outputs the scene wants and where gravity and the
 * pivot's acceleration are in p; the generated model.c gives one joint's kinematics
 * (cp_joint, from sympy.physics.mechanics). Everything else is generic and costs O(n):
 * no matrix of the size of the chain is formed to integrate it.
 */
#ifndef CP_CHAIN_H
#define CP_CHAIN_H

#include "real.h"

typedef struct {
    int l, m, M, Ixx, Iyy, Izz;  /* indices into p; m: -1 without a bob, M..Izz: -1 massless */
} cp_link_params;

/* One 'Space' 'ZXY' joint at angles (a, b): C, the child's axes in parent components
 * (3x3, row-major), and J, the relative angular velocity per angle rate in parent
 * components (3x2, row-major), with its derivatives dJ/da and dJ/db. */
void cp_joint(cp_real a, cp_real b, cp_real C[9], cp_real J[6], cp_real Ja[6], cp_real Jb[6]);

#endif
