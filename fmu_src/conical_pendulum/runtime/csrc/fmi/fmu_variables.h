/* The variable table read: a variable's name, when it may be set, and its part in directional
 * derivatives, by value reference. Hand-written C over the data a model's generated
 * fmu_config.h holds (builder/native.py, config_header), which includes this header after
 * defining:
 *   CP_NVARIABLE             the number of variables (value references 0 to CP_NVARIABLE - 1);
 *   cp_names[]               their names, by value reference;
 *   CP_SET_NEVER, CP_SET_BEFORE_INIT, CP_SET_ALWAYS, and cp_settable[CP_NVARIABLE], one of
 *                            them per variable (its causality, variability and initial);
 *   CP_CALCULATED_MESSAGE, CP_FIXED_MESSAGE
 *                            the refusals of a calculated and of a fixed variable, printf
 *                            formats of one %s, the name (runtime/rules.py's CALCULATED, FIXED);
 *   CP_KNOWN, CP_UNKNOWN, and cp_role[CP_NVARIABLE], their bits per variable.
 * The FMI layers read names only (cp_variable_name); the models all four. */
#ifndef CP_FMU_VARIABLES_H
#define CP_FMU_VARIABLES_H

#include <stddef.h>
#include <stdio.h>

/* A variable's name by value reference (Reals, then Integers, then derivatives); "?" for no
 * variable. */
static inline const char *cp_variable_name(unsigned vr)
{
    return vr < CP_NVARIABLE ? cp_names[vr] : "?";
}

/* NULL if the variable may be set now, or why not: a calculated variable never, a fixed one (a
 * parameter or a setting) only before the model is initialized, an input always. */
static inline const char *cp_not_settable(unsigned vr, int initialized, char *message, size_t size)
{
    const int how = vr < CP_NVARIABLE ? cp_settable[vr] : CP_SET_NEVER;
    if (how == CP_SET_NEVER) snprintf(message, size, CP_CALCULATED_MESSAGE, cp_variable_name(vr));
    else if (how == CP_SET_BEFORE_INIT && initialized)
        snprintf(message, size, CP_FIXED_MESSAGE, cp_variable_name(vr));
    else return NULL;
    return message;
}

/* NULL if the variable may be a known of a directional derivative (a state or an input), or
 * the refusal. */
static inline const char *cp_known_refusal(unsigned vr, char *message, size_t size)
{
    if (vr < CP_NVARIABLE && (cp_role[vr] & CP_KNOWN)) return NULL;
    snprintf(message, size, "value reference %u (%s) as a known: only states and inputs are", vr,
             cp_variable_name(vr));
    return message;
}

/* NULL if the variable may be an unknown (an output, a state among them, or a state
 * derivative), or the refusal. */
static inline const char *cp_unknown_refusal(unsigned vr, char *message, size_t size)
{
    if (vr < CP_NVARIABLE && (cp_role[vr] & CP_UNKNOWN)) return NULL;
    snprintf(message, size, "value reference %u (%s) as an unknown: only outputs and state "
             "derivatives are", vr, cp_variable_name(vr));
    return message;
}

#endif
