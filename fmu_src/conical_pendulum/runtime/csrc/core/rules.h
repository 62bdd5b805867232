/* The value rules of runtime/rules.py as numbers: the table itself is generated into
 * fmu_config.h from that file, so C and Python apply the same rules with the same words. */
#ifndef CP_RULES_H
#define CP_RULES_H

#include <stddef.h>

typedef struct {
    double low;
    int low_open;         /* the value must exceed low, not only reach it */
    double high;          /* the value must stay below high */
    const char *refusal;  /* what a message says when the value breaks the rule */
    int whole;            /* the value must be a whole number (a count carried as a Real) */
} cp_rule;

/* rules.c: what every model of the package applies to a value set through an FMI layer (or
 * the pythonfmu slave) or restored from an FMU state, with the words of runtime/rules.py. */

/* A double as Python's repr writes it (1.5e-05, 0.001, -1.0, nan, inf), so that the FMUs'
 * messages read as runtime/rules.py's (the scene's, the build's) do. */
void cp_python_repr(char *buf, size_t size, double value);

/* NULL if value keeps the rule, or the message refusing it, "<name> = <shown>: must be
 * finite" or "<name> = <shown>: <what> <the rule's refusal>" (shown: the value as written). */
const char *cp_refusal(const char *name, const char *shown, double value, const cp_rule *rule,
                       const char *what, char *message, size_t size);

/* cp_refusal of a Real, shown as Python's repr. */
const char *cp_real_refusal(const char *name, double value, const cp_rule *rule, const char *what,
                            char *message, size_t size);

/* cp_refusal of an Integer, shown as a count reads (7, not 7.0). */
const char *cp_integer_refusal(const char *name, int value, const cp_rule *rule, const char *what,
                               char *message, size_t size);

#endif
