/*
 * FMI 2.0 Co-Simulation and Model Exchange glue for the impact oscillator: instance life cycle,
 * the state machine of the standard, typed get/set by value reference, FMU state
 * save/restore/serialisation, fmi2DoStep on top of the CVODE driver, and the Model Exchange
 * functions (the importer integrates u, v and watches the wall indicator). No physics here
 * (see model.c).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "model.h"
#include "solver.h"

typedef enum {
    ST_INSTANTIATED = 1 << 0,
    ST_INIT = 1 << 1,
    ST_STEP = 1 << 2,
    ST_TERMINATED = 1 << 3,
    ST_ERROR = 1 << 4,
    ST_EVENT = 1 << 5, /* Model Exchange: event mode */
    ST_CONT = 1 << 6,  /* Model Exchange: continuous-time mode */
} InstanceState;

#define ANY_STATE (ST_INSTANTIATED | ST_INIT | ST_STEP | ST_TERMINATED | ST_ERROR | ST_EVENT | ST_CONT)
#define RUN_STATES (ST_STEP | ST_EVENT | ST_CONT) /* initialised, not terminated */

typedef struct {
    char *name;
    fmi2CallbackFunctions cb;
    fmi2Boolean logging;
    InstanceState state;
    double start_time;
    ModelData m;
    Solver s;
    int is_me;       /* instantiated for Model Exchange */
    double me_time;  /* Model Exchange: the time set by the importer */
} Instance;

/* What an FMU state snapshot holds: enough to restart CVODE at exactly the saved point. */
#define SNAPSHOT_MAGIC 0x494d504fu /* "IMPO" */
#define SNAPSHOT_VERSION 1u
typedef struct {
    unsigned magic, version;
    InstanceState state;
    double start_time;
    ModelData m;
    double origin, tau;
    long events, guard_hits;
    double me_time;
} Snapshot;

static void log_msg(Instance *c, fmi2Status status, const char *category, const char *fmt, ...) {
    if (!c || !c->cb.logger) return;
    if (status == fmi2OK && !c->logging) return;
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    /* '%' in the message would be read as a format by the importer's logger */
    for (char *p = buf; *p; ++p)
        if (*p == '%') *p = ' ';
    c->cb.logger(c->cb.componentEnvironment, c->name, status, category, "%s", buf);
}

static fmi2Status fail(Instance *c, const char *fn, const char *fmt, ...) {
    char buf[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    if (c) log_msg(c, fmi2Error, "logStatusError", "%s: %s", fn, buf);
    return fmi2Error;
}

/* The standard's state machine: a call outside its allowed states is an error, never a crash. */
static int allowed(Instance *c, const char *fn, int states) {
    if (!c) return 0;
    if (c->state & states) return 1;
    fail(c, fn, "not allowed in the current state (%d)", (int)c->state);
    return 0;
}

static void *alloc_mem(Instance *c, size_t n) {
    return c->cb.allocateMemory ? c->cb.allocateMemory(1, n) : calloc(1, n);
}

static void free_mem(Instance *c, void *p) {
    if (!p) return;
    if (c->cb.freeMemory) c->cb.freeMemory(p);
    else free(p);
}

/* ---------------------------------------------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean on, size_t n,
                               const fmi2String categories[]) {
    (void)n; (void)categories;
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2SetDebugLogging", ANY_STATE)) return fmi2Error;
    c->logging = on;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources, const fmi2CallbackFunctions *cb,
                              fmi2Boolean visible, fmi2Boolean logging) {
    (void)resources; (void)visible;
    if (!cb || !cb->logger) return NULL;
    if (!name || !name[0]) name = "ImpactOscillator";
    if (type != fmi2CoSimulation && type != fmi2ModelExchange) {
        cb->logger(cb->componentEnvironment, name, fmi2Error, "logStatusError",
                   "fmi2Instantiate: unknown FMU type");
        return NULL;
    }
    if (!guid || strcmp(guid, MODEL_GUID) != 0) {
        cb->logger(cb->componentEnvironment, name, fmi2Error, "logStatusError",
                   "fmi2Instantiate: GUID mismatch (modelDescription.xml and binary differ)");
        return NULL;
    }
    Instance *c = cb->allocateMemory ? cb->allocateMemory(1, sizeof(Instance))
                                     : calloc(1, sizeof(Instance));
    if (!c) return NULL;
    c->cb = *cb;
    c->logging = logging;
    c->name = alloc_mem(c, strlen(name) + 1);
    if (c->name) strcpy(c->name, name);
    model_set_defaults(&c->m);
    if (solver_create(&c->s, &c->m) != 0) {
        cb->logger(cb->componentEnvironment, name, fmi2Error, "logStatusError",
                   "fmi2Instantiate: %s", c->s.msg);
        free_mem(c, c->name);
        free_mem(c, c);
        return NULL;
    }
    c->is_me = type == fmi2ModelExchange;
    c->state = ST_INSTANTIATED;
    return c;
}

void fmi2FreeInstance(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    if (!c) return;
    solver_free(&c->s);
    free_mem(c, c->name);
    free_mem(c, c);
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean tol_defined, fmi2Real tol,
                               fmi2Real start, fmi2Boolean stop_defined, fmi2Real stop) {
    (void)stop_defined; (void)stop;
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2SetupExperiment", ST_INSTANTIATED)) return fmi2Error;
    if (!isfinite(start)) return fail(c, "fmi2SetupExperiment", "startTime must be finite");
    /* The importer's tolerance tightens (never loosens) the FMU's own rtol. */
    if (tol_defined && isfinite(tol) && tol > 0.0 && tol < c->m.rtol) c->m.rtol = tol;
    c->start_time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2EnterInitializationMode", ST_INSTANTIATED)) return fmi2Error;
    c->state = ST_INIT;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2ExitInitializationMode", ST_INIT)) return fmi2Error;
    char buf[256];
    const char *why = model_check_consistency(&c->m, buf, sizeof buf);
    if (why) {
        c->state = ST_ERROR;
        return fail(c, "fmi2ExitInitializationMode", "%s", why);
    }
    model_update_derived(&c->m);
    solver_start(&c->s, c->start_time);
    model_initialize_state(&c->m, c->s.tau);
    c->s.events = c->s.guard_hits = 0;
    c->me_time = c->start_time;
    c->state = c->is_me ? ST_EVENT : ST_STEP;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2Terminate", RUN_STATES | ST_ERROR)) return fmi2Error;
    c->state = ST_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2Reset", ANY_STATE)) return fmi2Error;
    /* CVODE's memory is kept: the next run re-initialises it instead of reallocating. */
    model_set_defaults(&c->m);
    c->start_time = 0.0;
    c->s.needs_reinit = 1;
    c->state = ST_INSTANTIATED;
    return fmi2OK;
}

/* ---------------------------------------------------------------------------------------- */
/* get / set */

#define GET_STATES (ST_INIT | RUN_STATES | ST_TERMINATED | ST_ERROR)

/* Local time (model.h) of the current state: the solver's, or in Model Exchange the importer's
 * time reduced by whole periods (exact in floating point). */
static double local_tau(const Instance *c) {
    return c->is_me ? c->me_time - floor(c->me_time) : c->s.tau;
}

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                       fmi2Real value[]) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2GetReal", GET_STATES | ST_INSTANTIATED)) return fmi2Error;
    if (n > 0 && (!vr || !value)) return fail(c, "fmi2GetReal", "NULL argument");
    for (size_t i = 0; i < n; ++i) {
        const char *why = model_get_real_at(&c->m, local_tau(c), (int)vr[i], &value[i]);
        if (why) return fail(c, "fmi2GetReal", "value reference %u %s", vr[i], why);
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          fmi2Integer value[]) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2GetInteger", GET_STATES | ST_INSTANTIATED)) return fmi2Error;
    if (n > 0 && (!vr || !value)) return fail(c, "fmi2GetInteger", "NULL argument");
    for (size_t i = 0; i < n; ++i) {
        int x;
        const char *why = model_get_integer(&c->m, (int)vr[i], &x);
        if (why) return fail(c, "fmi2GetInteger", "value reference %u %s", vr[i], why);
        value[i] = x;
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          fmi2Boolean value[]) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2GetBoolean", GET_STATES | ST_INSTANTIATED)) return fmi2Error;
    if (n > 0 && (!vr || !value)) return fail(c, "fmi2GetBoolean", "NULL argument");
    for (size_t i = 0; i < n; ++i) {
        int x;
        const char *why = model_get_boolean(&c->m, (int)vr[i], &x);
        if (why) return fail(c, "fmi2GetBoolean", "value reference %u %s", vr[i], why);
        value[i] = x ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                         fmi2String value[]) {
    (void)value;
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2GetString", GET_STATES | ST_INSTANTIATED)) return fmi2Error;
    if (n == 0) return fmi2OK;
    return fail(c, "fmi2GetString", "value reference %u: the model has no String variables",
                vr ? vr[0] : 0u);
}

/* Parameters may be set before initialisation ends; afterwards only tunable ones. */
static fmi2Status check_settable(Instance *c, const char *fn, fmi2ValueReference vr) {
    if (c->state & (ST_INSTANTIATED | ST_INIT)) return fmi2OK;
    if ((c->state & RUN_STATES) && model_is_tunable((int)vr)) return fmi2OK;
    return fail(c, fn, "%s (value reference %u) cannot be set now: only sigma is tunable "
                "after initialisation", model_variable_name((int)vr), vr);
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real value[]) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2SetReal", ST_INSTANTIATED | ST_INIT | RUN_STATES)) return fmi2Error;
    if (n > 0 && (!vr || !value)) return fail(c, "fmi2SetReal", "NULL argument");
    for (size_t i = 0; i < n; ++i) {
        if (check_settable(c, "fmi2SetReal", vr[i]) != fmi2OK) return fmi2Error;
        const char *why = model_set_real(&c->m, (int)vr[i], value[i]);
        if (why)
            return fail(c, "fmi2SetReal", "%s = %g rejected: %s (value kept at its previous "
                        "setting)", model_variable_name((int)vr[i]), value[i], why);
        /* a new sigma changes the right-hand side from now on: CVODE restarts here */
        if (c->state == ST_STEP) c->s.needs_reinit = 1;
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          const fmi2Integer value[]) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2SetInteger", ST_INSTANTIATED | ST_INIT | RUN_STATES)) return fmi2Error;
    if (n > 0 && (!vr || !value)) return fail(c, "fmi2SetInteger", "NULL argument");
    for (size_t i = 0; i < n; ++i) {
        if (check_settable(c, "fmi2SetInteger", vr[i]) != fmi2OK) return fmi2Error;
        const char *why = model_set_integer(&c->m, (int)vr[i], value[i]);
        if (why)
            return fail(c, "fmi2SetInteger", "%s = %d rejected: %s",
                        model_variable_name((int)vr[i]), value[i], why);
    }
    return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          const fmi2Boolean value[]) {
    (void)value;
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2SetBoolean", ST_INSTANTIATED | ST_INIT | RUN_STATES)) return fmi2Error;
    if (n == 0) return fmi2OK;
    return fail(c, "fmi2SetBoolean", "value reference %u is not a settable Boolean",
                vr ? vr[0] : 0u);
}

fmi2Status fmi2SetString(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                         const fmi2String value[]) {
    (void)value;
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2SetString", ST_INSTANTIATED | ST_INIT | RUN_STATES)) return fmi2Error;
    if (n == 0) return fmi2OK;
    return fail(c, "fmi2SetString", "value reference %u: the model has no String variables",
                vr ? vr[0] : 0u);
}

/* ---------------------------------------------------------------------------------------- */
/* FMU state */

static void snapshot_take(Instance *c, Snapshot *s) {
    memset(s, 0, sizeof *s);
    s->magic = SNAPSHOT_MAGIC;
    s->version = SNAPSHOT_VERSION;
    s->state = c->state;
    s->start_time = c->start_time;
    s->m = c->m;
    s->origin = c->s.origin;
    s->tau = c->s.tau;
    s->events = c->s.events;
    s->guard_hits = c->s.guard_hits;
    s->me_time = c->me_time;
    /* CVODE's step history is not part of the snapshot; restarting the live instance here too
     * makes "continue" and "restore, then continue" follow the very same computation. */
    c->s.needs_reinit = 1;
}

static void snapshot_restore(Instance *c, const Snapshot *s) {
    c->state = s->state;
    c->start_time = s->start_time;
    c->m = s->m;
    c->s.origin = s->origin;
    c->s.tau = s->tau;
    c->s.events = s->events;
    c->s.guard_hits = s->guard_hits;
    c->me_time = s->me_time;
    c->s.needs_reinit = 1;
}

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *state) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2GetFMUstate", ST_INSTANTIATED | ST_INIT | RUN_STATES | ST_TERMINATED))
        return fmi2Error;
    if (!state) return fail(c, "fmi2GetFMUstate", "NULL argument");
    Snapshot *s = *state ? (Snapshot *)*state : alloc_mem(c, sizeof(Snapshot));
    if (!s) return fail(c, "fmi2GetFMUstate", "out of memory");
    snapshot_take(c, s);
    *state = s;
    return fmi2OK;
}

static int snapshot_valid(const Snapshot *s) {
    return s && s->magic == SNAPSHOT_MAGIC && s->version == SNAPSHOT_VERSION;
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate state) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2SetFMUstate", ST_INSTANTIATED | ST_INIT | RUN_STATES | ST_TERMINATED))
        return fmi2Error;
    if (!snapshot_valid((const Snapshot *)state))
        return fail(c, "fmi2SetFMUstate", "not a state of this FMU");
    snapshot_restore(c, (const Snapshot *)state);
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *state) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2FreeFMUstate", ANY_STATE)) return fmi2Error;
    if (state && *state) {
        free_mem(c, *state);
        *state = NULL;
    }
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate state, size_t *size) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2SerializedFMUstateSize", ANY_STATE)) return fmi2Error;
    if (!size || !snapshot_valid((const Snapshot *)state))
        return fail(c, "fmi2SerializedFMUstateSize", "not a state of this FMU");
    *size = sizeof(Snapshot);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate state, fmi2Byte bytes[],
                                 size_t size) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2SerializeFMUstate", ANY_STATE)) return fmi2Error;
    if (!bytes || size < sizeof(Snapshot) || !snapshot_valid((const Snapshot *)state))
        return fail(c, "fmi2SerializeFMUstate", "bad state or buffer too small");
    memcpy(bytes, state, sizeof(Snapshot));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *state) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2DeSerializeFMUstate", ANY_STATE)) return fmi2Error;
    Snapshot tmp;
    if (!bytes || !state || size != sizeof(Snapshot))
        return fail(c, "fmi2DeSerializeFMUstate", "%zu bytes are not a serialised state of this "
                    "FMU (expected %zu)", size, sizeof(Snapshot));
    memcpy(&tmp, bytes, sizeof tmp);
    if (!snapshot_valid(&tmp))
        return fail(c, "fmi2DeSerializeFMUstate", "not a state of this FMU (bad header)");
    Snapshot *s = *state ? (Snapshot *)*state : alloc_mem(c, sizeof(Snapshot));
    if (!s) return fail(c, "fmi2DeSerializeFMUstate", "out of memory");
    *s = tmp;
    *state = s;
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp, const fmi2ValueReference u[],
                                        size_t nu, const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real dv[], fmi2Real dz[]) {
    (void)u; (void)nu; (void)z; (void)nz; (void)dv; (void)dz;
    return fail((Instance *)comp, "fmi2GetDirectionalDerivative", "not provided by this FMU");
}

/* ---------------------------------------------------------------------------------------- */
/* Co-Simulation */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                       size_t n, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    (void)vr; (void)n; (void)order; (void)value;
    return fail((Instance *)comp, "fmi2SetRealInputDerivatives", "the model has no inputs");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                        size_t n, const fmi2Integer order[], fmi2Real value[]) {
    (void)vr; (void)n; (void)order; (void)value;
    return fail((Instance *)comp, "fmi2GetRealOutputDerivatives", "not provided by this FMU");
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real t, fmi2Real h, fmi2Boolean no_prior) {
    (void)no_prior;
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2DoStep", ST_STEP)) return fmi2Error;
    if (!isfinite(t) || !isfinite(h) || h < 0.0)
        return fail(c, "fmi2DoStep", "bad communication step (t = %g, h = %g)", t, h);
    const double now = solver_time(&c->s);
    if (fabs(t - now) > 1e-9 * fmax(1.0, fabs(now)))
        return fail(c, "fmi2DoStep", "currentCommunicationPoint %.17g differs from the FMU's "
                    "time %.17g", t, now);
    const long guard_before = c->s.guard_hits, events_before = c->s.events;
    if (solver_advance(&c->s, &c->m, t + h) != 0) {
        c->state = ST_ERROR;
        return fail(c, "fmi2DoStep", "integration failed: %s", c->s.msg);
    }
    if (c->s.events != events_before)
        log_msg(c, fmi2OK, "logEvents", "fmi2DoStep: %ld wall events in (%.17g, %.17g], "
                "%ld of them found by the grazing guard", c->s.events - events_before, t, t + h,
                c->s.guard_hits - guard_before);
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component comp) {
    return fail((Instance *)comp, "fmi2CancelStep", "doStep is synchronous; nothing to cancel");
}

fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value) {
    (void)s; (void)value;
    return fail((Instance *)comp, "fmi2GetStatus", "doStep is synchronous; no status to query");
}

fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real *value) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2GetRealStatus", ANY_STATE)) return fmi2Error;
    if (s != fmi2LastSuccessfulTime || !value)
        return fail(c, "fmi2GetRealStatus", "only fmi2LastSuccessfulTime is available");
    *value = solver_time(&c->s);
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s; (void)value;
    return fail((Instance *)comp, "fmi2GetIntegerStatus", "no integer status");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Boolean *value) {
    (void)s; (void)value;
    return fail((Instance *)comp, "fmi2GetBooleanStatus", "no boolean status");
}

fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s, fmi2String *value) {
    (void)s; (void)value;
    return fail((Instance *)comp, "fmi2GetStringStatus", "no string status");
}

/* ---------------------------------------------------------------------------------------- */
/* Model Exchange: the importer integrates (u, v); the FMU gives derivatives, the wall
 * indicator g0 and the jumps. The grazing guard of the CS solver is not part of ME: a contact
 * that enters and leaves the wall within one of the importer's steps is the importer's to find
 * (or miss). */

#define ME_ONLY(c, fn, states) \
    do { \
        if (!allowed(c, fn, states)) return fmi2Error; \
        if (!c->is_me) return fail(c, fn, "instance was not instantiated for Model Exchange"); \
    } while (0)

fmi2Status fmi2EnterEventMode(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    ME_ONLY(c, "fmi2EnterEventMode", ST_EVENT | ST_CONT);
    c->state = ST_EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component comp, fmi2EventInfo *info) {
    Instance *c = (Instance *)comp;
    ME_ONLY(c, "fmi2NewDiscreteStates", ST_EVENT);
    if (!info) return fail(c, "fmi2NewDiscreteStates", "NULL argument");
    double y[2] = {c->m.u, c->m.v};
    const int impacts = c->m.impacts;
    const int changed = model_me_event_update(&c->m, local_tau(c), y);
    c->m.u = y[0];
    c->m.v = y[1];
    if (changed) {
        c->s.events++;
        log_msg(c, fmi2OK, "logEvents", "fmi2NewDiscreteStates: wall event at t = %.17g%s",
                c->me_time, c->m.impacts != impacts ? " (impact)" : "");
    }
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = changed ? fmi2True : fmi2False;
    info->nextEventTimeDefined = fmi2False;
    info->nextEventTime = 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    ME_ONLY(c, "fmi2EnterContinuousTimeMode", ST_EVENT);
    c->state = ST_CONT;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component comp, fmi2Boolean no_prior,
                                       fmi2Boolean *enter_event, fmi2Boolean *terminate) {
    (void)no_prior;
    Instance *c = (Instance *)comp;
    ME_ONLY(c, "fmi2CompletedIntegratorStep", ST_CONT);
    if (enter_event) *enter_event = fmi2False;
    if (terminate) *terminate = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component comp, fmi2Real t) {
    Instance *c = (Instance *)comp;
    ME_ONLY(c, "fmi2SetTime", ST_EVENT | ST_CONT);
    if (!isfinite(t)) return fail(c, "fmi2SetTime", "time must be finite");
    c->me_time = t;
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component comp, const fmi2Real x[], size_t n) {
    Instance *c = (Instance *)comp;
    ME_ONLY(c, "fmi2SetContinuousStates", ST_EVENT | ST_CONT);
    if (n != 2 || !x) return fail(c, "fmi2SetContinuousStates", "expected 2 states, got %zu", n);
    if (!isfinite(x[0]) || !isfinite(x[1]))
        return fail(c, "fmi2SetContinuousStates", "states must be finite");
    c->m.u = x[0];
    c->m.v = x[1];
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component comp, fmi2Real dx[], size_t n) {
    Instance *c = (Instance *)comp;
    ME_ONLY(c, "fmi2GetDerivatives", GET_STATES);
    if (n != 2 || !dx) return fail(c, "fmi2GetDerivatives", "expected 2 states, got %zu", n);
    const double y[2] = {c->m.u, c->m.v};
    model_derivatives(&c->m, local_tau(c), y, dx);
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component comp, fmi2Real g[], size_t n) {
    Instance *c = (Instance *)comp;
    ME_ONLY(c, "fmi2GetEventIndicators", GET_STATES);
    if (n != MODEL_N_ME_EVENTS || !g)
        return fail(c, "fmi2GetEventIndicators", "expected %d indicators, got %zu",
                    MODEL_N_ME_EVENTS, n);
    const double y[2] = {c->m.u, c->m.v};
    double all[MODEL_N_EVENTS];
    model_event_indicators(&c->m, local_tau(c), y, all);
    g[0] = all[0];
    return fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component comp, fmi2Real x[], size_t n) {
    Instance *c = (Instance *)comp;
    ME_ONLY(c, "fmi2GetContinuousStates", GET_STATES);
    if (n != 2 || !x) return fail(c, "fmi2GetContinuousStates", "expected 2 states, got %zu", n);
    x[0] = c->m.u;
    x[1] = c->m.v;
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component comp, fmi2Real x[], size_t n) {
    Instance *c = (Instance *)comp;
    ME_ONLY(c, "fmi2GetNominalsOfContinuousStates", ANY_STATE);
    if (n != 2 || !x) return fail(c, "fmi2GetNominalsOfContinuousStates", "expected 2 states");
    x[0] = x[1] = 1.0;
    return fmi2OK;
}
