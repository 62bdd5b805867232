/* fmi_host.c's FMI 3.0 twin: a small Co-Simulation host that is not Python. POSIX (dlopen) or
 * Windows (LoadLibrary; cross-compiled and run under wine).
 *
 *   fmi3_host LIBRARY TOKEN STOP STEP CYCLES OUT_VRS [VR=VALUE ...]
 *
 * OUT_VRS: comma-separated value references, each VR or VR:N for an array of N values (one
 * fmi3GetFloat64 reads them all). VR=VALUE sets a Float64 scalar, VR=V1:V2:... an array, before
 * initialization. Runs CYCLES times (instantiate, simulate, free) and prints the last cycle
 * as CSV: time, then the values. Exit status 1 on any FMI status other than fmi3OK.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

#ifdef _WIN32
#include <windows.h>
#define OPEN(path) LoadLibraryA(path)
#define SYMBOL(library, name) ((void *)GetProcAddress((HMODULE)(library), name))
#define CLOSE(library) FreeLibrary((HMODULE)(library))
#define OPEN_ERROR "LoadLibrary failed"
#else
#include <dlfcn.h>
#define OPEN(path) dlopen(path, RTLD_NOW | RTLD_LOCAL)
#define SYMBOL(library, name) dlsym(library, name)
#define CLOSE(library) dlclose(library)
#define OPEN_ERROR dlerror()
#endif

#define MAX_VALUES 256
#define MAX_SETS 32

static void log_message(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                        fmi3String message)
{
    (void)env;
    fprintf(stderr, "%s (status %d): %s\n", category, status, message);
}

#define LOAD(name) fmi3##name##TYPE *name = (fmi3##name##TYPE *)SYMBOL(library, "fmi3" #name); \
    if (!name) { fprintf(stderr, "missing fmi3" #name "\n"); return 1; }
#define CHECK(call) do { if ((call) != fmi3OK) { fprintf(stderr, "failed: " #call "\n"); return 1; } } while (0)

int main(int argc, char **argv)
{
    if (argc < 7) {
        fprintf(stderr, "usage: %s LIBRARY TOKEN STOP STEP CYCLES OUT_VRS [VR=VALUE ...]\n", argv[0]);
        return 2;
    }
    void *library = OPEN(argv[1]);
    if (!library) { fprintf(stderr, "%s: %s\n", argv[1], OPEN_ERROR); return 1; }
    LOAD(InstantiateCoSimulation) LOAD(FreeInstance) LOAD(EnterInitializationMode)
    LOAD(ExitInitializationMode) LOAD(Terminate) LOAD(SetFloat64) LOAD(GetFloat64) LOAD(DoStep)
    const char *token = argv[2];
    const double stop = atof(argv[3]), step = atof(argv[4]);
    const int cycles = atoi(argv[5]);

    fmi3ValueReference outputs[MAX_VALUES];
    size_t n_outputs = 0, n_values = 0;
    for (char *item = strtok(argv[6], ","); item && n_outputs < MAX_VALUES; item = strtok(NULL, ",")) {
        outputs[n_outputs++] = (fmi3ValueReference)atoi(item);
        const char *count = strchr(item, ':');
        n_values += count ? (size_t)atoi(count + 1) : 1;
    }
    if (n_values > MAX_VALUES) return 2;

    fmi3ValueReference set_vr[MAX_SETS];
    fmi3Float64 set_values[MAX_SETS][MAX_VALUES];
    size_t set_count[MAX_SETS], n_sets = 0;
    for (int k = 7; k < argc && n_sets < MAX_SETS; k++, n_sets++) {
        set_vr[n_sets] = (fmi3ValueReference)atoi(argv[k]);
        set_count[n_sets] = 0;
        for (char *value = strchr(argv[k], '='); value && set_count[n_sets] < MAX_VALUES;
             value = strchr(value + 1, ':'))
            set_values[n_sets][set_count[n_sets]++] = atof(value + 1);
    }

    const long steps = (long)(stop / step + 0.5);
    for (int cycle = 0; cycle < cycles; cycle++) {
        const int last = cycle == cycles - 1;
        fmi3Instance c = InstantiateCoSimulation("host", token, "", fmi3False, fmi3False, fmi3False,
                                                 fmi3False, NULL, 0, NULL, log_message, NULL);
        if (!c) { fprintf(stderr, "fmi3InstantiateCoSimulation failed\n"); return 1; }
        for (size_t s = 0; s < n_sets; s++)
            CHECK(SetFloat64(c, &set_vr[s], 1, set_values[s], set_count[s]));
        CHECK(EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3True, stop));
        CHECK(ExitInitializationMode(c));
        for (long n = 0; n <= steps; n++) {
            const double time = n * step;
            if (n) {
                fmi3Boolean event, terminate, early;
                fmi3Float64 reached;
                CHECK(DoStep(c, (n - 1) * step, time - (n - 1) * step, fmi3True, &event, &terminate,
                             &early, &reached));
                (void)reached;
                if (early) { fprintf(stderr, "returned early\n"); return 1; }
            }
            if (!last) continue;
            fmi3Float64 values[MAX_VALUES];
            CHECK(GetFloat64(c, outputs, n_outputs, values, n_values));
            printf("%.17g", time);
            for (size_t k = 0; k < n_values; k++) printf(",%.17g", values[k]);
            printf("\n");
        }
        CHECK(Terminate(c));
        FreeInstance(c);
    }
    CLOSE(library);
    return 0;
}
