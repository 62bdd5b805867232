/* The value rules of runtime/rules.py as numbers: the table itself is generated into
 * fmu_config.h from that file, so C and Python apply the same rules with the same words. */
#ifndef CP_RULES_H
#define CP_RULES_H

typedef struct {
    double low;
    int low_open;         /* the value must exceed low, not only reach it */
    double high;          /* the value must stay below high */
    const char *refusal;  /* what a message says when the value breaks the rule */
    int whole;            /* the value must be a whole number (a count carried as a Real) */
} cp_rule;

#endif
