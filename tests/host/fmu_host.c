/*
 * A small FMI importer in portable C for the platform tests (tests/platforms/test_platforms.py): it loads
 * one binary of the FMU (FMI 2.0 or 3.0), and for each start state read from stdin runs one
 * forcing period with Co-Simulation (one doStep of length 1) or Model Exchange (its own
 * fixed-step RK4 with event location by bisection on the wall indicator), and prints the state
 * at the end. Built natively and with each cross toolchain (cmake/toolchain-*.cmake); runs under
 * wine and qemu-user there. Doubles travel as their 64-bit patterns in hex, so that no printf or
 * strtod of any C library changes a bit.
 *
 *   fmu_host BINARY fmi2|fmi3 cs|me TOKEN < input > output
 *
 * input:  blocks (one per case) of "P n", then n lines "r VR HEX" (Real/Float64) or "i VR INT"
 *         (Integer/Int32) parameters; "S m", then m lines "T0HEX U0HEX V0HEX" (start time and
 *         state, u0 = VR 6, v0 = VR 7).
 * output: per start, "ok UHEX VHEX" (u = VR 13, v = VR 14 at T0 + 1) or "err WHERE STATUS".
 * Exit status 0 when the input was read, whatever the FMU answered (the test judges).
 */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
#define LOAD(path) ((void *)LoadLibraryA(path))
#define SYM(lib, name) ((void *)GetProcAddress((HMODULE)(lib), name))
#else
#include <dlfcn.h>
#define LOAD(path) dlopen(path, RTLD_NOW | RTLD_LOCAL)
#define SYM(lib, name) dlsym(lib, name)
#endif

#include "fmi2Functions.h"
#include "fmi3Functions.h"

#define MAXP 32
#define NX 2
#define RK4_STEPS 700 /* per period: h = 1/700; error < 4e-9 per period in the test cases */

static void *lib;
static int fmi3, me;
static const char *token;
static int np;
static char pkind[MAXP];
static unsigned pvr[MAXP];
static double preal[MAXP];
static int pint[MAXP];
static void *inst;

static double from_hex(const char *s) {
    uint64_t b = strtoull(s, NULL, 16);
    double x;
    memcpy(&x, &b, sizeof x);
    return x;
}
static uint64_t to_bits(double x) {
    uint64_t b;
    memcpy(&b, &x, sizeof b);
    return b;
}
static void *sym(const char *name) {
    void *f = SYM(lib, name);
    if (!f) {
        fprintf(stderr, "missing symbol %s\n", name);
        exit(3);
    }
    return f;
}
#define CALL(T, name) ((name##TYPE *)sym(#name))

static void logger2(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c,
                    fmi2String m, ...) {
    (void)e; (void)n; (void)s; (void)c; (void)m;
}
static void logger3(fmi3InstanceEnvironment e, fmi3Status s, fmi3String c, fmi3String m) {
    (void)e; (void)s; (void)c; (void)m;
}
static const fmi2CallbackFunctions callbacks2 = {logger2, calloc, free, NULL, NULL};

/* ---- the calls that differ between FMI 2.0 and 3.0 ------------------------------------- */
static int set_real(unsigned vr, double x) {
    return fmi3 ? CALL(T, fmi3SetFloat64)(inst, &vr, 1, &x, 1) : CALL(T, fmi2SetReal)(inst, &vr, 1, &x);
}
static int set_int(unsigned vr, int x) {
    if (fmi3) {
        fmi3Int32 v = x;
        return CALL(T, fmi3SetInt32)(inst, &vr, 1, &v, 1);
    }
    return CALL(T, fmi2SetInteger)(inst, &vr, 1, &x);
}
static int get_real(unsigned vr, double *x) {
    return fmi3 ? CALL(T, fmi3GetFloat64)(inst, &vr, 1, x, 1) : CALL(T, fmi2GetReal)(inst, &vr, 1, x);
}
static int set_time(double t) {
    return fmi3 ? CALL(T, fmi3SetTime)(inst, t) : CALL(T, fmi2SetTime)(inst, t);
}
static int set_x(const double *x) {
    return fmi3 ? CALL(T, fmi3SetContinuousStates)(inst, x, NX)
                : CALL(T, fmi2SetContinuousStates)(inst, x, NX);
}
static int get_x(double *x) {
    return fmi3 ? CALL(T, fmi3GetContinuousStates)(inst, x, NX)
                : CALL(T, fmi2GetContinuousStates)(inst, x, NX);
}
static int get_der(double *dx) {
    return fmi3 ? CALL(T, fmi3GetContinuousStateDerivatives)(inst, dx, NX)
                : CALL(T, fmi2GetDerivatives)(inst, dx, NX);
}
static int get_ind(double *g) {
    return fmi3 ? CALL(T, fmi3GetEventIndicators)(inst, g, 1) : CALL(T, fmi2GetEventIndicators)(inst, g, 1);
}
/* Event mode, discrete updates until none is needed, back to continuous time. */
static int event_iteration(int enter) {
    int st;
    if (enter && (st = fmi3 ? CALL(T, fmi3EnterEventMode)(inst) : CALL(T, fmi2EnterEventMode)(inst)) > 1)
        return st;
    for (int k = 0; k < 100; k++) {
        int again;
        if (fmi3) {
            fmi3Boolean need, term, nom, val, defined;
            fmi3Float64 next;
            st = CALL(T, fmi3UpdateDiscreteStates)(inst, &need, &term, &nom, &val, &defined, &next);
            again = need;
        } else {
            fmi2EventInfo info;
            st = CALL(T, fmi2NewDiscreteStates)(inst, &info);
            again = info.newDiscreteStatesNeeded;
        }
        if (st > 1) return st;
        if (!again) break;
    }
    return fmi3 ? CALL(T, fmi3EnterContinuousTimeMode)(inst) : CALL(T, fmi2EnterContinuousTimeMode)(inst);
}

/* ---- Model Exchange: RK4 from (t, x) over h, the FMU's derivatives ---------------------- */
static int rk4(double t, const double *x, double h, double *out) {
    double k[4][NX], y[NX];
    const double c[4] = {0.0, 0.5, 0.5, 1.0};
    for (int s = 0; s < 4; s++) {
        for (int i = 0; i < NX; i++) y[i] = x[i] + (s ? c[s] * h * k[s - 1][i] : 0.0);
        if (set_time(t + c[s] * h) > 1 || set_x(y) > 1 || get_der(k[s]) > 1) return 3;
    }
    for (int i = 0; i < NX; i++) out[i] = x[i] + h / 6.0 * (k[0][i] + 2 * k[1][i] + 2 * k[2][i] + k[3][i]);
    return 0;
}
static int indicator_at(double t, const double *x, double *g) {
    if (set_time(t) > 1 || set_x(x) > 1) return 3;
    return get_ind(g) > 1 ? 3 : 0;
}
/* One period t0 .. t0 + 1; a sign change of the indicator over a step is located by bisection
 * on the step length (to 1e-15), the state is put just past it and the FMU's event handled. */
static int me_period(double t0, double *x) {
    const double h = 1.0 / RK4_STEPS;
    double t = t0, g0, g1, y[NX];
    if (indicator_at(t, x, &g0)) return 3;
    for (int n = 0; n < RK4_STEPS;) {
        double tn = t0 + (n + 1) * h, step = tn - t;
        if (rk4(t, x, step, y) || indicator_at(tn, y, &g1)) return 3;
        if ((g0 > 0) != (g1 > 0)) {
            double lo = 0.0, hi = step, z[NX];
            while (hi - lo > 1e-15) {
                double mid = 0.5 * (lo + hi), gm;
                if (rk4(t, x, mid, z) || indicator_at(t + mid, z, &gm)) return 3;
                if ((gm > 0) == (g0 > 0)) lo = mid; else hi = mid;
            }
            if (rk4(t, x, hi, y) || indicator_at(t + hi, y, &g1)) return 3;
            fmi2Boolean enter2 = 0, term2 = 0;
            fmi3Boolean enter3 = 0, term3 = 0;
            if ((fmi3 ? CALL(T, fmi3CompletedIntegratorStep)(inst, 1, &enter3, &term3)
                      : CALL(T, fmi2CompletedIntegratorStep)(inst, 1, &enter2, &term2)) > 1)
                return 3;
            if (event_iteration(1) > 1 || get_x(x) > 1) return 3;
            t += hi;
            if (indicator_at(t, x, &g0)) return 3;
            continue;
        }
        memcpy(x, y, sizeof y);
        t = tn;
        g0 = g1;
        n++;
    }
    return 0;
}

/* ---- one start: instantiate, parameters, initialise, one period, u and v, free ---------- */
static void run(double t0, double u0, double v0) {
    const char *where = "instantiate";
    int st = 0;
    if (fmi3)
        inst = me ? CALL(T, fmi3InstantiateModelExchange)("host", token, NULL, 0, 0, NULL, logger3)
                  : CALL(T, fmi3InstantiateCoSimulation)("host", token, NULL, 0, 0, 0, 0, NULL, 0,
                                                          NULL, logger3, NULL);
    else
        inst = CALL(T, fmi2Instantiate)("host", me ? fmi2ModelExchange : fmi2CoSimulation, token,
                                        "file:///", &callbacks2, 0, 0);
    if (!inst) { printf("err instantiate 0\n"); return; }
    where = "parameters";
    for (int i = 0; i < np && st <= 1; i++)
        st = pkind[i] == 'r' ? set_real(pvr[i], preal[i]) : set_int(pvr[i], pint[i]);
    if (st <= 1) st = set_real(6, u0);
    if (st <= 1) st = set_real(7, v0);
    if (st <= 1) {
        where = "initialise";
        if (fmi3) {
            st = CALL(T, fmi3EnterInitializationMode)(inst, 0, 0.0, t0, 1, t0 + 1.0);
        } else {
            st = CALL(T, fmi2SetupExperiment)(inst, 0, 0.0, t0, 1, t0 + 1.0);
            if (st <= 1) st = CALL(T, fmi2EnterInitializationMode)(inst);
        }
        if (st <= 1) st = fmi3 ? CALL(T, fmi3ExitInitializationMode)(inst) : CALL(T, fmi2ExitInitializationMode)(inst);
    }
    double x[NX] = {0, 0};
    if (st <= 1 && me) {
        where = "model exchange";
        st = event_iteration(0);
        if (st <= 1) st = get_x(x);
        if (st <= 1) st = me_period(t0, x);
        if (st <= 1) st = set_time(t0 + 1.0);
        if (st <= 1) st = set_x(x);
    } else if (st <= 1) {
        where = "doStep";
        if (fmi3) {
            fmi3Boolean ev, term, early;
            fmi3Float64 last;
            st = CALL(T, fmi3DoStep)(inst, t0, 1.0, 1, &ev, &term, &early, &last);
        } else {
            st = CALL(T, fmi2DoStep)(inst, t0, 1.0, 1);
        }
    }
    double u = 0, v = 0;
    if (st <= 1) { where = "get"; st = get_real(13, &u); }
    if (st <= 1) st = get_real(14, &v);
    if (st <= 1)
        printf("ok %016" PRIx64 " %016" PRIx64 "\n", to_bits(u), to_bits(v));
    else
        printf("err %s %d\n", where, st);
    if (fmi3) CALL(T, fmi3FreeInstance)(inst); else CALL(T, fmi2FreeInstance)(inst);
}

int main(int argc, char **argv) {
    char a[64], b[64], c[64];
    int n;
    if (argc != 5) {
        fprintf(stderr, "usage: fmu_host BINARY fmi2|fmi3 cs|me TOKEN < input\n");
        return 2;
    }
    fmi3 = strcmp(argv[2], "fmi3") == 0;
    me = strcmp(argv[3], "me") == 0;
    token = argv[4];
    if (!(lib = LOAD(argv[1]))) {
#ifdef _WIN32
        fprintf(stderr, "cannot load %s (error %lu)\n", argv[1], (unsigned long)GetLastError());
#else
        fprintf(stderr, "cannot load %s: %s\n", argv[1], dlerror());
#endif
        return 3;
    }
    /* one block per case, until the end of the input (one process per platform and interface:
     * wine's start is what costs) */
    while (scanf(" P %d", &np) == 1) {
        if (np < 0 || np > MAXP) return 2;
        for (int i = 0; i < np; i++) {
            if (scanf(" %1s %u %63s", a, &pvr[i], b) != 3) return 2;
            pkind[i] = a[0];
            if (a[0] == 'r') preal[i] = from_hex(b); else pint[i] = atoi(b);
        }
        if (scanf(" S %d", &n) != 1) return 2;
        for (int i = 0; i < n; i++) {
            if (scanf(" %63s %63s %63s", a, b, c) != 3) return 2;
            run(from_hex(a), from_hex(b), from_hex(c));
        }
    }
    fflush(stdout);
    return 0;
}
