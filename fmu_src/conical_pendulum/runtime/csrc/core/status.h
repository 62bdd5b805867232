/* Status codes of the core (solvers and right-hand side) and their messages: the one list.
 * The solvers' own codes are below 10; a right-hand side stops an integration with a code
 * of 10 or more, which the solver passes on as it is. */
#ifndef CP_STATUS_H
#define CP_STATUS_H

#define CP_STATUS_LIST(X) \
    X(CP_OK, 0, "ok") \
    X(CP_TOO_MANY_STEPS, 1, "too many steps") \
    X(CP_STEP_UNDERFLOW, 2, "step size underflow") \
    X(CP_BAD_STEP, 3, "invalid communication step") \
    X(CP_MAX_STEP_UNRESOLVED, 4, "max_step below the resolution of time") \
    X(CP_STIFF, 5, "too many steps: the scene is stiff") \
    X(CP_SINGULAR, 10, "singular mass matrix") \
    X(CP_NONFINITE, 11, "non-finite acceleration") \
    X(CP_ROPE_RANGE, 12, "a rope's length left its range") \
    X(CP_ROPE_SLACK, 13, "a rope went slack")

#define CP_STATUS_ENUM(name, code, text) name = code,
enum { CP_STATUS_LIST(CP_STATUS_ENUM) };
#undef CP_STATUS_ENUM

#define CP_STATUS_CODE(name, code, text) code,
static const int cp_status_codes[] = { CP_STATUS_LIST(CP_STATUS_CODE) };
#undef CP_STATUS_CODE
#define CP_NSTATUS ((int)(sizeof cp_status_codes / sizeof cp_status_codes[0]))

/* The message of a status code, or NULL for a code that is not one. */
static inline const char *cp_status_message(int status)
{
#define CP_STATUS_CASE(name, code, text) case code: return text;
    switch (status) { CP_STATUS_LIST(CP_STATUS_CASE) }
#undef CP_STATUS_CASE
    return 0;
}

#endif
