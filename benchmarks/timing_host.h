/* What the benchmarks' C hosts share: value references from the command line, a monotonic
 * clock, the comparison that sorts timings for their median; for a host of an FMU's
 * library (fmi2Functions.h included first), its logger and the LOAD and CHECK macros. */
#ifndef TIMING_HOST_H
#define TIMING_HOST_H

#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAX_VR 4096

/* Comma-separated value references ("-" for none) into out; how many. */
static inline size_t parse(const char *text, unsigned *out)
{
    size_t n = 0;
    if (strcmp(text, "-") == 0) return 0;
    for (const char *s = text; *s && n < MAX_VR; n++) {
        char *end;
        out[n] = (unsigned)strtoul(s, &end, 10);
        s = *end == ',' ? end + 1 : end;
    }
    return n;
}

static inline double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static inline int compare(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

#ifdef fmi2Functions_h /* a host of an FMU's library, loaded with dlopen */
#include <dlfcn.h>
#include <stdio.h>

static inline void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                          fmi2String category, fmi2String message, ...)
{
    (void)env, (void)name, (void)category;
    if (status != fmi2OK) fprintf(stderr, "[%d] %s\n", status, message);
}

#define LOAD(name) name##TYPE *name = (name##TYPE *)dlsym(lib, #name)
#define CHECK(call) do { if ((call) != fmi2OK) { fprintf(stderr, "failed: %s\n", #call); return 1; } } while (0)
#endif

#endif
