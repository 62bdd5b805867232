/* The variable table's readers (variable_table.h) over the generated fmu_config.h's data. */
#include "variable_table.h"

#include <stdio.h>

#include "fmu_config.h"
#include "fmu_model.h"

const char *cp_variable_name(unsigned vr)
{
    return vr < CP_NVARIABLE ? cp_names[vr] : "?";
}

const char *cp_not_settable(unsigned vr, int phase, char *message, size_t size)
{
    int how = vr < CP_NVARIABLE ? cp_settable[vr] : CP_SET_NEVER;
    if (how == CP_SET_NEVER) snprintf(message, size, CP_CALCULATED_MESSAGE, cp_variable_name(vr));
    else if (how == CP_SET_BEFORE_INIT && phase != MODEL_BEFORE_INIT)
        snprintf(message, size, CP_FIXED_MESSAGE, cp_variable_name(vr));
    else if (how == CP_SET_AT_EVENTS && phase == MODEL_CONTINUOUS_TIME)
        snprintf(message, size, CP_TUNABLE_MESSAGE, cp_variable_name(vr));
    else return NULL;
    return message;
}

const char *cp_known_refusal(unsigned vr, char *message, size_t size)
{
    if (vr < CP_NVARIABLE && (cp_role[vr] & CP_KNOWN)) return NULL;
    snprintf(message, size, "value reference %u (%s) as a known: only states, inputs and Real "
             "parameters are", vr, cp_variable_name(vr));
    return message;
}

const char *cp_unknown_refusal(unsigned vr, char *message, size_t size)
{
    if (vr < CP_NVARIABLE && (cp_role[vr] & CP_UNKNOWN)) return NULL;
    snprintf(message, size, "value reference %u (%s) as an unknown: only outputs and state "
             "derivatives are", vr, cp_variable_name(vr));
    return message;
}
