/* AmplitudeController: the z-feedback of a tapping-mode AFM as an FMI 2.0 Co-Simulation FMU.
 *
 * Input u (the cantilever tip's position, the ImpactOscillator's output u), output u_wall (the
 * sample surface's position, the ImpactOscillator's input u_wall).  The controller samples u at
 * each communication point (the value the master sets before fmi2DoStep(t, h) is u(t)) and keeps
 * the largest and smallest sample of the current measurement window [theta + k T, theta + (k+1) T).
 * When a step ends on or past the end of a window that it watched from its start, the window's
 * amplitude A = max - min is compared with the set-point and the PI law
 *
 *     e = A - A_set,   I += e T,   u_wall = u_wall_start - (Kp e + Ki I)
 *
 * gives the wall position, held (zero-order hold) until the next window ends: an amplitude
 * above the set-point moves the surface towards the tip.  The output changes only at window
 * ends, and depends on u only through earlier samples (no direct feedthrough), so Jacobi and
 * Gauss-Seidel masters that both deliver u(t) at the start of each step see the same numbers.
 *
 * Windows are counted with floor((t - theta)/T + 1e-9): communication points computed by
 * summing t += h lie a few ulps either side of a window boundary, and both must count as on it.
 * The same expression, in the same double arithmetic, is in examples/afm/monolithic.py.
 */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define GUID "{3f0c6d1e-8a7b-4c52-9e1d-af3c2b7d9e41}"

enum { VR_A_SET, VR_KP, VR_KI, VR_T, VR_THETA, VR_U_WALL_START, VR_U, VR_U_WALL, VR_AMPLITUDE,
       VR_INTEGRAL, VR_WINDOWS, N_REAL = VR_WINDOWS };

typedef enum { S_INSTANTIATED, S_INIT, S_STEP, S_TERMINATED, S_ERROR } State;

typedef struct {
    double r[N_REAL];        /* Real variables by value reference */
    int windows;             /* completed windows (Integer output, VR 10) */
    double t_start;          /* fmi2SetupExperiment's start time */
    double t;                /* current communication point */
    double hi, lo;           /* extremes of the samples in the current window */
    int have_window;         /* 1 once a window is watched from its start */
    State state;
    fmi2CallbackFunctions cb;
    char name[64];
    int logging;
} Ctrl;

static void log_msg(Ctrl *c, fmi2Status s, const char *cat, const char *fmt, ...) {
    if (!c->cb.logger) return;
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    c->cb.logger(c->cb.componentEnvironment, c->name, s, cat, "%s", buf);
}

static fmi2Status fail(Ctrl *c, const char *fmt, const char *what) {
    log_msg(c, fmi2Error, "logStatusError", fmt, what);
    return fmi2Error;
}

static double window_index(const Ctrl *c, double t) {
    return floor((t - c->r[VR_THETA]) / c->r[VR_T] + 1e-9);
}

static void set_defaults(Ctrl *c) {
    memset(c->r, 0, sizeof c->r);
    c->r[VR_A_SET] = 2.5;
    c->r[VR_KP] = 0.1;
    c->r[VR_KI] = 0.3;
    c->r[VR_T] = 1.0;
    c->r[VR_THETA] = 0.4;
    c->r[VR_U_WALL_START] = 0.0;
    c->windows = 0;
    c->t_start = 0.0;
    c->t = 0.0;
    c->have_window = 0;
    c->state = S_INSTANTIATED;
}

/* ------------------------------------------------------------------------------------------ */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String res,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible,
                              fmi2Boolean logging) {
    (void)res; (void)visible;
    if (!cb || !cb->allocateMemory || !cb->freeMemory) return NULL;
    if (type != fmi2CoSimulation || !guid || strcmp(guid, GUID) != 0) {
        if (cb->logger)
            cb->logger(cb->componentEnvironment, name ? name : "", fmi2Error, "logStatusError",
                       "%s", "AmplitudeController: Co-Simulation only, and the GUID must match");
        return NULL;
    }
    Ctrl *c = (Ctrl *)cb->allocateMemory(1, sizeof(Ctrl));
    if (!c) return NULL;
    c->cb = *cb;
    snprintf(c->name, sizeof c->name, "%s", name ? name : "");
    c->logging = logging;
    set_defaults(c);
    return c;
}

void fmi2FreeInstance(fmi2Component comp) {
    Ctrl *c = (Ctrl *)comp;
    if (c) c->cb.freeMemory(c);
}

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean on, size_t n,
                               const fmi2String cats[]) {
    (void)n; (void)cats;
    ((Ctrl *)comp)->logging = on;
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean tolDefined, fmi2Real tol,
                               fmi2Real start, fmi2Boolean stopDefined, fmi2Real stop) {
    (void)tolDefined; (void)tol; (void)stopDefined; (void)stop;
    Ctrl *c = (Ctrl *)comp;
    if (c->state != S_INSTANTIATED) return fail(c, "%s", "fmi2SetupExperiment in the wrong state");
    c->t_start = c->t = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp) {
    Ctrl *c = (Ctrl *)comp;
    if (c->state != S_INSTANTIATED) return fail(c, "%s", "fmi2EnterInitializationMode in the wrong state");
    c->state = S_INIT;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp) {
    Ctrl *c = (Ctrl *)comp;
    if (c->state != S_INIT) return fail(c, "%s", "fmi2ExitInitializationMode in the wrong state");
    if (!(c->r[VR_T] > 0.0) || !isfinite(c->r[VR_T])) return fail(c, "%s", "T must be > 0");
    for (int i = 0; i < N_REAL; ++i)
        if (!isfinite(c->r[i])) return fail(c, "variable %s is not finite", "(a Real)");
    c->r[VR_U_WALL] = c->r[VR_U_WALL_START];
    c->r[VR_AMPLITUDE] = 0.0;
    c->r[VR_INTEGRAL] = 0.0;
    c->state = S_STEP;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component comp) {
    ((Ctrl *)comp)->state = S_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component comp) {
    set_defaults((Ctrl *)comp);
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    (void)noSetPrior;
    Ctrl *c = (Ctrl *)comp;
    if (c->state != S_STEP) return fail(c, "%s", "fmi2DoStep in the wrong state");
    if (!(h > 0.0)) return fail(c, "%s", "fmi2DoStep: the step size must be > 0");
    const double k0 = window_index(c, t), k1 = window_index(c, t + h);
    /* A window is watched from its start when its start lies at or after the start time
     * (the partial first window is ignored: at the first step some masters deliver the
     * connection's default instead of u(t0)). */
    const double win_start = c->r[VR_THETA] + k0 * c->r[VR_T];
    if (!c->have_window && win_start >= c->t_start - 1e-9 * c->r[VR_T]) {
        c->have_window = 1;
        c->hi = -DBL_MAX;
        c->lo = DBL_MAX;
    }
    if (c->have_window) {
        const double u = c->r[VR_U];
        if (u > c->hi) c->hi = u;
        if (u < c->lo) c->lo = u;
    }
    if (k1 > k0) {                     /* the step ends on or past the end of window k0 */
        if (c->have_window) {
            const double A = c->hi - c->lo, e = A - c->r[VR_A_SET];
            c->r[VR_INTEGRAL] += e * c->r[VR_T];
            c->r[VR_AMPLITUDE] = A;
            c->r[VR_U_WALL] = c->r[VR_U_WALL_START]
                              - (c->r[VR_KP] * e + c->r[VR_KI] * c->r[VR_INTEGRAL]);
            c->windows += 1;
            if (c->logging)
                log_msg(c, fmi2OK, "logUpdates", "t = %.17g: A = %.17g, u_wall = %.17g", t + h,
                        A, c->r[VR_U_WALL]);
        }
        c->have_window = 1;            /* the next window starts at this communication point */
        c->hi = -DBL_MAX;
        c->lo = DBL_MAX;
        if (k1 > k0 + 1)
            log_msg(c, fmi2Warning, "logStatusError",
                    "fmi2DoStep at t = %.17g spans more than one window: the step must not exceed T", t);
    }
    c->t = t + h;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component comp) { (void)comp; return fmi2Error; }

/* ------------------------------------------------------------------------------------------ */
static int is_parameter(fmi2ValueReference vr) { return vr <= VR_U_WALL_START; }

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    Ctrl *c = (Ctrl *)comp;
    for (size_t i = 0; i < n; ++i) {
        if (vr[i] >= N_REAL) return fail(c, "%s", "fmi2GetReal: unknown value reference");
        v[i] = c->r[vr[i]];
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real v[]) {
    Ctrl *c = (Ctrl *)comp;
    for (size_t i = 0; i < n; ++i) {
        if (vr[i] != VR_U && !is_parameter(vr[i]))
            return fail(c, "%s", "fmi2SetReal: not a parameter or input");
        if (!isfinite(v[i])) return fail(c, "%s", "fmi2SetReal: value is not finite");
        /* after initialisation only the input u and the tunable set-point and gains */
        if (c->state == S_STEP && vr[i] != VR_U && vr[i] != VR_A_SET && vr[i] != VR_KP &&
            vr[i] != VR_KI)
            return fail(c, "%s", "fmi2SetReal: only u, A_set, Kp, Ki may change after initialisation");
        c->r[vr[i]] = v[i];
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          fmi2Integer v[]) {
    Ctrl *c = (Ctrl *)comp;
    for (size_t i = 0; i < n; ++i) {
        if (vr[i] != VR_WINDOWS) return fail(c, "%s", "fmi2GetInteger: unknown value reference");
        v[i] = c->windows;
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Integer v[]) {
    (void)vr; (void)v;
    return n ? fail((Ctrl *)c, "%s", "fmi2SetInteger: no Integer inputs") : fmi2OK;
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[]) {
    (void)vr; (void)v;
    return n ? fail((Ctrl *)c, "%s", "no Boolean variables") : fmi2OK;
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Boolean v[]) {
    (void)vr; (void)v;
    return n ? fail((Ctrl *)c, "%s", "no Boolean variables") : fmi2OK;
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]) {
    (void)vr; (void)v;
    return n ? fail((Ctrl *)c, "%s", "no String variables") : fmi2OK;
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         const fmi2String v[]) {
    (void)vr; (void)v;
    return n ? fail((Ctrl *)c, "%s", "no String variables") : fmi2OK;
}

/* Not supported (the modelDescription says so). */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)s; return fail((Ctrl *)c, "%s", "no FMU state"); }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { (void)s; return fail((Ctrl *)c, "%s", "no FMU state"); }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)s; return fail((Ctrl *)c, "%s", "no FMU state"); }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n) { (void)s; (void)n; return fail((Ctrl *)c, "%s", "no FMU state"); }
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n) { (void)s; (void)b; (void)n; return fail((Ctrl *)c, "%s", "no FMU state"); }
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s) { (void)b; (void)n; (void)s; return fail((Ctrl *)c, "%s", "no FMU state"); }
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference a[], size_t na,
                                        const fmi2ValueReference b[], size_t nb,
                                        const fmi2Real d[], fmi2Real r[]) {
    (void)a; (void)na; (void)b; (void)nb; (void)d; (void)r;
    return fail((Ctrl *)c, "%s", "no directional derivatives");
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer o[], const fmi2Real v[]) {
    (void)vr; (void)n; (void)o; (void)v;
    return fail((Ctrl *)c, "%s", "canInterpolateInputs is false");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer o[], fmi2Real v[]) {
    (void)vr; (void)n; (void)o; (void)v;
    return fail((Ctrl *)c, "%s", "maxOutputDerivativeOrder is 0");
}
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind k, fmi2Status *v) { (void)k; (void)v; return fail((Ctrl *)c, "%s", "no asynchronous steps"); }
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind k, fmi2Real *v) {
    if (k == fmi2LastSuccessfulTime) { *v = ((Ctrl *)c)->t; return fmi2OK; }
    return fail((Ctrl *)c, "%s", "fmi2GetRealStatus: only fmi2LastSuccessfulTime");
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind k, fmi2Integer *v) { (void)k; (void)v; return fail((Ctrl *)c, "%s", "no asynchronous steps"); }
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind k, fmi2Boolean *v) {
    if (k == fmi2Terminated) { *v = fmi2False; return fmi2OK; }
    return fail((Ctrl *)c, "%s", "fmi2GetBooleanStatus: only fmi2Terminated");
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String *v) { (void)k; (void)v; return fail((Ctrl *)c, "%s", "no asynchronous steps"); }
