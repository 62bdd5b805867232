#include "rules.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void cp_python_repr(char *buf, size_t size, double value)
{
    if (isnan(value)) { snprintf(buf, size, "nan"); return; }
    if (isinf(value)) { snprintf(buf, size, value > 0 ? "inf" : "-inf"); return; }
    int digits = 1;
    for (; digits < 17; digits++) {
        snprintf(buf, size, "%.*e", digits - 1, value);
        if (strtod(buf, NULL) == value) break;
    }
    snprintf(buf, size, "%.*e", digits - 1, value);  /* e.g. 1.5e-05, as Python writes it */
    int exponent = atoi(strchr(buf, 'e') + 1);
    if (exponent >= -4 && exponent < 16) {  /* Python writes these positionally */
        int decimals = digits - 1 - exponent;
        snprintf(buf, size, "%.*f", decimals < 1 ? 1 : decimals, value);
    }
}

const char *cp_refusal(const char *name, const char *shown, double value, const cp_rule *rule,
                       const char *what, char *message, size_t size)
{
    if (!isfinite(value)) {
        snprintf(message, size, "%s = %s: must be finite", name, shown);
        return message;
    }
    int holds = (rule->low_open ? value > rule->low : value >= rule->low) && value < rule->high
                && (!rule->whole || value == floor(value));
    if (holds) return NULL;
    snprintf(message, size, "%s = %s: %s%s%s", name, shown, what, *what ? " " : "", rule->refusal);
    return message;
}

const char *cp_real_refusal(const char *name, double value, const cp_rule *rule, const char *what,
                            char *message, size_t size)
{
    char shown[40];
    cp_python_repr(shown, sizeof shown, value);
    return cp_refusal(name, shown, value, rule, what, message, size);
}

const char *cp_integer_refusal(const char *name, int value, const cp_rule *rule, const char *what,
                               char *message, size_t size)
{
    char shown[16];
    snprintf(shown, sizeof shown, "%d", value);
    return cp_refusal(name, shown, value, rule, what, message, size);
}
