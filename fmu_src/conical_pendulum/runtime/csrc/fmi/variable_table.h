/* A model's variables by value reference, read from the tables its generated fmu_config.h
 * holds (cp_names, cp_settable, cp_role: data only, written by builder/fmi/fmu_config.py): the
 * name of a variable, and whether it may be set now, or taken as a known or an unknown of a
 * directional derivative. Every model behind fmu_model.h compiles variable_table.c. */
#ifndef CP_VARIABLE_TABLE_H
#define CP_VARIABLE_TABLE_H

#include <stddef.h>

/* cp_settable's values: when a variable may be set (its causality, variability, initial):
 * never, before initialization (a fixed parameter), always (an input), or also at events (a
 * tunable parameter: at a communication point or in event mode, not in continuous-time mode). */
enum { CP_SET_NEVER, CP_SET_BEFORE_INIT, CP_SET_ALWAYS, CP_SET_AT_EVENTS };

/* cp_role's bits: the directional derivatives' knowns (states, inputs and Real parameters)
 * and unknowns (outputs, states among them, and state derivatives). */
enum { CP_KNOWN = 1, CP_UNKNOWN = 2 };

/* A variable's name by value reference (Reals, then Integers, then derivatives); "?" for
 * none. */
const char *cp_variable_name(unsigned vr);

/* NULL if the variable may be set now, in phase (fmu_model.h's ModelPhase), or why not (in
 * message): a calculated variable never, a fixed one (a parameter or a setting) only before
 * the model is initialized, a tunable one but in continuous-time mode, an input always. */
const char *cp_not_settable(unsigned vr, int phase, char *message, size_t size);

/* NULL if the variable is a known of a directional derivative (a state, an input or a Real
 * parameter), or why not (in message). */
const char *cp_known_refusal(unsigned vr, char *message, size_t size);

/* NULL if the variable is an unknown of a directional derivative (an output or a state
 * derivative), or why not (in message). */
const char *cp_unknown_refusal(unsigned vr, char *message, size_t size);

#endif
