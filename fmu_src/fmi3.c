/*
 * FMI 3.0 Co-Simulation and Model Exchange glue for the impact oscillator (a separate shared
 * library from the FMI 2.0 one, same model.c and solver_cvode.c).
 *
 * Co-Simulation: fmi3DoStep integrates with CVODE as fmi2DoStep does. With eventModeUsed and
 * earlyReturnAllowed it stops at each located wall event instead: earlyReturn = true,
 * lastSuccessfulTime = the event time, eventHandlingNeeded = true, outputs = the state at the
 * crossing before the jump; the jump is applied in fmi3UpdateDiscreteStates (after
 * fmi3EnterEventMode), so an importer sees the pre- and post-impact states of every impact.
 * Without eventModeUsed and earlyReturnAllowed it is the FMI 2.0 FMU. If an intermediateUpdate
 * callback is given, it is called at every wall event (before the jump) and may request an early
 * return there when earlyReturnAllowed.
 *
 * Model Exchange: as the FMI 2.0 ME interface (fmi2_cs.c): 2 states, 1 event indicator (the
 * wall), the jumps in fmi3UpdateDiscreteStates; the grazing guard is the importer's business.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "model.h"
#include "solver.h"

typedef enum {
    ST_INSTANTIATED = 1 << 0,
    ST_INIT = 1 << 1,
    ST_STEP = 1 << 2,
    ST_EVENT = 1 << 3,
    ST_CONT = 1 << 4,
    ST_TERMINATED = 1 << 5,
    ST_ERROR = 1 << 6,
} InstanceState;

#define ANY_STATE 0x7f
#define RUN_STATES (ST_STEP | ST_EVENT | ST_CONT)
#define GET_STATES (ST_INSTANTIATED | ST_INIT | RUN_STATES | ST_TERMINATED | ST_ERROR)

typedef struct {
    char *name;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback logger;
    fmi3IntermediateUpdateCallback intermediate;
    int logging;
    int is_me;
    int event_mode_used, early_return_allowed;
    InstanceState state;
    double start_time;
    double me_time;
    ModelData m;
    Solver s;
} Instance;

#define SNAPSHOT_MAGIC 0x494d5033u /* "IMP3" */
typedef struct {
    unsigned magic;
    InstanceState state;
    double start_time, me_time;
    ModelData m;
    double origin, tau;
    long events, guard_hits;
    int pending;
} Snapshot;

static void log_msg(Instance *c, fmi3Status status, const char *category, const char *fmt, ...) {
    if (!c || !c->logger) return;
    if (status == fmi3OK && !c->logging) return;
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    c->logger(c->env, status, category, buf);
}

static fmi3Status fail(Instance *c, const char *fn, const char *fmt, ...) {
    char buf[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    if (c) log_msg(c, fmi3Error, "logStatusError", "%s: %s", fn, buf);
    return fmi3Error;
}

static int allowed(Instance *c, const char *fn, int states) {
    if (!c) return 0;
    if (c->state & states) return 1;
    fail(c, fn, "not allowed in the current state (%d)", (int)c->state);
    return 0;
}

#define CHECK(fn, states) \
    Instance *c = (Instance *)instance; \
    if (!allowed(c, fn, states)) return fmi3Error

static double local_tau(const Instance *c) {
    return c->is_me ? c->me_time - floor(c->me_time) : c->s.tau;
}

static double now(const Instance *c) {
    return c->is_me ? c->me_time : solver_time(&c->s);
}

/* ---------------------------------------------------------------------------------------- */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean on, size_t n,
                               const fmi3String categories[]) {
    (void)n; (void)categories;
    CHECK("fmi3SetDebugLogging", ANY_STATE);
    c->logging = on;
    return fmi3OK;
}

static Instance *instantiate(fmi3String name, fmi3String token, fmi3Boolean logging,
                             fmi3InstanceEnvironment env, fmi3LogMessageCallback logger, int me) {
    if (!name || !name[0]) name = "ImpactOscillator";
    if (!token || strcmp(token, MODEL_GUID) != 0) {
        if (logger)
            logger(env, fmi3Error, "logStatusError",
                   "fmi3Instantiate: instantiationToken mismatch (modelDescription.xml and "
                   "binary differ)");
        return NULL;
    }
    Instance *c = calloc(1, sizeof(Instance));
    if (!c) return NULL;
    c->name = malloc(strlen(name) + 1);
    if (c->name) strcpy(c->name, name);
    c->env = env;
    c->logger = logger;
    c->logging = logging;
    c->is_me = me;
    model_set_defaults(&c->m);
    if (solver_create(&c->s, &c->m) != 0) {
        if (logger) logger(env, fmi3Error, "logStatusError", c->s.msg);
        free(c->name);
        free(c);
        return NULL;
    }
    c->state = ST_INSTANTIATED;
    return c;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token,
                                          fmi3String resources, fmi3Boolean visible,
                                          fmi3Boolean logging, fmi3InstanceEnvironment env,
                                          fmi3LogMessageCallback logger) {
    (void)resources; (void)visible;
    return instantiate(name, token, logging, env, logger, 1);
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
    fmi3Boolean logging, fmi3Boolean event_mode_used, fmi3Boolean early_return_allowed,
    const fmi3ValueReference required[], size_t n_required, fmi3InstanceEnvironment env,
    fmi3LogMessageCallback logger, fmi3IntermediateUpdateCallback intermediate) {
    (void)resources; (void)visible; (void)required; (void)n_required;
    Instance *c = instantiate(name, token, logging, env, logger, 0);
    if (!c) return NULL;
    c->event_mode_used = event_mode_used;
    c->early_return_allowed = early_return_allowed;
    c->intermediate = intermediate;
    return c;
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
    fmi3Boolean logging, fmi3InstanceEnvironment env, fmi3LogMessageCallback logger,
    fmi3ClockUpdateCallback clock, fmi3LockPreemptionCallback lock,
    fmi3UnlockPreemptionCallback unlock) {
    (void)name; (void)token; (void)resources; (void)visible; (void)logging; (void)clock;
    (void)lock; (void)unlock;
    if (logger)
        logger(env, fmi3Error, "logStatusError",
               "fmi3InstantiateScheduledExecution: not supported by this FMU");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    if (!c) return;
    solver_free(&c->s);
    free(c->name);
    free(c);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean tol_defined,
                                       fmi3Float64 tol, fmi3Float64 start,
                                       fmi3Boolean stop_defined, fmi3Float64 stop) {
    (void)stop_defined; (void)stop;
    CHECK("fmi3EnterInitializationMode", ST_INSTANTIATED);
    if (!isfinite(start)) return fail(c, "fmi3EnterInitializationMode", "startTime must be finite");
    if (tol_defined && isfinite(tol) && tol > 0.0 && tol < c->m.rtol) c->m.rtol = tol;
    c->start_time = start;
    c->state = ST_INIT;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    CHECK("fmi3ExitInitializationMode", ST_INIT);
    char buf[256];
    const char *why = model_check_consistency(&c->m, buf, sizeof buf);
    if (why) {
        c->state = ST_ERROR;
        return fail(c, "fmi3ExitInitializationMode", "%s", why);
    }
    model_update_derived(&c->m);
    solver_start(&c->s, c->start_time);
    model_initialize_state(&c->m, c->s.tau);
    c->s.events = c->s.guard_hits = 0;
    c->s.pending = 0;
    c->me_time = c->start_time;
    c->state = (c->is_me || c->event_mode_used) ? ST_EVENT : ST_STEP;
    return fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    CHECK("fmi3EnterEventMode", ST_STEP | ST_CONT);
    if (!c->is_me && !c->event_mode_used)
        return fail(c, "fmi3EnterEventMode", "instantiated with eventModeUsed = false");
    c->state = ST_EVENT;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    CHECK("fmi3Terminate", RUN_STATES | ST_ERROR);
    c->state = ST_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    CHECK("fmi3Reset", ANY_STATE);
    model_set_defaults(&c->m);
    c->start_time = 0.0;
    c->s.needs_reinit = 1;
    c->s.pending = 0;
    c->state = ST_INSTANTIATED;
    return fmi3OK;
}

/* ---------------------------------------------------------------------------------------- */
/* get / set */

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                          fmi3Float64 values[], size_t nv) {
    CHECK("fmi3GetFloat64", GET_STATES);
    if (n != nv || (n > 0 && (!vr || !values))) return fail(c, "fmi3GetFloat64", "bad arguments");
    for (size_t i = 0; i < n; ++i) {
        if (vr[i] == VR_TIME) {
            values[i] = now(c);
            continue;
        }
        const char *why = model_get_real_at(&c->m, local_tau(c), (int)vr[i], &values[i]);
        if (why) return fail(c, "fmi3GetFloat64", "value reference %u %s", vr[i], why);
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                        fmi3Int32 values[], size_t nv) {
    CHECK("fmi3GetInt32", GET_STATES);
    if (n != nv || (n > 0 && (!vr || !values))) return fail(c, "fmi3GetInt32", "bad arguments");
    for (size_t i = 0; i < n; ++i) {
        int x;
        const char *why = model_get_integer(&c->m, (int)vr[i], &x);
        if (why) return fail(c, "fmi3GetInt32", "value reference %u %s", vr[i], why);
        values[i] = x;
    }
    return fmi3OK;
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                          fmi3Boolean values[], size_t nv) {
    CHECK("fmi3GetBoolean", GET_STATES);
    if (n != nv || (n > 0 && (!vr || !values))) return fail(c, "fmi3GetBoolean", "bad arguments");
    for (size_t i = 0; i < n; ++i) {
        int x;
        const char *why = model_get_boolean(&c->m, (int)vr[i], &x);
        if (why) return fail(c, "fmi3GetBoolean", "value reference %u %s", vr[i], why);
        values[i] = x ? fmi3True : fmi3False;
    }
    return fmi3OK;
}

static fmi3Status check_settable(Instance *c, const char *fn, fmi3ValueReference vr) {
    if (c->state & (ST_INSTANTIATED | ST_INIT)) return fmi3OK;
    if ((c->state & (ST_STEP | ST_EVENT)) && model_is_tunable((int)vr)) return fmi3OK;
    return fail(c, fn, "%s (value reference %u) cannot be set now: only sigma is tunable "
                "after initialisation", model_variable_name((int)vr), vr);
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                          const fmi3Float64 values[], size_t nv) {
    CHECK("fmi3SetFloat64", ST_INSTANTIATED | ST_INIT | ST_STEP | ST_EVENT);
    if (n != nv || (n > 0 && (!vr || !values))) return fail(c, "fmi3SetFloat64", "bad arguments");
    for (size_t i = 0; i < n; ++i) {
        if (check_settable(c, "fmi3SetFloat64", vr[i]) != fmi3OK) return fmi3Error;
        const char *why = model_set_real(&c->m, (int)vr[i], values[i]);
        if (why)
            return fail(c, "fmi3SetFloat64", "%s = %g rejected: %s (value kept at its previous "
                        "setting)", model_variable_name((int)vr[i]), values[i], why);
        if (c->state & RUN_STATES) c->s.needs_reinit = 1;
    }
    return fmi3OK;
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                        const fmi3Int32 values[], size_t nv) {
    CHECK("fmi3SetInt32", ST_INSTANTIATED | ST_INIT | ST_STEP | ST_EVENT);
    if (n != nv || (n > 0 && (!vr || !values))) return fail(c, "fmi3SetInt32", "bad arguments");
    for (size_t i = 0; i < n; ++i) {
        if (check_settable(c, "fmi3SetInt32", vr[i]) != fmi3OK) return fmi3Error;
        const char *why = model_set_integer(&c->m, (int)vr[i], values[i]);
        if (why)
            return fail(c, "fmi3SetInt32", "%s = %d rejected: %s",
                        model_variable_name((int)vr[i]), values[i], why);
    }
    return fmi3OK;
}

/* Types the model has no variables of: an empty call is fine, anything else an error. */
#define NO_VARIABLES_GET(T)                                                                     \
    fmi3Status fmi3Get##T(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,       \
                          fmi3##T values[], size_t nv) {                                        \
        (void)vr; (void)values; (void)nv;                                                       \
        CHECK("fmi3Get" #T, GET_STATES);                                                        \
        return n == 0 ? fmi3OK : fail(c, "fmi3Get" #T, "the model has no " #T " variables");   \
    }
#define NO_VARIABLES_SET(T)                                                                     \
    fmi3Status fmi3Set##T(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,       \
                          const fmi3##T values[], size_t nv) {                                  \
        (void)vr; (void)values; (void)nv;                                                       \
        CHECK("fmi3Set" #T, ANY_STATE);                                                         \
        return n == 0 ? fmi3OK : fail(c, "fmi3Set" #T, "the model has no settable " #T          \
                                      " variables");                                            \
    }
#define NO_VARIABLES(T) NO_VARIABLES_GET(T) NO_VARIABLES_SET(T)
NO_VARIABLES(Float32)
NO_VARIABLES(Int8)
NO_VARIABLES(UInt8)
NO_VARIABLES(Int16)
NO_VARIABLES(UInt16)
NO_VARIABLES(UInt32)
NO_VARIABLES(Int64)
NO_VARIABLES(UInt64)
NO_VARIABLES(String)

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                          const fmi3Boolean values[], size_t nv) {
    (void)vr; (void)values; (void)nv;
    CHECK("fmi3SetBoolean", ANY_STATE);
    return n == 0 ? fmi3OK : fail(c, "fmi3SetBoolean", "no settable Boolean variables");
}

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                         size_t sizes[], fmi3Binary values[], size_t nv) {
    (void)vr; (void)sizes; (void)values; (void)nv;
    CHECK("fmi3GetBinary", ANY_STATE);
    return n == 0 ? fmi3OK : fail(c, "fmi3GetBinary", "the model has no Binary variables");
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                         const size_t sizes[], const fmi3Binary values[], size_t nv) {
    (void)vr; (void)sizes; (void)values; (void)nv;
    CHECK("fmi3SetBinary", ANY_STATE);
    return n == 0 ? fmi3OK : fail(c, "fmi3SetBinary", "the model has no Binary variables");
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                        fmi3Clock values[]) {
    (void)vr; (void)values;
    CHECK("fmi3GetClock", ANY_STATE);
    return n == 0 ? fmi3OK : fail(c, "fmi3GetClock", "the model has no clocks");
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                        const fmi3Clock values[]) {
    (void)vr; (void)values;
    CHECK("fmi3SetClock", ANY_STATE);
    return n == 0 ? fmi3OK : fail(c, "fmi3SetClock", "the model has no clocks");
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference vr,
                                               size_t *n) {
    (void)vr; (void)n;
    CHECK("fmi3GetNumberOfVariableDependencies", ANY_STATE);
    return fail(c, "fmi3GetNumberOfVariableDependencies", "not provided by this FMU");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t ei_dep[], fmi3ValueReference independents[],
                                       size_t ei_ind[], fmi3DependencyKind kinds[], size_t n) {
    (void)dependent; (void)ei_dep; (void)independents; (void)ei_ind; (void)kinds; (void)n;
    CHECK("fmi3GetVariableDependencies", ANY_STATE);
    return fail(c, "fmi3GetVariableDependencies", "not provided by this FMU");
}

/* ---------------------------------------------------------------------------------------- */
/* FMU state */

static void snapshot_take(Instance *c, Snapshot *s) {
    memset(s, 0, sizeof *s);
    s->magic = SNAPSHOT_MAGIC;
    s->state = c->state;
    s->start_time = c->start_time;
    s->me_time = c->me_time;
    s->m = c->m;
    s->origin = c->s.origin;
    s->tau = c->s.tau;
    s->events = c->s.events;
    s->guard_hits = c->s.guard_hits;
    s->pending = c->s.pending;
    c->s.needs_reinit = 1; /* same computation after "continue" and "restore, continue" */
}

static void snapshot_restore(Instance *c, const Snapshot *s) {
    c->state = s->state;
    c->start_time = s->start_time;
    c->me_time = s->me_time;
    c->m = s->m;
    c->s.origin = s->origin;
    c->s.tau = s->tau;
    c->s.events = s->events;
    c->s.guard_hits = s->guard_hits;
    c->s.pending = s->pending;
    c->s.needs_reinit = 1;
}

static int snapshot_valid(const Snapshot *s) { return s && s->magic == SNAPSHOT_MAGIC; }

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *state) {
    CHECK("fmi3GetFMUState", ST_INSTANTIATED | ST_INIT | RUN_STATES | ST_TERMINATED);
    if (!state) return fail(c, "fmi3GetFMUState", "NULL argument");
    Snapshot *s = *state ? (Snapshot *)*state : calloc(1, sizeof(Snapshot));
    if (!s) return fail(c, "fmi3GetFMUState", "out of memory");
    snapshot_take(c, s);
    *state = s;
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState state) {
    CHECK("fmi3SetFMUState", ST_INSTANTIATED | ST_INIT | RUN_STATES | ST_TERMINATED);
    if (!snapshot_valid((const Snapshot *)state))
        return fail(c, "fmi3SetFMUState", "not a state of this FMU");
    snapshot_restore(c, (const Snapshot *)state);
    return fmi3OK;
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *state) {
    CHECK("fmi3FreeFMUState", ANY_STATE);
    if (state && *state) {
        free(*state);
        *state = NULL;
    }
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState state, size_t *size) {
    CHECK("fmi3SerializedFMUStateSize", ANY_STATE);
    if (!size || !snapshot_valid((const Snapshot *)state))
        return fail(c, "fmi3SerializedFMUStateSize", "not a state of this FMU");
    *size = sizeof(Snapshot);
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState state, fmi3Byte bytes[],
                                 size_t size) {
    CHECK("fmi3SerializeFMUState", ANY_STATE);
    if (!bytes || size < sizeof(Snapshot) || !snapshot_valid((const Snapshot *)state))
        return fail(c, "fmi3SerializeFMUState", "bad state or buffer too small");
    memcpy(bytes, state, sizeof(Snapshot));
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte bytes[], size_t size,
                                   fmi3FMUState *state) {
    CHECK("fmi3DeserializeFMUState", ANY_STATE);
    Snapshot tmp;
    if (!bytes || !state || size != sizeof(Snapshot))
        return fail(c, "fmi3DeserializeFMUState", "%zu bytes are not a serialised state of this "
                    "FMU (expected %zu)", size, sizeof(Snapshot));
    memcpy(&tmp, bytes, sizeof tmp);
    if (!snapshot_valid(&tmp)) return fail(c, "fmi3DeserializeFMUState", "bad header");
    Snapshot *s = *state ? (Snapshot *)*state : calloc(1, sizeof(Snapshot));
    if (!s) return fail(c, "fmi3DeserializeFMUState", "out of memory");
    *s = tmp;
    *state = s;
    return fmi3OK;
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference u[],
                                        size_t nu, const fmi3ValueReference k[], size_t nk,
                                        const fmi3Float64 seed[], size_t ns,
                                        fmi3Float64 sens[], size_t nsens) {
    (void)u; (void)nu; (void)k; (void)nk; (void)seed; (void)ns; (void)sens; (void)nsens;
    CHECK("fmi3GetDirectionalDerivative", ANY_STATE);
    return fail(c, "fmi3GetDirectionalDerivative", "not provided by this FMU");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference u[],
                                    size_t nu, const fmi3ValueReference k[], size_t nk,
                                    const fmi3Float64 seed[], size_t ns, fmi3Float64 sens[],
                                    size_t nsens) {
    (void)u; (void)nu; (void)k; (void)nk; (void)seed; (void)ns; (void)sens; (void)nsens;
    CHECK("fmi3GetAdjointDerivative", ANY_STATE);
    return fail(c, "fmi3GetAdjointDerivative", "not provided by this FMU");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    CHECK("fmi3EnterConfigurationMode", ANY_STATE);
    return fail(c, "fmi3EnterConfigurationMode", "the model has no structural parameters");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    CHECK("fmi3ExitConfigurationMode", ANY_STATE);
    return fail(c, "fmi3ExitConfigurationMode", "the model has no structural parameters");
}

#define NO_CLOCKS(fn, ...)                                                                     \
    fmi3Status fn(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,              \
                  __VA_ARGS__) {                                                               \
        (void)vr;                                                                              \
        CHECK(#fn, ANY_STATE);                                                                 \
        return n == 0 ? fmi3OK : fail(c, #fn, "the model has no clocks");                      \
    }
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-parameter"
NO_CLOCKS(fmi3GetIntervalDecimal, fmi3Float64 iv[], fmi3IntervalQualifier q[])
NO_CLOCKS(fmi3GetIntervalFraction, fmi3UInt64 cn[], fmi3UInt64 res[], fmi3IntervalQualifier q[])
NO_CLOCKS(fmi3GetShiftDecimal, fmi3Float64 sh[])
NO_CLOCKS(fmi3GetShiftFraction, fmi3UInt64 cn[], fmi3UInt64 res[])
NO_CLOCKS(fmi3SetIntervalDecimal, const fmi3Float64 iv[])
NO_CLOCKS(fmi3SetIntervalFraction, const fmi3UInt64 cn[], const fmi3UInt64 res[])
NO_CLOCKS(fmi3SetShiftDecimal, const fmi3Float64 sh[])
NO_CLOCKS(fmi3SetShiftFraction, const fmi3UInt64 cn[], const fmi3UInt64 res[])
#pragma GCC diagnostic pop

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    CHECK("fmi3EvaluateDiscreteStates", ANY_STATE);
    return fmi3OK;
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *need_update,
                                    fmi3Boolean *terminate, fmi3Boolean *nominals_changed,
                                    fmi3Boolean *values_changed, fmi3Boolean *next_defined,
                                    fmi3Float64 *next_time) {
    CHECK("fmi3UpdateDiscreteStates", ST_EVENT);
    int changed;
    const int impacts = c->m.impacts;
    if (c->is_me) {
        double y[2] = {c->m.u, c->m.v};
        changed = model_me_event_update(&c->m, local_tau(c), y);
        c->m.u = y[0];
        c->m.v = y[1];
        if (changed) c->s.events++;
    } else {
        changed = solver_apply_pending(&c->s, &c->m); /* the jump of an early return */
    }
    if (changed)
        log_msg(c, fmi3OK, "logEvents", "fmi3UpdateDiscreteStates: wall event at t = %.17g%s",
                now(c), c->m.impacts != impacts ? " (impact)" : "");
    if (need_update) *need_update = fmi3False;
    if (terminate) *terminate = fmi3False;
    if (nominals_changed) *nominals_changed = fmi3False;
    if (values_changed) *values_changed = changed ? fmi3True : fmi3False;
    if (next_defined) *next_defined = fmi3False;
    if (next_time) *next_time = 0.0;
    return fmi3OK;
}

/* ---------------------------------------------------------------------------------------- */
/* Model Exchange */

#define ME_CHECK(fn, states) \
    CHECK(fn, states); \
    if (!c->is_me) return fail(c, fn, "instance was not instantiated for Model Exchange")

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    ME_CHECK("fmi3EnterContinuousTimeMode", ST_EVENT);
    c->state = ST_CONT;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean no_prior,
                                       fmi3Boolean *enter_event, fmi3Boolean *terminate) {
    (void)no_prior;
    ME_CHECK("fmi3CompletedIntegratorStep", ST_CONT);
    if (enter_event) *enter_event = fmi3False;
    if (terminate) *terminate = fmi3False;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 t) {
    ME_CHECK("fmi3SetTime", ST_EVENT | ST_CONT);
    if (!isfinite(t)) return fail(c, "fmi3SetTime", "time must be finite");
    c->me_time = t;
    return fmi3OK;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 x[], size_t n) {
    ME_CHECK("fmi3SetContinuousStates", ST_EVENT | ST_CONT);
    if (n != 2 || !x) return fail(c, "fmi3SetContinuousStates", "expected 2 states, got %zu", n);
    if (!isfinite(x[0]) || !isfinite(x[1]))
        return fail(c, "fmi3SetContinuousStates", "states must be finite");
    c->m.u = x[0];
    c->m.v = x[1];
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 dx[], size_t n) {
    ME_CHECK("fmi3GetContinuousStateDerivatives", GET_STATES);
    if (n != 2 || !dx) return fail(c, "fmi3GetContinuousStateDerivatives", "expected 2 states");
    const double y[2] = {c->m.u, c->m.v};
    model_derivatives(&c->m, local_tau(c), y, dx);
    return fmi3OK;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 g[], size_t n) {
    ME_CHECK("fmi3GetEventIndicators", GET_STATES);
    if (n != MODEL_N_ME_EVENTS || !g) return fail(c, "fmi3GetEventIndicators", "expected 1");
    const double y[2] = {c->m.u, c->m.v};
    double all[MODEL_N_EVENTS];
    model_event_indicators(&c->m, local_tau(c), y, all);
    g[0] = all[0];
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t n) {
    ME_CHECK("fmi3GetContinuousStates", GET_STATES);
    if (n != 2 || !x) return fail(c, "fmi3GetContinuousStates", "expected 2 states");
    x[0] = c->m.u;
    x[1] = c->m.v;
    return fmi3OK;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t n) {
    ME_CHECK("fmi3GetNominalsOfContinuousStates", ANY_STATE);
    if (n != 2 || !x) return fail(c, "fmi3GetNominalsOfContinuousStates", "expected 2 states");
    x[0] = x[1] = 1.0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n) {
    CHECK("fmi3GetNumberOfEventIndicators", ANY_STATE);
    if (!n) return fail(c, "fmi3GetNumberOfEventIndicators", "NULL argument");
    *n = MODEL_N_ME_EVENTS;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n) {
    CHECK("fmi3GetNumberOfContinuousStates", ANY_STATE);
    if (!n) return fail(c, "fmi3GetNumberOfContinuousStates", "NULL argument");
    *n = 2;
    return fmi3OK;
}

/* ---------------------------------------------------------------------------------------- */
/* Co-Simulation */

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    CHECK("fmi3EnterStepMode", ST_EVENT);
    if (c->is_me) return fail(c, "fmi3EnterStepMode", "a Model Exchange instance");
    solver_apply_pending(&c->s, &c->m); /* an importer that skipped fmi3UpdateDiscreteStates */
    c->state = ST_STEP;
    return fmi3OK;
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[],
                                    size_t n, const fmi3Int32 order[], fmi3Float64 values[],
                                    size_t nv) {
    (void)vr; (void)n; (void)order; (void)values; (void)nv;
    CHECK("fmi3GetOutputDerivatives", ANY_STATE);
    return fail(c, "fmi3GetOutputDerivatives", "not provided by this FMU");
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 t, fmi3Float64 h, fmi3Boolean no_prior,
                      fmi3Boolean *event_needed, fmi3Boolean *terminate,
                      fmi3Boolean *early_return, fmi3Float64 *last_time) {
    (void)no_prior;
    CHECK("fmi3DoStep", ST_STEP);
    if (c->is_me) return fail(c, "fmi3DoStep", "a Model Exchange instance");
    if (!isfinite(t) || !isfinite(h) || h < 0.0)
        return fail(c, "fmi3DoStep", "bad communication step (t = %g, h = %g)", t, h);
    const double t0 = solver_time(&c->s);
    if (fabs(t - t0) > 1e-9 * fmax(1.0, fabs(t0)))
        return fail(c, "fmi3DoStep", "currentCommunicationPoint %.17g differs from the FMU's "
                    "time %.17g", t, t0);
    if (event_needed) *event_needed = fmi3False;
    if (terminate) *terminate = fmi3False;
    if (early_return) *early_return = fmi3False;
    const double t_end = t + h;
    const long events_before = c->s.events;
    const int stop_for_event_mode = c->event_mode_used && c->early_return_allowed;

    if (!stop_for_event_mode && !c->intermediate) {
        /* the FMI 2.0 path, unchanged */
        if (solver_advance(&c->s, &c->m, t_end) != 0) {
            c->state = ST_ERROR;
            return fail(c, "fmi3DoStep", "integration failed: %s", c->s.msg);
        }
    } else {
        for (;;) {
            const int rc = solver_advance_ex(&c->s, &c->m, t_end, 1);
            if (rc < 0) {
                c->state = ST_ERROR;
                return fail(c, "fmi3DoStep", "integration failed: %s", c->s.msg);
            }
            if (rc == 0) break; /* reached t_end */
            const double te = solver_time(&c->s);
            fmi3Boolean requested = fmi3False;
            fmi3Float64 requested_time = te;
            if (c->intermediate)
                c->intermediate(c->env, te, fmi3False, fmi3True, fmi3True,
                                c->early_return_allowed ? fmi3True : fmi3False, &requested,
                                &requested_time);
            if (stop_for_event_mode || (c->early_return_allowed && requested)) {
                /* With event mode the jump waits for fmi3UpdateDiscreteStates; without, it is
                 * applied here (outputs after the event). */
                if (c->event_mode_used) {
                    if (event_needed) *event_needed = fmi3True;
                } else {
                    solver_apply_pending(&c->s, &c->m);
                }
                if (early_return) *early_return = te < t_end ? fmi3True : fmi3False;
                log_msg(c, fmi3OK, "logEvents", "fmi3DoStep: early return at the wall event "
                        "t = %.17g", te);
                break;
            }
            solver_apply_pending(&c->s, &c->m);
        }
    }
    if (last_time) *last_time = solver_time(&c->s);
    if (c->s.events != events_before)
        log_msg(c, fmi3OK, "logEvents", "fmi3DoStep: %ld wall events in (%.17g, %.17g]",
                c->s.events - events_before, t, solver_time(&c->s));
    return fmi3OK;
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clock,
                                      fmi3Float64 t) {
    (void)clock; (void)t;
    CHECK("fmi3ActivateModelPartition", ANY_STATE);
    return fail(c, "fmi3ActivateModelPartition", "not a Scheduled Execution FMU");
}
