/*
 * A short run of the release FMU binaries for valgrind (memcheck): every life-cycle path once.
 * FMI 2.0: Co-Simulation (steps, a refused parameter, get/set/serialise/deserialise/free of
 * FMU states, a corrupted state, reset, terminate) and Model Exchange (Euler with events);
 * FMI 3.0: Co-Simulation with event mode and early return, Model Exchange. Then, for all four,
 * the refused initialisation (solver = 1 with a Hertz or Hunt-Crossley compliant wall) while
 * other instances are alive, with a logger that formats the message printf-style as importers do,
 * and every way on from the Error state: free at once, terminate, reset and run again.
 *
 *   cc -g -I fmu_src/include/fmi2 -I fmu_src/include/fmi3 tests/fuzz/valgrind_driver.c -ldl
 *   valgrind --error-exitcode=99 --leak-check=full ./a.out FMI2.so FMI3.so GUID [leak]
 *
 * Exit status 0 when every call that must succeed did; the memory checks are valgrind's.
 */
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmi3Functions.h"

static int failures = 0;
static int leak_on_purpose = 0; /* "leak": forget one FMU state (the test that valgrind can fail) */
#define MUST(call)                                                                  \
    do {                                                                            \
        int st_ = (int)(call);                                                      \
        if (st_ > 1) {                                                              \
            fprintf(stderr, "%s:%d: %s -> %d\n", __FILE__, __LINE__, #call, st_);   \
            failures++;                                                             \
        }                                                                           \
    } while (0)
#define MUST_FAIL(call)                                                             \
    do {                                                                            \
        if ((int)(call) < 2) {                                                      \
            fprintf(stderr, "%s:%d: %s accepted\n", __FILE__, __LINE__, #call);     \
            failures++;                                                             \
        }                                                                           \
    } while (0)

static void *lib2, *lib3;
#define F2(name) ((name##TYPE *)dlsym(lib2, #name))
#define F3(name) ((name##TYPE *)dlsym(lib3, #name))

static void logger2(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                    fmi2String category, fmi2String message, ...) {
    (void)env; (void)name; (void)status; (void)category; (void)message;
}
static void logger3(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                    fmi3String message) {
    (void)env; (void)status; (void)category; (void)message;
}

/* Loggers that read the whole message (an importer formats and prints it): a bad pointer or an
 * unterminated or uninitialised text is a memcheck error; the refusal's text is counted. */
static int refusals_logged = 0;
static void note(const char *text) {
    if (strstr(text, "closed form") && strstr(text, "linear contact law")) refusals_logged++;
}
static void formatting_logger2(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                               fmi2String category, fmi2String message, ...) {
    char buf[2048];
    va_list ap;
    va_start(ap, message);
    vsnprintf(buf, sizeof buf, message, ap);
    va_end(ap);
    (void)env; (void)status;
    if (strlen(name) + strlen(category) > 0) note(buf);
}
static void reading_logger3(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                            fmi3String message) {
    (void)env; (void)status;
    if (strlen(category) + strlen(message) > 0) note(message);
}

/* The refused configuration: solver = 1 (closed form) with contact law `law` (1 Hertz, 2 Hunt-
 * Crossley) on the compliant wall; `after`: 0 free at once, 1 terminate then free, 2 reset, run
 * a valid configuration, free. */
static const fmi2ValueReference VR_REFUSED[] = {5, 17, 31}; /* wall, contact, solver */

static void fmi2_refused(const char *guid, fmi2Type type, int law, int after) {
    fmi2CallbackFunctions cb = {formatting_logger2, calloc, free, NULL, NULL};
    fmi2Component c = F2(fmi2Instantiate)("refused2", type, guid, "", &cb, 0, 0);
    if (!c) { failures++; return; }
    const int bad[] = {1, law, 1}, good[] = {1, 0, 1};
    double out[2];
    const fmi2ValueReference vr_uv[] = {13, 14};
    MUST(F2(fmi2SetupExperiment)(c, 0, 0.0, 0.0, 0, 0.0));
    MUST(F2(fmi2EnterInitializationMode)(c));
    MUST(F2(fmi2SetInteger)(c, VR_REFUSED, 3, bad));
    MUST_FAIL(F2(fmi2ExitInitializationMode)(c));
    MUST_FAIL(F2(fmi2ExitInitializationMode)(c)); /* again: not allowed in Error */
    MUST(F2(fmi2GetReal)(c, vr_uv, 2, out));
    /* in Error fmi2Terminate is refused too (FMI 2.0.4 2.1.3: only the state functions, reset
     * and free lead on) */
    if (after >= 1) MUST_FAIL(F2(fmi2Terminate)(c));
    if (after == 2) {
        MUST(F2(fmi2Reset)(c));
        MUST(F2(fmi2SetupExperiment)(c, 0, 0.0, 0.0, 0, 0.0));
        MUST(F2(fmi2EnterInitializationMode)(c));
        MUST(F2(fmi2SetInteger)(c, VR_REFUSED, 3, good));
        MUST(F2(fmi2ExitInitializationMode)(c));
        if (type == fmi2CoSimulation) {
            MUST(F2(fmi2DoStep)(c, 0.0, 1.5, 1));
        } else {
            fmi2EventInfo info;
            MUST(F2(fmi2NewDiscreteStates)(c, &info));
            MUST(F2(fmi2EnterContinuousTimeMode)(c));
            MUST(F2(fmi2GetContinuousStates)(c, out, 2));
            MUST(F2(fmi2GetDerivatives)(c, out, 2));
        }
        MUST(F2(fmi2Terminate)(c));
    }
    F2(fmi2FreeInstance)(c);
}

static void fmi3_refused(const char *token, int me, int law, int after) {
    fmi3Instance c = me ? F3(fmi3InstantiateModelExchange)("refused3", token, "", 0, 0, NULL,
                                                           reading_logger3)
                        : F3(fmi3InstantiateCoSimulation)("refused3", token, "", 0, 0, 0, 0, NULL,
                                                          0, NULL, reading_logger3, NULL);
    if (!c) { failures++; return; }
    const int bad[] = {1, law, 1}, good[] = {1, 0, 1};
    const fmi3ValueReference vr_uv[] = {13, 14};
    double out[2];
    MUST(F3(fmi3EnterInitializationMode)(c, 0, 0.0, 0.0, 0, 0.0));
    MUST(F3(fmi3SetInt32)(c, VR_REFUSED, 3, bad, 3));
    MUST_FAIL(F3(fmi3ExitInitializationMode)(c));
    MUST_FAIL(F3(fmi3ExitInitializationMode)(c));
    MUST(F3(fmi3GetFloat64)(c, vr_uv, 2, out, 2));
    /* FMI 3.0: after fmi3Error the instance is Terminated; terminating again is refused */
    if (after >= 1) MUST_FAIL(F3(fmi3Terminate)(c));
    if (after == 2) {
        MUST(F3(fmi3Reset)(c));
        MUST(F3(fmi3EnterInitializationMode)(c, 0, 0.0, 0.0, 0, 0.0));
        MUST(F3(fmi3SetInt32)(c, VR_REFUSED, 3, good, 3));
        MUST(F3(fmi3ExitInitializationMode)(c));
        if (!me) {
            fmi3Boolean ev, term, early;
            double last;
            MUST(F3(fmi3DoStep)(c, 0.0, 1.5, 1, &ev, &term, &early, &last));
        }
        MUST(F3(fmi3Terminate)(c));
    }
    F3(fmi3FreeInstance)(c);
}

static void refused_paths(const char *guid) {
    /* instances alive around the refused ones, used after them */
    fmi2CallbackFunctions cb = {formatting_logger2, calloc, free, NULL, NULL};
    fmi2Component alive2 = F2(fmi2Instantiate)("alive2", fmi2CoSimulation, guid, "", &cb, 0, 0);
    fmi3Instance alive3 = F3(fmi3InstantiateCoSimulation)("alive3", guid, "", 0, 0, 0, 0, NULL, 0,
                                                          NULL, reading_logger3, NULL);
    if (!alive2 || !alive3) { failures++; return; }
    MUST(F2(fmi2SetupExperiment)(alive2, 0, 0.0, 0.0, 0, 0.0));
    MUST(F2(fmi2EnterInitializationMode)(alive2));
    MUST(F2(fmi2ExitInitializationMode)(alive2));
    MUST(F3(fmi3EnterInitializationMode)(alive3, 0, 0.0, 0.0, 0, 0.0));
    MUST(F3(fmi3ExitInitializationMode)(alive3));
    double t = 0.0;
    for (int law = 1; law <= 2; ++law)
        for (int after = 0; after <= 2; ++after) {
            fmi2_refused(guid, fmi2CoSimulation, law, after);
            fmi2_refused(guid, fmi2ModelExchange, law, after);
            fmi3_refused(guid, 0, law, after);
            fmi3_refused(guid, 1, law, after);
            fmi3Boolean ev, term, early;
            double last;
            MUST(F2(fmi2DoStep)(alive2, t, 0.25, 1));
            MUST(F3(fmi3DoStep)(alive3, t, 0.25, 1, &ev, &term, &early, &last));
            t += 0.25;
        }
    /* each refused instance logged its refusal twice: the Error state refuses the second exit
     * with another message, so count only that every first one arrived */
    if (refusals_logged != 2 * 3 * 4) {
        fprintf(stderr, "refusal messages logged: %d, expected %d\n", refusals_logged, 2 * 3 * 4);
        failures++;
    }
    MUST(F2(fmi2Terminate)(alive2));
    F2(fmi2FreeInstance)(alive2);
    MUST(F3(fmi3Terminate)(alive3));
    F3(fmi3FreeInstance)(alive3);
}

static void fmi2_cs(const char *guid) {
    fmi2CallbackFunctions cb = {logger2, calloc, free, NULL, NULL};
    fmi2Component c = F2(fmi2Instantiate)("cs", fmi2CoSimulation, guid, "", &cb, 0, 0);
    if (!c) { failures++; return; }
    const fmi2ValueReference vr_sigma = 2, vr_out[] = {13, 14, 10, 11, 12};
    double sigma = 0.1, bad = NAN, out[5];
    MUST(F2(fmi2SetupExperiment)(c, 0, 0.0, 0.0, 0, 0.0));
    MUST(F2(fmi2EnterInitializationMode)(c));
    MUST(F2(fmi2SetReal)(c, &vr_sigma, 1, &sigma));
    fmi2FMUstate before = NULL;
    MUST(F2(fmi2GetFMUstate)(c, &before));
    MUST_FAIL(F2(fmi2SetReal)(c, &vr_sigma, 1, &bad));
    MUST_FAIL(F2(fmi2ExitInitializationMode)(c)); /* Error state (FMI 2.0.4 2.1.3) ... */
    MUST(F2(fmi2SetFMUstate)(c, before));         /* ... left by restoring a saved state */
    MUST(F2(fmi2FreeFMUstate)(c, &before));
    MUST(F2(fmi2ExitInitializationMode)(c));
    double t = 0.0;
    fmi2FMUstate s = NULL, s2 = NULL;
    for (int i = 0; i < 20; ++i, t += 0.5) {
        MUST(F2(fmi2DoStep)(c, t, 0.5, 1));
        MUST(F2(fmi2GetReal)(c, vr_out, 5, out));
        if (i == 5) MUST(F2(fmi2GetFMUstate)(c, &s));
    }
    size_t n = 0;
    MUST(F2(fmi2SerializedFMUstateSize)(c, s, &n));
    char *bytes = malloc(n);
    MUST(F2(fmi2SerializeFMUstate)(c, s, bytes, n));
    MUST(F2(fmi2DeSerializeFMUstate)(c, bytes, n, &s2));
    MUST(F2(fmi2SetFMUstate)(c, s2));
    MUST(F2(fmi2DoStep)(c, 3.0, 1.0, 1));
    memset(bytes + n / 2, 0xff, 8); /* NaN in the body: must not crash either way */
    fmi2FMUstate s3 = NULL;
    if (F2(fmi2DeSerializeFMUstate)(c, bytes, n, &s3) == fmi2OK) {
        F2(fmi2SetFMUstate)(c, s3);
        F2(fmi2FreeFMUstate)(c, &s3);
    }
    MUST_FAIL(F2(fmi2DeSerializeFMUstate)(c, bytes, n / 2, &s3));
    free(bytes);
    MUST(F2(fmi2FreeFMUstate)(c, &s));
    if (!leak_on_purpose) MUST(F2(fmi2FreeFMUstate)(c, &s2));
    MUST(F2(fmi2Reset)(c));
    MUST(F2(fmi2SetupExperiment)(c, 0, 0.0, 0.0, 0, 0.0));
    MUST(F2(fmi2EnterInitializationMode)(c));
    MUST(F2(fmi2ExitInitializationMode)(c));
    MUST(F2(fmi2DoStep)(c, 0.0, 2.0, 1));
    MUST(F2(fmi2Terminate)(c));
    F2(fmi2FreeInstance)(c);
}

static void fmi2_me(const char *guid) {
    fmi2CallbackFunctions cb = {logger2, calloc, free, NULL, NULL};
    fmi2Component c = F2(fmi2Instantiate)("me", fmi2ModelExchange, guid, "", &cb, 0, 0);
    if (!c) { failures++; return; }
    MUST(F2(fmi2SetupExperiment)(c, 0, 0.0, 0.0, 0, 0.0));
    MUST(F2(fmi2EnterInitializationMode)(c));
    MUST(F2(fmi2ExitInitializationMode)(c));
    fmi2EventInfo info;
    MUST(F2(fmi2NewDiscreteStates)(c, &info));
    MUST(F2(fmi2EnterContinuousTimeMode)(c));
    double x[2], dx[2], g = 0.0, g_old;
    MUST(F2(fmi2GetEventIndicators)(c, &g, 1));
    const double h = 1e-3;
    for (int i = 1; i <= 3000; ++i) {
        MUST(F2(fmi2GetContinuousStates)(c, x, 2));
        MUST(F2(fmi2GetDerivatives)(c, dx, 2));
        MUST(F2(fmi2SetTime)(c, i * h));
        x[0] += h * dx[0];
        x[1] += h * dx[1];
        MUST(F2(fmi2SetContinuousStates)(c, x, 2));
        fmi2Boolean ev, term;
        MUST(F2(fmi2CompletedIntegratorStep)(c, 1, &ev, &term));
        g_old = g;
        MUST(F2(fmi2GetEventIndicators)(c, &g, 1));
        if ((g > 0) != (g_old > 0)) {
            MUST(F2(fmi2EnterEventMode)(c));
            MUST(F2(fmi2NewDiscreteStates)(c, &info));
            MUST(F2(fmi2EnterContinuousTimeMode)(c));
            MUST(F2(fmi2GetEventIndicators)(c, &g, 1));
        }
    }
    MUST_FAIL(F2(fmi2DoStep)(c, 3.0, 1.0, 1));
    MUST_FAIL(F2(fmi2Terminate)(c)); /* the refused call left it in Error */
    F2(fmi2FreeInstance)(c);
}

static void fmi3_cs(const char *token) {
    fmi3Instance c = F3(fmi3InstantiateCoSimulation)("cs3", token, "", 0, 0, 1, 1, NULL, 0, NULL,
                                                     logger3, NULL);
    if (!c) { failures++; return; }
    MUST(F3(fmi3EnterInitializationMode)(c, 0, 0.0, 0.0, 0, 0.0));
    MUST(F3(fmi3ExitInitializationMode)(c));
    fmi3Boolean a, b, d, e, f;
    double next, t = 0.0, last;
    MUST(F3(fmi3UpdateDiscreteStates)(c, &a, &b, &d, &e, &f, &next));
    MUST(F3(fmi3EnterStepMode)(c));
    fmi3FMUState s = NULL;
    for (int i = 0; i < 60 && t < 10.0; ++i) {
        fmi3Boolean ev, term, early;
        MUST(F3(fmi3DoStep)(c, t, 10.0 - t, 1, &ev, &term, &early, &last));
        t = last;
        if (ev) {
            MUST(F3(fmi3EnterEventMode)(c));
            MUST(F3(fmi3UpdateDiscreteStates)(c, &a, &b, &d, &e, &f, &next));
            MUST(F3(fmi3EnterStepMode)(c));
        }
        if (i == 0) MUST(F3(fmi3GetFMUState)(c, &s));
    }
    size_t n = 0;
    MUST(F3(fmi3SerializedFMUStateSize)(c, s, &n));
    fmi3Byte *bytes = malloc(n);
    MUST(F3(fmi3SerializeFMUState)(c, s, bytes, n));
    MUST(F3(fmi3DeserializeFMUState)(c, bytes, n, &s));
    MUST(F3(fmi3SetFMUState)(c, s));
    free(bytes);
    MUST(F3(fmi3FreeFMUState)(c, &s));
    MUST(F3(fmi3Terminate)(c));
    MUST(F3(fmi3Reset)(c));
    F3(fmi3FreeInstance)(c);
}

static void fmi3_me(const char *token) {
    fmi3Instance c = F3(fmi3InstantiateModelExchange)("me3", token, "", 0, 0, NULL, logger3);
    if (!c) { failures++; return; }
    MUST(F3(fmi3EnterInitializationMode)(c, 0, 0.0, 0.0, 0, 0.0));
    MUST(F3(fmi3ExitInitializationMode)(c));
    fmi3Boolean a, b, d, e, f;
    double next, x[2], dx[2], g;
    MUST(F3(fmi3UpdateDiscreteStates)(c, &a, &b, &d, &e, &f, &next));
    MUST(F3(fmi3EnterContinuousTimeMode)(c));
    for (int i = 1; i <= 500; ++i) {
        MUST(F3(fmi3GetContinuousStates)(c, x, 2));
        MUST(F3(fmi3GetContinuousStateDerivatives)(c, dx, 2));
        MUST(F3(fmi3SetTime)(c, i * 1e-3));
        x[0] += 1e-3 * dx[0];
        x[1] += 1e-3 * dx[1];
        MUST(F3(fmi3SetContinuousStates)(c, x, 2));
        MUST(F3(fmi3GetEventIndicators)(c, &g, 1));
    }
    fmi3FMUState s = NULL;
    MUST(F3(fmi3GetFMUState)(c, &s));
    MUST(F3(fmi3SetFMUState)(c, s));
    MUST(F3(fmi3FreeFMUState)(c, &s));
    MUST(F3(fmi3Terminate)(c));
    F3(fmi3FreeInstance)(c);
}

int main(int argc, char **argv) {
    if (argc != 4 && argc != 5) {
        fprintf(stderr, "usage: %s FMI2.so FMI3.so GUID [leak]\n", argv[0]);
        return 2;
    }
    lib2 = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    lib3 = dlopen(argv[2], RTLD_NOW | RTLD_LOCAL);
    if (!lib2 || !lib3) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 2;
    }
    leak_on_purpose = argc == 5 && strcmp(argv[4], "leak") == 0;
    fmi2_cs(argv[3]);
    fmi2_me(argv[3]);
    fmi3_cs(argv[3]);
    fmi3_me(argv[3]);
    refused_paths(argv[3]);
    printf("%d failures\n", failures);
    return failures ? 1 : 0;
}
