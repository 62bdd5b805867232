/* What the FMI layers (fmi2_glue.c, fmi3_glue.c) share that is not the standards' types: the
 * machine an instance keeps besides the model's data, the name of its state, the parsing of
 * SetDebugLogging's categories, the header of a serialized FMU state and the formatting of a
 * message for the host's logger. Plain C: no FMI header, no fmu_config.h; each layer passes
 * its names, its token and its logger. */
#ifndef FMI_LAYER_H
#define FMI_LAYER_H

#include <stdarg.h>
#include <stddef.h>

/* Where an instance is in its standard's state machine (one bit per state), its time, and
 * the last time a step reached; plain data, saved and serialized as a whole. */
typedef struct {
    int state;
    double time;
    double last_successful_time;
} FmiMachine;

/* The machine as instantiation and Reset leave it, in state: zeroed, padding too (it is
 * serialized). */
void fmi_machine_reset(FmiMachine *machine, int state);

/* The name of a one-bit state word (bit k: names[k], n names), "?" for any other word. */
const char *fmi_state_name(int state, const char *const names[], int n);

/* Why a function is refused in its instance's state (allowed, other: the states of the
 * instance's interface's column and of the other's; cs: the instance is a Co-Simulation one):
 * ": a Model Exchange function" or ": a Co-Simulation function" if only the other interface
 * has it, never if neither has it, otherwise otherwise. */
const char *fmi_refusal_reason(int cs, int allowed, int other, const char *never,
                               const char *otherwise);

/* SetDebugLogging's rules (FMI 2.0, section 2.1.5; FMI 3.0, section 2.3.1): with n = 0, on
 * applies to every one of the n_names categories; with a list, on makes the listed ones the
 * categories in force, off turns the listed ones off and leaves the others. 0 with *logging
 * (bit k: category names[k]) updated; or 1 with *logging as it was and the refusal in
 * refusal, beginning with function: categories is NULL, or a name names[] does not hold
 * (named, with the declared ones). */
int fmi_set_logging(unsigned *logging, int on, size_t n, const char *const categories[],
                    const char *const names[], int n_names, const char *function, char *refusal,
                    size_t size);

/* A serialized FMU state begins with a header: magic, the size of what follows, and the
 * token (its terminating '\0' included) of the build that wrote it, padded to an unsigned's
 * alignment. Its size in bytes; writing it; whether bytes begin with the header of this magic,
 * size and token (nonzero if they do). */
size_t fmi_state_header_size(const char *token);
void fmi_state_header_write(void *bytes, unsigned magic, unsigned size, const char *token);
int fmi_state_header_matches(const void *bytes, unsigned magic, unsigned size, const char *token);

/* A message for the host's logger: formatted (at most 4095 characters) and handed to emit
 * with context, status and category, if it is reported: always when always is nonzero,
 * otherwise only when category's bit is on in logging. */
typedef void (*FmiEmit)(void *context, int status, int category, const char *text);
void fmi_vlog(FmiEmit emit, void *context, int status, int always, unsigned logging, int category,
              const char *format, va_list args);

#endif
