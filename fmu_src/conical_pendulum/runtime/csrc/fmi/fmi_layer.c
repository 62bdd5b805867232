/* What the FMI layers share that is not the standards' types (fmi_layer.h). */
#include <stdio.h>
#include <string.h>

#include "fmi_layer.h"

void fmi_machine_reset(FmiMachine *machine, int state)
{
    memset(machine, 0, sizeof *machine);
    machine->state = state;
}

const char *fmi_state_name(int state, const char *const names[], int n)
{
    for (int k = 0; k < n; k++)
        if (state == 1 << k) return names[k];
    return "?";
}

const char *fmi_refusal_reason(int cs, int allowed, int other, const char *never,
                               const char *otherwise)
{
    if (!allowed && other) return cs ? ": a Model Exchange function" : ": a Co-Simulation function";
    return allowed ? otherwise : never;
}

int fmi_set_logging(unsigned *logging, int on, size_t n, const char *const categories[],
                    const char *const names[], int n_names, const char *function, char *refusal,
                    size_t size)
{
    if (n && !categories) {
        snprintf(refusal, size, "%s: categories is NULL", function);
        return 1;
    }
    unsigned listed = 0;
    for (size_t k = 0; k < n; k++) {
        int found = -1;
        for (int j = 0; j < n_names && categories[k]; j++)
            if (strcmp(categories[k], names[j]) == 0) found = j;
        if (found < 0) {
            char declared[512] = "";
            for (int j = 0, used = 0; j < n_names && used < (int)sizeof declared; j++)
                used += snprintf(declared + used, sizeof declared - used, "%s%s", j ? ", " : "",
                                 names[j]);
            snprintf(refusal, size, "%s: log category \"%s\" is not this FMU's (its model "
                     "description declares %s)", function, categories[k] ? categories[k] : "(null)",
                     declared);
            return 1;
        }
        listed |= 1u << found;
    }
    const unsigned all = (1u << n_names) - 1;
    if (!n) *logging = on ? all : 0;
    else *logging = on ? listed : *logging & ~listed;
    return 0;
}

size_t fmi_state_header_size(const char *token)
{
    const size_t size = 2 * sizeof(unsigned) + strlen(token) + 1;
    return (size + sizeof(unsigned) - 1) / sizeof(unsigned) * sizeof(unsigned);
}

void fmi_state_header_write(void *bytes, unsigned magic, unsigned size, const char *token)
{
    unsigned char *out = bytes;
    memset(out, 0, fmi_state_header_size(token));
    memcpy(out, &magic, sizeof magic);
    memcpy(out + sizeof magic, &size, sizeof size);
    memcpy(out + 2 * sizeof(unsigned), token, strlen(token) + 1);
}

int fmi_state_header_matches(const void *bytes, unsigned magic, unsigned size, const char *token)
{
    const unsigned char *in = bytes;
    unsigned read_magic, read_size;
    memcpy(&read_magic, in, sizeof read_magic);
    memcpy(&read_size, in + sizeof read_magic, sizeof read_size);
    return read_magic == magic && read_size == size
           && memcmp(in + 2 * sizeof(unsigned), token, strlen(token) + 1) == 0;
}

void fmi_vlog(FmiEmit emit, void *context, int status, int always, unsigned logging, int category,
              const char *format, va_list args)
{
    if (!always && !(logging >> category & 1u)) return;
    char text[4096];
    vsnprintf(text, sizeof text, format, args);
    emit(context, status, category, text);
}
