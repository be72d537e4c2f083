/*
 * Bare C driver of the ImpactOscillator FMU (FMI 2.0 Co-Simulation): no Python, no fmpy.
 *
 * It does the same FMI calls per period as the harness (harness.dynamics.sampling.strobe on
 * harness.fmu.simulator.FmuSimulator): one fmi2DoStep of exactly one period, then one fmi2GetReal of
 * (u, v) and one fmi2GetInteger of (impacts). Set-up is also the same: fmi2SetupExperiment(t0),
 * enter initialization, one fmi2SetReal and one fmi2SetInteger of all parameters, exit.
 *
 * Built by bench/run.py at benchmark time:
 *   cc -O2 -I fmu_src/include/fmi2 bench/c_driver.c -o c_driver -ldl
 * Usage:
 *   c_driver LIB.so GUID RESOURCE_URI T0 PERIODS REPEAT OUT.bin [r:VR=VALUE | i:VR=VALUE | b:VR=0|1]...
 * The parameters are set in the order given. The timed loop (PERIODS periods from T0) is run
 * REPEAT times, each from a fresh fmi2Reset + initialization; for each run the wall and CPU
 * seconds of the loop are printed as "run WALL CPU". OUT.bin receives, for the last run,
 * PERIODS records of (double u, double v, double impacts) after each period, so that
 * bench/run.py can check that the harness read the very same orbit.
 */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

#define MAX_VARS 64

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)env;
    if (status < fmi2Warning) return;
    va_list ap;
    va_start(ap, message);
    fprintf(stderr, "[%s %d %s] ", name, (int)status, category);
    vfprintf(stderr, message, ap);
    fputc('\n', stderr);
    va_end(ap);
}

static void *sym(void *lib, const char *name) {
    void *f = dlsym(lib, name);
    if (!f) {
        fprintf(stderr, "missing symbol %s\n", name);
        exit(2);
    }
    return f;
}

static double now(clockid_t clock) {
    struct timespec ts;
    clock_gettime(clock, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv) {
    if (argc < 8) {
        fprintf(stderr, "usage: %s LIB GUID RESOURCE_URI T0 PERIODS REPEAT OUT.bin [r:VR=X|i:VR=N|b:VR=0|1]...\n",
                argv[0]);
        return 2;
    }
    const char *libpath = argv[1], *guid = argv[2], *resources = argv[3];
    const double t0 = atof(argv[4]);
    const long periods = atol(argv[5]);
    const int repeat = atoi(argv[6]);
    const char *outpath = argv[7];

    fmi2ValueReference rvr[MAX_VARS], ivr[MAX_VARS], bvr[MAX_VARS];
    fmi2Boolean bval[MAX_VARS];
    size_t nb = 0;
    fmi2Real rval[MAX_VARS];
    fmi2Integer ival[MAX_VARS];
    size_t nr = 0, ni = 0;
    for (int k = 8; k < argc; ++k) {
        char kind;
        unsigned vr;
        char value[128];
        if (sscanf(argv[k], "%c:%u=%127s", &kind, &vr, value) != 3 || nr >= MAX_VARS || ni >= MAX_VARS ||
            nb >= MAX_VARS) {
            fprintf(stderr, "bad variable argument %s\n", argv[k]);
            return 2;
        }
        if (kind == 'r') {
            rvr[nr] = vr;
            rval[nr++] = strtod(value, NULL);
        } else if (kind == 'i') {
            ivr[ni] = vr;
            ival[ni++] = atoi(value);
        } else if (kind == 'b') {
            bvr[nb] = vr;
            bval[nb++] = atoi(value) ? fmi2True : fmi2False;
        } else {
            fprintf(stderr, "bad variable kind in %s\n", argv[k]);
            return 2;
        }
    }

    void *lib = dlopen(libpath, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 2;
    }
    fmi2InstantiateTYPE *instantiate = (fmi2InstantiateTYPE *)sym(lib, "fmi2Instantiate");
    fmi2FreeInstanceTYPE *free_instance = (fmi2FreeInstanceTYPE *)sym(lib, "fmi2FreeInstance");
    fmi2SetupExperimentTYPE *setup = (fmi2SetupExperimentTYPE *)sym(lib, "fmi2SetupExperiment");
    fmi2EnterInitializationModeTYPE *enter = (fmi2EnterInitializationModeTYPE *)sym(lib, "fmi2EnterInitializationMode");
    fmi2ExitInitializationModeTYPE *exit_init = (fmi2ExitInitializationModeTYPE *)sym(lib, "fmi2ExitInitializationMode");
    fmi2ResetTYPE *reset = (fmi2ResetTYPE *)sym(lib, "fmi2Reset");
    fmi2TerminateTYPE *terminate = (fmi2TerminateTYPE *)sym(lib, "fmi2Terminate");
    fmi2SetRealTYPE *set_real = (fmi2SetRealTYPE *)sym(lib, "fmi2SetReal");
    fmi2SetIntegerTYPE *set_integer = (fmi2SetIntegerTYPE *)sym(lib, "fmi2SetInteger");
    fmi2SetBooleanTYPE *set_boolean = (fmi2SetBooleanTYPE *)sym(lib, "fmi2SetBoolean");
    fmi2GetRealTYPE *get_real = (fmi2GetRealTYPE *)sym(lib, "fmi2GetReal");
    fmi2GetIntegerTYPE *get_integer = (fmi2GetIntegerTYPE *)sym(lib, "fmi2GetInteger");
    fmi2DoStepTYPE *do_step = (fmi2DoStepTYPE *)sym(lib, "fmi2DoStep");

    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = instantiate("bench-c", fmi2CoSimulation, guid, resources, &cb, fmi2False, fmi2False);
    if (!c) {
        fprintf(stderr, "fmi2Instantiate failed\n");
        return 1;
    }
    const fmi2ValueReference vr_state[2] = {13, 14}, vr_imp[1] = {15};
    double *out = malloc(sizeof(double) * 3 * (size_t)(periods > 0 ? periods : 1));
    for (int run = 0; run < repeat; ++run) {
        if (run > 0 && (terminate(c) > fmi2Warning || reset(c) > fmi2Warning)) {
            fprintf(stderr, "reset failed\n");
            return 1;
        }
        const double w0 = now(CLOCK_MONOTONIC), c0 = now(CLOCK_PROCESS_CPUTIME_ID);
        if (setup(c, fmi2False, 0.0, t0, fmi2False, 0.0) > fmi2Warning || enter(c) > fmi2Warning ||
            (nr && set_real(c, rvr, nr, rval) > fmi2Warning) ||
            (ni && set_integer(c, ivr, ni, ival) > fmi2Warning) ||
            (nb && set_boolean(c, bvr, nb, bval) > fmi2Warning) || exit_init(c) > fmi2Warning) {
            fprintf(stderr, "initialization failed\n");
            return 1;
        }
        fmi2Real x[2];
        fmi2Integer n;
        for (long k = 0; k < periods; ++k) {
            /* the harness steps from absolute times t0 + k to t0 + k + 1 */
            if (do_step(c, t0 + (double)k, (t0 + (double)(k + 1)) - (t0 + (double)k), fmi2True) > fmi2Warning) {
                fprintf(stderr, "doStep failed at period %ld\n", k);
                return 1;
            }
            get_real(c, vr_state, 2, x);
            get_integer(c, vr_imp, 1, &n);
            out[3 * k] = x[0];
            out[3 * k + 1] = x[1];
            out[3 * k + 2] = (double)n;
        }
        const double w1 = now(CLOCK_MONOTONIC), c1 = now(CLOCK_PROCESS_CPUTIME_ID);
        printf("run %.9f %.9f\n", w1 - w0, c1 - c0);
        fflush(stdout);
    }
    FILE *f = fopen(outpath, "wb");
    if (!f || fwrite(out, sizeof(double) * 3, (size_t)periods, f) != (size_t)periods) {
        fprintf(stderr, "cannot write %s\n", outpath);
        return 1;
    }
    fclose(f);
    terminate(c);
    free_instance(c);
    free(out);
    dlclose(lib);
    return 0;
}
