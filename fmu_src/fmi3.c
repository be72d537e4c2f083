/*
 * FMI 3.0 Co-Simulation and Model Exchange glue for the impact oscillator (a separate shared
 * library from the FMI 2.0 one, same core, model.c and steppers).
 *
 * Co-Simulation: fmi3DoStep integrates with the stepper as fmi2DoStep does. With eventModeUsed and
 * earlyReturnAllowed it stops at each located wall event instead: earlyReturn = true,
 * lastSuccessfulTime = the event time, eventHandlingNeeded = true, outputs = the state at the
 * crossing before the jump; the jump is applied in fmi3UpdateDiscreteStates (after
 * fmi3EnterEventMode), so an importer sees the pre- and post-impact states of every impact.
 * Without eventModeUsed and earlyReturnAllowed it is the FMI 2.0 FMU. If an intermediateUpdate
 * callback is given, it is called at every wall event (before the jump) and may request an early
 * return there when earlyReturnAllowed.
 *
 * Model Exchange: as the FMI 2.0 ME interface (fmi2.c): 2 states, 1 event indicator (the
 * wall), the jumps in fmi3UpdateDiscreteStates; the grazing guard is the importer's business.
 *
 * Everything but the type translation lives in the shared core (fmu_core.h).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "fmu_core.h"

/* What the core needs beyond its own instance: the importer's callbacks. */
typedef struct {
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback logger;
    fmi3IntermediateUpdateCallback intermediate;
} Fmi3Env;

typedef struct {
    Fmi3Env e;
    CoreInstance *core;
} Fmi3Instance;

static void log_fmi3(void *env, const char *name, int status, const char *category,
                     const char *message) {
    (void)name;
    const Fmi3Env *e = (const Fmi3Env *)env;
    if (e->logger) e->logger(e->env, (fmi3Status)status, category, message);
}

#define S(x) ((fmi3Status)(x))
#define CHECK(fn) \
    CoreInstance *c = instance ? ((Fmi3Instance *)instance)->core : NULL; \
    if (!core_allowed(c, fn)) return fmi3Error
#define CORE(instance) ((instance) ? ((Fmi3Instance *)(instance))->core : NULL)

/* ---------------------------------------------------------------------------------------- */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean on, size_t n,
                               const fmi3String categories[]) {
    return S(core_set_logging(CORE(instance), "fmi3SetDebugLogging", on, n, categories));
}

static Fmi3Instance *instantiate(fmi3String name, fmi3String token, fmi3Boolean logging,
                                 fmi3InstanceEnvironment env, fmi3LogMessageCallback logger,
                                 CoreInterface iface) {
    if (!name || !name[0]) name = "ImpactOscillator";
    if (!token || strcmp(token, MODEL_GUID) != 0) {
        if (logger)
            logger(env, fmi3Error, "logStatusError",
                   "fmi3Instantiate: instantiationToken mismatch (modelDescription.xml and "
                   "binary differ)");
        return NULL;
    }
    Fmi3Instance *w = calloc(1, sizeof *w);
    if (!w) return NULL;
    w->e.env = env;
    w->e.logger = logger;
    w->core = core_instantiate(name, iface, &w->e, log_fmi3, NULL, NULL, logging);
    if (!w->core) {
        free(w);
        return NULL;
    }
    return w;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token,
                                          fmi3String resources, fmi3Boolean visible,
                                          fmi3Boolean logging, fmi3InstanceEnvironment env,
                                          fmi3LogMessageCallback logger) {
    (void)resources; (void)visible;
    return instantiate(name, token, logging, env, logger, IF_FMI3_ME);
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
    fmi3Boolean logging, fmi3Boolean event_mode_used, fmi3Boolean early_return_allowed,
    const fmi3ValueReference required[], size_t n_required, fmi3InstanceEnvironment env,
    fmi3LogMessageCallback logger, fmi3IntermediateUpdateCallback intermediate) {
    (void)resources; (void)visible; (void)required; (void)n_required;
    Fmi3Instance *w = instantiate(name, token, logging, env, logger, IF_FMI3_CS);
    if (!w) return NULL;
    w->core->event_mode_used = event_mode_used;
    w->core->early_return_allowed = early_return_allowed;
    w->e.intermediate = intermediate;
    return w;
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
    Fmi3Instance *w = (Fmi3Instance *)instance;
    if (!w || !core_allowed(w->core, "fmi3FreeInstance")) return; /* not from intermediateUpdate */
    core_free(w->core);
    free(w);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean tol_defined,
                                       fmi3Float64 tol, fmi3Float64 start,
                                       fmi3Boolean stop_defined, fmi3Float64 stop) {
    (void)stop_defined; (void)stop;
    CoreInstance *c = CORE(instance);
    const int st = core_setup(c, "fmi3EnterInitializationMode", tol_defined, tol, start);
    if (st != CORE_OK) return S(st);
    return S(core_enter_init(c, "fmi3EnterInitializationMode"));
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    return S(core_exit_init(CORE(instance), "fmi3ExitInitializationMode"));
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    return S(core_enter_event_mode(CORE(instance), "fmi3EnterEventMode"));
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    return S(core_terminate(CORE(instance), "fmi3Terminate"));
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    return S(core_reset(CORE(instance), "fmi3Reset"));
}

/* ---------------------------------------------------------------------------------------- */
/* get / set */

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                          fmi3Float64 values[], size_t nv) {
    CHECK("fmi3GetFloat64");
    if (n != nv) return S(core_fail(c, "fmi3GetFloat64", "bad arguments"));
    return S(core_get(c, "fmi3GetFloat64", VT_REAL, vr, n, values));
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                          const fmi3Float64 values[], size_t nv) {
    CHECK("fmi3SetFloat64");
    if (n != nv) return S(core_fail(c, "fmi3SetFloat64", "bad arguments"));
    return S(core_set(c, "fmi3SetFloat64", VT_REAL, vr, n, values));
}

/* Int32 and Boolean: one value at a time through the core's double interface. */
#define INT_ACCESS(T, VT, CT)                                                                  \
    fmi3Status fmi3Get##T(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,     \
                          CT values[], size_t nv) {                                            \
        CHECK("fmi3Get" #T);                                                           \
        if (n != nv || (n > 0 && (!vr || !values)))                                            \
            return S(core_fail(c, "fmi3Get" #T, "bad arguments"));                             \
        for (size_t i = 0; i < n; ++i) {                                                       \
            double x;                                                                          \
            const int st = core_get(c, "fmi3Get" #T, VT, &vr[i], 1, &x);                       \
            if (st != CORE_OK) return S(st);                                                   \
            values[i] = (CT)x;                                                                 \
        }                                                                                      \
        return fmi3OK;                                                                         \
    }                                                                                          \
    fmi3Status fmi3Set##T(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,     \
                          const CT values[], size_t nv) {                                      \
        CHECK("fmi3Set" #T);                                                           \
        if (n != nv || (n > 0 && (!vr || !values)))                                            \
            return S(core_fail(c, "fmi3Set" #T, "bad arguments"));                             \
        if (n == 0) return S(core_set(c, "fmi3Set" #T, VT, vr, 0, NULL));                      \
        for (size_t i = 0; i < n; ++i) {                                                       \
            const double x = (double)values[i];                                                \
            const int st = core_set(c, "fmi3Set" #T, VT, &vr[i], 1, &x);                       \
            if (st != CORE_OK) return S(st);                                                   \
        }                                                                                      \
        return fmi3OK;                                                                         \
    }
INT_ACCESS(Int32, VT_INTEGER, fmi3Int32)
INT_ACCESS(Boolean, VT_BOOLEAN, fmi3Boolean)

/* Types the model has no variables of: an empty call is fine, anything else an error. */
#define NO_VARIABLES_GET(T)                                                                     \
    fmi3Status fmi3Get##T(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,       \
                          fmi3##T values[], size_t nv) {                                        \
        (void)vr; (void)values; (void)nv;                                                       \
        CHECK("fmi3Get" #T);                                                        \
        return n == 0 ? fmi3OK : core_fail(c, "fmi3Get" #T, "the model has no " #T " variables");   \
    }
#define NO_VARIABLES_SET(T)                                                                     \
    fmi3Status fmi3Set##T(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,       \
                          const fmi3##T values[], size_t nv) {                                  \
        (void)vr; (void)values; (void)nv;                                                       \
        CHECK("fmi3Set" #T);                                                         \
        return n == 0 ? fmi3OK : core_fail(c, "fmi3Set" #T, "the model has no settable " #T          \
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

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                         size_t sizes[], fmi3Binary values[], size_t nv) {
    (void)vr; (void)sizes; (void)values; (void)nv;
    CHECK("fmi3GetBinary");
    return n == 0 ? fmi3OK : core_fail(c, "fmi3GetBinary", "the model has no Binary variables");
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                         const size_t sizes[], const fmi3Binary values[], size_t nv) {
    (void)vr; (void)sizes; (void)values; (void)nv;
    CHECK("fmi3SetBinary");
    return n == 0 ? fmi3OK : core_fail(c, "fmi3SetBinary", "the model has no Binary variables");
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                        fmi3Clock values[]) {
    (void)vr; (void)values;
    CHECK("fmi3GetClock");
    return n == 0 ? fmi3OK : core_fail(c, "fmi3GetClock", "the model has no clocks");
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                        const fmi3Clock values[]) {
    (void)vr; (void)values;
    CHECK("fmi3SetClock");
    return n == 0 ? fmi3OK : core_fail(c, "fmi3SetClock", "the model has no clocks");
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference vr,
                                               size_t *n) {
    (void)vr; (void)n;
    CHECK("fmi3GetNumberOfVariableDependencies");
    return core_fail(c, "fmi3GetNumberOfVariableDependencies", "not provided by this FMU");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t ei_dep[], fmi3ValueReference independents[],
                                       size_t ei_ind[], fmi3DependencyKind kinds[], size_t n) {
    (void)dependent; (void)ei_dep; (void)independents; (void)ei_ind; (void)kinds; (void)n;
    CHECK("fmi3GetVariableDependencies");
    return core_fail(c, "fmi3GetVariableDependencies", "not provided by this FMU");
}

/* ---------------------------------------------------------------------------------------- */
/* FMU state */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *state) {
    return S(core_get_state(CORE(instance), "fmi3GetFMUState", state));
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState state) {
    return S(core_set_state(CORE(instance), "fmi3SetFMUState", state));
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *state) {
    return S(core_free_state(CORE(instance), "fmi3FreeFMUState", state));
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState state, size_t *size) {
    return S(core_serialized_size(CORE(instance), "fmi3SerializedFMUStateSize", state, size));
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState state, fmi3Byte bytes[],
                                 size_t size) {
    return S(core_serialize(CORE(instance), "fmi3SerializeFMUState", state,
                            (unsigned char *)bytes, size));
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte bytes[], size_t size,
                                   fmi3FMUState *state) {
    return S(core_deserialize(CORE(instance), "fmi3DeserializeFMUState",
                              (const unsigned char *)bytes, size, state));
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference u[],
                                        size_t nu, const fmi3ValueReference k[], size_t nk,
                                        const fmi3Float64 seed[], size_t ns,
                                        fmi3Float64 sens[], size_t nsens) {
    CHECK("fmi3GetDirectionalDerivative");
    if (ns != nk || nsens != nu) /* FMI 3.0: nSeed = nKnowns, nSensitivity = nUnknowns */
        return S(core_fail(c, "fmi3GetDirectionalDerivative", "nSeed = %zu, nSensitivity = %zu: "
                           "must equal nKnowns = %zu and nUnknowns = %zu", ns, nsens, nk, nu));
    return S(core_directional_derivative(c, "fmi3GetDirectionalDerivative", u, nu, k, nk, seed,
                                         sens));
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference u[],
                                    size_t nu, const fmi3ValueReference k[], size_t nk,
                                    const fmi3Float64 seed[], size_t ns, fmi3Float64 sens[],
                                    size_t nsens) {
    CHECK("fmi3GetAdjointDerivative");
    if (ns != nu || nsens != nk) /* FMI 3.0: nSeed = nUnknowns, nSensitivity = nKnowns */
        return S(core_fail(c, "fmi3GetAdjointDerivative", "nSeed = %zu, nSensitivity = %zu: "
                           "must equal nUnknowns = %zu and nKnowns = %zu", ns, nsens, nu, nk));
    return S(core_adjoint_derivative(c, "fmi3GetAdjointDerivative", u, nu, k, nk, seed, sens));
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    CHECK("fmi3EnterConfigurationMode");
    return core_fail(c, "fmi3EnterConfigurationMode", "the model has no structural parameters");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    CHECK("fmi3ExitConfigurationMode");
    return core_fail(c, "fmi3ExitConfigurationMode", "the model has no structural parameters");
}

#define NO_CLOCKS(fn, ...)                                                                     \
    fmi3Status fn(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,              \
                  __VA_ARGS__) {                                                               \
        (void)vr;                                                                              \
        CHECK(#fn);                                                                 \
        return n == 0 ? fmi3OK : core_fail(c, #fn, "the model has no clocks");                      \
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
    CHECK("fmi3EvaluateDiscreteStates");
    return fmi3OK;
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *need_update,
                                    fmi3Boolean *terminate, fmi3Boolean *nominals_changed,
                                    fmi3Boolean *values_changed, fmi3Boolean *next_defined,
                                    fmi3Float64 *next_time) {
    int changed = 0;
    const int st = core_update_discrete(CORE(instance), "fmi3UpdateDiscreteStates", &changed);
    /* fmi3EvaluateDiscreteStates is not declared (providesEvaluateDiscreteStates): the table
     * refuses it in every state. */
    if (st != CORE_OK) return S(st);
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

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    return S(core_enter_continuous_mode(CORE(instance), "fmi3EnterContinuousTimeMode"));
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean no_prior,
                                       fmi3Boolean *enter_event, fmi3Boolean *terminate) {
    (void)no_prior;
    int e = 0, t = 0;
    const int st = core_completed_step(CORE(instance), "fmi3CompletedIntegratorStep", &e, &t);
    if (enter_event) *enter_event = e ? fmi3True : fmi3False;
    if (terminate) *terminate = t ? fmi3True : fmi3False;
    return S(st);
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 t) {
    return S(core_set_time(CORE(instance), "fmi3SetTime", t));
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 x[], size_t n) {
    return S(core_set_states(CORE(instance), "fmi3SetContinuousStates", x, n));
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 dx[], size_t n) {
    return S(core_get_derivatives(CORE(instance), "fmi3GetContinuousStateDerivatives", dx, n));
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 g[], size_t n) {
    return S(core_get_event_indicators(CORE(instance), "fmi3GetEventIndicators", g, n));
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t n) {
    return S(core_get_states(CORE(instance), "fmi3GetContinuousStates", x, n));
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t n) {
    return S(core_get_nominals(CORE(instance), "fmi3GetNominalsOfContinuousStates", x, n));
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n) {
    CHECK("fmi3GetNumberOfEventIndicators");
    if (!n) return S(core_fail(c, "fmi3GetNumberOfEventIndicators", "NULL argument"));
    *n = MODEL_N_ME_EVENTS;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n) {
    CHECK("fmi3GetNumberOfContinuousStates");
    if (!n) return S(core_fail(c, "fmi3GetNumberOfContinuousStates", "NULL argument"));
    *n = MODEL_N_STATES;
    return fmi3OK;
}

/* ---------------------------------------------------------------------------------------- */
/* Co-Simulation */

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    return S(core_enter_step_mode(CORE(instance), "fmi3EnterStepMode"));
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[],
                                    size_t n, const fmi3Int32 order[], fmi3Float64 values[],
                                    size_t nv) {
    (void)vr; (void)n; (void)order; (void)values; (void)nv;
    CHECK("fmi3GetOutputDerivatives");
    return S(core_fail(c, "fmi3GetOutputDerivatives", "not provided by this FMU"));
}

/* The importer's intermediateUpdate at a wall event (before its jump): it may ask for an early
 * return there. */
static int intermediate_update(CoreInstance *c, double te) {
    const Fmi3Env *e = (const Fmi3Env *)c->env;
    fmi3Boolean requested = fmi3False;
    fmi3Float64 requested_time = te;
    e->intermediate(e->env, te, fmi3False, fmi3True, fmi3True,
                    c->early_return_allowed ? fmi3True : fmi3False, &requested,
                    &requested_time);
    return requested == fmi3True;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 t, fmi3Float64 h, fmi3Boolean no_prior,
                      fmi3Boolean *event_needed, fmi3Boolean *terminate,
                      fmi3Boolean *early_return, fmi3Float64 *last_time) {
    (void)no_prior;
    CoreInstance *c = CORE(instance);
    if (terminate) *terminate = fmi3False;
    int ev = 0, early = 0;
    double last = 0.0;
    const Fmi3Env *e = c ? (const Fmi3Env *)c->env : NULL;
    const int st = core_do_step(c, "fmi3DoStep", t, h,
                                c && c->event_mode_used && c->early_return_allowed,
                                e && e->intermediate ? intermediate_update : NULL, &ev, &early,
                                &last);
    if (event_needed) *event_needed = ev ? fmi3True : fmi3False;
    if (early_return) *early_return = early ? fmi3True : fmi3False;
    if (last_time && st == CORE_OK) *last_time = last;
    return S(st);
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clock,
                                      fmi3Float64 t) {
    (void)clock; (void)t;
    CHECK("fmi3ActivateModelPartition");
    return S(core_fail(c, "fmi3ActivateModelPartition", "not a Scheduled Execution FMU"));
}
