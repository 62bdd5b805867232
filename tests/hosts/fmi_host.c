/* A small FMI 2.0 Co-Simulation host that is not Python: load the library, the FMI calls, a
 * fixed step. POSIX (dlopen) or Windows (LoadLibrary; cross-compiled and run under wine).
 *
 *   fmi_host LIBRARY GUID STOP STEP CYCLES OUT_VRS [-- VR=VALUE ...]...
 *
 * Runs one instance per "--" group (side by side, stepped in turn), each with its Real
 * start values set by value reference, CYCLES times over (instantiate, simulate, free),
 * and prints the last cycle as CSV: time, then the OUT_VRS (comma-separated value
 * references) of each instance. Exit status 1 on any FMI status other than fmi2OK, which
 * leaves the instance and the library as they are (no free, no unload). The resource
 * location passed to fmi2Instantiate is $FMI_RESOURCE_LOCATION, empty if unset (the
 * native FMU needs none; the pythonfmu FMU finds its slave there).
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

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

#define MAX_INSTANCES 4
#define MAX_OUTPUTS 64
#define MAX_SETS 64

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    fprintf(stderr, "[%s] %s (status %d): %s\n", name, category, status, message);
}

#define LOAD(name) fmi2##name##TYPE *name = (fmi2##name##TYPE *)SYMBOL(library, "fmi2" #name); \
    if (!name) { fprintf(stderr, "missing fmi2" #name "\n"); return 1; }
#define CHECK(call) do { if ((call) != fmi2OK) { fprintf(stderr, "failed: " #call "\n"); return 1; } } while (0)

int main(int argc, char **argv)
{
    if (argc < 7) {
        fprintf(stderr, "usage: %s LIBRARY GUID STOP STEP CYCLES OUT_VRS [-- VR=VALUE ...]...\n",
                argv[0]);
        return 2;
    }
    void *library = OPEN(argv[1]);
    if (!library) { fprintf(stderr, "%s: %s\n", argv[1], OPEN_ERROR); return 1; }
    LOAD(Instantiate) LOAD(FreeInstance) LOAD(SetupExperiment) LOAD(EnterInitializationMode)
    LOAD(ExitInitializationMode) LOAD(Terminate) LOAD(SetReal) LOAD(GetReal) LOAD(DoStep)
    const char *guid = argv[2];
    const double stop = atof(argv[3]), step = atof(argv[4]);
    const int cycles = atoi(argv[5]);

    fmi2ValueReference outputs[MAX_OUTPUTS];
    size_t n_outputs = 0;
    for (char *token = strtok(argv[6], ","); token && n_outputs < MAX_OUTPUTS; token = strtok(NULL, ","))
        outputs[n_outputs++] = (fmi2ValueReference)atoi(token);

    fmi2ValueReference set_vr[MAX_INSTANCES][MAX_SETS];
    fmi2Real set_value[MAX_INSTANCES][MAX_SETS];
    size_t n_sets[MAX_INSTANCES] = {0};
    int n_instances = 0;
    for (int k = 7; k < argc; k++) {
        if (strcmp(argv[k], "--") == 0) {
            if (n_instances == MAX_INSTANCES) return 2;
            n_instances++;
        } else if (n_instances && n_sets[n_instances - 1] < MAX_SETS) {
            int i = n_instances - 1;
            set_vr[i][n_sets[i]] = (fmi2ValueReference)atoi(argv[k]);
            set_value[i][n_sets[i]++] = atof(strchr(argv[k], '=') + 1);
        }
    }
    if (!n_instances) n_instances = 1;

    const char *resources = getenv("FMI_RESOURCE_LOCATION");
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    const long steps = (long)(stop / step + 0.5);
    for (int cycle = 0; cycle < cycles; cycle++) {
        const int last = cycle == cycles - 1;
        fmi2Component c[MAX_INSTANCES];
        for (int i = 0; i < n_instances; i++) {
            char name[16];
            snprintf(name, sizeof name, "host%d", i);
            c[i] = Instantiate(name, fmi2CoSimulation, guid, resources ? resources : "", &callbacks,
                               fmi2False, fmi2False);
            if (!c[i]) { fprintf(stderr, "fmi2Instantiate failed\n"); return 1; }
            CHECK(SetReal(c[i], set_vr[i], n_sets[i], set_value[i]));
            CHECK(SetupExperiment(c[i], fmi2False, 0.0, 0.0, fmi2True, stop));
            CHECK(EnterInitializationMode(c[i]));
            CHECK(ExitInitializationMode(c[i]));
        }
        for (long n = 0; n <= steps; n++) {
            const double time = n * step;
            if (n) {
                for (int i = 0; i < n_instances; i++)
                    CHECK(DoStep(c[i], (n - 1) * step, time - (n - 1) * step, fmi2True));
            }
            if (!last) continue;
            printf("%.17g", time);
            for (int i = 0; i < n_instances; i++) {
                fmi2Real values[MAX_OUTPUTS];
                CHECK(GetReal(c[i], outputs, n_outputs, values));
                for (size_t k = 0; k < n_outputs; k++) printf(",%.17g", values[k]);
            }
            printf("\n");
        }
        for (int i = 0; i < n_instances; i++) {
            CHECK(Terminate(c[i]));
            FreeInstance(c[i]);
        }
    }
    CLOSE(library);
    return 0;
}
