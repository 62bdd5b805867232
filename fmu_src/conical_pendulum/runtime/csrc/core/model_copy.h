/* The model's own C (model.c, dynamics.c, chain.c) compiled again in another number type:
 * directional.c's copy in double complex, second_directional.c's in long double complex.
 * Each defines CP_COMPLEX_STEP (real.h's cp_real) and CP_COPY_SUFFIX, then includes this
 * file, which renames the model's external names with that suffix so that one binary
 * carries the real model and its copies. One list for every copy: a function the model
 * gains is renamed in each (one left out is defined twice at link time). */
#ifndef CP_COPY_SUFFIX
#error "define CP_COPY_SUFFIX, the suffix of the copy's names, before including model_copy.h"
#endif
/* Complex products and quotients by the textbook formulas (GCC's -fcx-limited-range), not
 * C99 Annex G's library calls that sort out infinities and NaNs: a complex step has neither
 * (its parts are finite or the evaluation fails), and the calls cost most of its time. */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("cx-limited-range")
#endif
#define CP_COPY_PASTE_(name, suffix) name##suffix
#define CP_COPY_PASTE(name, suffix) CP_COPY_PASTE_(name, suffix)
#define cp_rhs CP_COPY_PASTE(cp_rhs, CP_COPY_SUFFIX)
#define cp_rope_law CP_COPY_PASTE(cp_rope_law, CP_COPY_SUFFIX)
#define cp_rope_tension_rates CP_COPY_PASTE(cp_rope_tension_rates, CP_COPY_SUFFIX)
#define cp_chain_rhs CP_COPY_PASTE(cp_chain_rhs, CP_COPY_SUFFIX)
#define cp_eval_outputs CP_COPY_PASTE(cp_eval_outputs, CP_COPY_SUFFIX)
#define cp_mass_forcing CP_COPY_PASTE(cp_mass_forcing, CP_COPY_SUFFIX)
#define cp_outputs CP_COPY_PASTE(cp_outputs, CP_COPY_SUFFIX)
#define cp_joint CP_COPY_PASTE(cp_joint, CP_COPY_SUFFIX)
#define cp_momentum CP_COPY_PASTE(cp_momentum, CP_COPY_SUFFIX)
#define cp_work_rates CP_COPY_PASTE(cp_work_rates, CP_COPY_SUFFIX)
#define cp_energy CP_COPY_PASTE(cp_energy, CP_COPY_SUFFIX)
#define cp_chain_rates_and_apparent_mass CP_COPY_PASTE(cp_chain_rates_and_apparent_mass, CP_COPY_SUFFIX)

#include "model.c"
#include "dynamics.c"
#include "chain.c"
