/*
 * FMI 2.0 Co-Simulation and Model Exchange glue: translates the fmi2 calls to the shared core
 * (fmu_core.h), which holds the instance, its state machine, the variables, the snapshots and
 * the stepping loop. No physics here (model.c), no rules either (the core's units).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmu_core.h"

/* The importer's fmi2 logger formats its message printf-style: '%' is replaced, and the text is
 * passed as the argument of "%s". */
static void log_fmi2(void *env, const char *name, int status, const char *category,
                     const char *message) {
    const fmi2CallbackFunctions *cb = (const fmi2CallbackFunctions *)env;
    char buf[1024];
    snprintf(buf, sizeof buf, "%s", message);
    for (char *p = buf; *p; ++p)
        if (*p == '%') *p = ' ';
    cb->logger(cb->componentEnvironment, name, (fmi2Status)status, category, "%s", buf);
}

typedef struct {
    fmi2CallbackFunctions cb; /* first: the core's log environment points here */
    CoreInstance *core;
} Fmi2Instance;

#define C(comp) ((comp) ? ((Fmi2Instance *)(comp))->core : NULL)
#define S(x) ((fmi2Status)(x))

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean on, size_t n,
                               const fmi2String categories[]) {
    return S(core_set_logging(C(comp), "fmi2SetDebugLogging", on, n, categories));
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
    Fmi2Instance *w = cb->allocateMemory ? cb->allocateMemory(1, sizeof *w) : calloc(1, sizeof *w);
    if (!w) return NULL;
    w->cb = *cb;
    w->core = core_instantiate(name, type == fmi2ModelExchange ? IF_FMI2_ME : IF_FMI2_CS, &w->cb,
                               log_fmi2, cb->allocateMemory, cb->freeMemory, logging);
    if (!w->core) {
        if (cb->freeMemory) cb->freeMemory(w);
        else free(w);
        return NULL;
    }
    return w;
}

void fmi2FreeInstance(fmi2Component comp) {
    Fmi2Instance *w = (Fmi2Instance *)comp;
    if (!w || !core_allowed(w->core, "fmi2FreeInstance")) return;
    core_free(w->core);
    if (w->cb.freeMemory) w->cb.freeMemory(w);
    else free(w);
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean tol_defined, fmi2Real tol,
                               fmi2Real start, fmi2Boolean stop_defined, fmi2Real stop) {
    (void)stop_defined; (void)stop;
    return S(core_setup(C(comp), "fmi2SetupExperiment", tol_defined, tol, start));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp) {
    return S(core_enter_init(C(comp), "fmi2EnterInitializationMode"));
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp) {
    return S(core_exit_init(C(comp), "fmi2ExitInitializationMode"));
}

fmi2Status fmi2Terminate(fmi2Component comp) {
    return S(core_terminate(C(comp), "fmi2Terminate"));
}

fmi2Status fmi2Reset(fmi2Component comp) { return S(core_reset(C(comp), "fmi2Reset")); }

/* ---------------------------------------------------------------------------------------- */
/* get / set: Real goes straight through; Integer and Boolean one value at a time as double */

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                       fmi2Real value[]) {
    return S(core_get(C(comp), "fmi2GetReal", VT_REAL, vr, n, value));
}

static fmi2Status get_ints(fmi2Component comp, const char *fn, CoreVarType t,
                           const fmi2ValueReference vr[], size_t n, int value[]) {
    CoreInstance *c = C(comp);
    if (n == 0 || !vr || !value) return S(core_get(c, fn, t, vr, n, NULL));
    for (size_t i = 0; i < n; ++i) {
        double x;
        const int st = core_get(c, fn, t, &vr[i], 1, &x);
        if (st != CORE_OK) return S(st);
        value[i] = t == VT_BOOLEAN ? (x != 0.0 ? fmi2True : fmi2False) : (int)x;
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          fmi2Integer value[]) {
    return get_ints(comp, "fmi2GetInteger", VT_INTEGER, vr, n, value);
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          fmi2Boolean value[]) {
    return get_ints(comp, "fmi2GetBoolean", VT_BOOLEAN, vr, n, value);
}

fmi2Status fmi2GetString(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                         fmi2String value[]) {
    (void)value;
    CoreInstance *c = C(comp);
    if (!core_allowed(c, "fmi2GetString")) return fmi2Error;
    if (n == 0) return fmi2OK;
    return S(core_fail(c, "fmi2GetString", "value reference %u: the model has no String "
                       "variables", vr ? vr[0] : 0u));
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real value[]) {
    return S(core_set(C(comp), "fmi2SetReal", VT_REAL, vr, n, value));
}

static fmi2Status set_ints(fmi2Component comp, const char *fn, CoreVarType t,
                           const fmi2ValueReference vr[], size_t n, const int value[]) {
    CoreInstance *c = C(comp);
    if (n == 0 || !vr || !value) return S(core_set(c, fn, t, vr, n, NULL));
    for (size_t i = 0; i < n; ++i) {
        const double x = t == VT_BOOLEAN ? (value[i] != fmi2False) : value[i];
        const int st = core_set(c, fn, t, &vr[i], 1, &x);
        if (st != CORE_OK) return S(st);
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          const fmi2Integer value[]) {
    return set_ints(comp, "fmi2SetInteger", VT_INTEGER, vr, n, value);
}

fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          const fmi2Boolean value[]) {
    return set_ints(comp, "fmi2SetBoolean", VT_BOOLEAN, vr, n, value);
}

fmi2Status fmi2SetString(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                         const fmi2String value[]) {
    (void)value;
    CoreInstance *c = C(comp);
    if (!core_allowed(c, "fmi2SetString")) return fmi2Error;
    if (n == 0) return fmi2OK;
    return S(core_fail(c, "fmi2SetString", "value reference %u: the model has no String "
                       "variables", vr ? vr[0] : 0u));
}

/* ---------------------------------------------------------------------------------------- */
/* FMU state */

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *state) {
    return S(core_get_state(C(comp), "fmi2GetFMUstate", state));
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate state) {
    return S(core_set_state(C(comp), "fmi2SetFMUstate", state));
}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *state) {
    return S(core_free_state(C(comp), "fmi2FreeFMUstate", state));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate state, size_t *size) {
    return S(core_serialized_size(C(comp), "fmi2SerializedFMUstateSize", state, size));
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate state, fmi2Byte bytes[],
                                 size_t size) {
    return S(core_serialize(C(comp), "fmi2SerializeFMUstate", state, (unsigned char *)bytes,
                            size));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *state) {
    return S(core_deserialize(C(comp), "fmi2DeSerializeFMUstate", (const unsigned char *)bytes,
                              size, state));
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp, const fmi2ValueReference u[],
                                        size_t nu, const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real dv[], fmi2Real dz[]) {
    /* FMI 2.0: u are the unknowns, z the knowns, dv the seed over z, dz the result over u */
    return S(core_directional_derivative(C(comp), "fmi2GetDirectionalDerivative", u, nu, z, nz,
                                         dv, dz));
}

/* ---------------------------------------------------------------------------------------- */
/* Co-Simulation */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                       size_t n, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    return S(core_set_input_derivatives(C(comp), "fmi2SetRealInputDerivatives", vr, n, order,
                                        value));
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                        size_t n, const fmi2Integer order[], fmi2Real value[]) {
    (void)vr; (void)n; (void)order; (void)value;
    CoreInstance *c = C(comp);
    if (!core_allowed(c, "fmi2GetRealOutputDerivatives")) return fmi2Error;
    return S(core_fail(c, "fmi2GetRealOutputDerivatives", "not provided by this FMU"));
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real t, fmi2Real h, fmi2Boolean no_prior) {
    (void)no_prior;
    return S(core_do_step(C(comp), "fmi2DoStep", t, h, 0, NULL, NULL, NULL, NULL));
}

fmi2Status fmi2CancelStep(fmi2Component comp) {
    CoreInstance *c = C(comp);
    if (!core_allowed(c, "fmi2CancelStep")) return fmi2Error; /* never: no step in progress */
    return S(core_fail(c, "fmi2CancelStep", "doStep is synchronous; nothing to cancel"));
}

fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value) {
    (void)s; (void)value;
    CoreInstance *c = C(comp);
    if (!core_allowed(c, "fmi2GetStatus")) return fmi2Error;
    return S(core_fail(c, "fmi2GetStatus", "doStep is synchronous; no status to query"));
}

fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real *value) {
    CoreInstance *c = C(comp);
    if (!core_allowed(c, "fmi2GetRealStatus")) return fmi2Error;
    if (s != fmi2LastSuccessfulTime || !value)
        return S(core_fail(c, "fmi2GetRealStatus", "only fmi2LastSuccessfulTime is available"));
    *value = core_time(c);
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s; (void)value;
    CoreInstance *c = C(comp);
    if (!core_allowed(c, "fmi2GetIntegerStatus")) return fmi2Error;
    return S(core_fail(c, "fmi2GetIntegerStatus", "no integer status"));
}

fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Boolean *value) {
    (void)s; (void)value;
    CoreInstance *c = C(comp);
    if (!core_allowed(c, "fmi2GetBooleanStatus")) return fmi2Error;
    return S(core_fail(c, "fmi2GetBooleanStatus", "no boolean status"));
}

fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s, fmi2String *value) {
    (void)s; (void)value;
    CoreInstance *c = C(comp);
    if (!core_allowed(c, "fmi2GetStringStatus")) return fmi2Error;
    return S(core_fail(c, "fmi2GetStringStatus", "no string status"));
}

/* ---------------------------------------------------------------------------------------- */
/* Model Exchange: the importer integrates (u, v); the FMU gives derivatives, the wall
 * indicator g0 and the jumps (fmu_me.c). */

fmi2Status fmi2EnterEventMode(fmi2Component comp) {
    return S(core_enter_event_mode(C(comp), "fmi2EnterEventMode"));
}

fmi2Status fmi2NewDiscreteStates(fmi2Component comp, fmi2EventInfo *info) {
    CoreInstance *c = C(comp);
    if (!core_allowed(c, "fmi2NewDiscreteStates")) return fmi2Error;
    if (!info) return S(core_fail(c, "fmi2NewDiscreteStates", "NULL argument"));
    int changed = 0;
    const int st = core_update_discrete(c, "fmi2NewDiscreteStates", &changed);
    if (st != CORE_OK) return S(st);
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = changed ? fmi2True : fmi2False;
    info->nextEventTimeDefined = fmi2False;
    info->nextEventTime = 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component comp) {
    return S(core_enter_continuous_mode(C(comp), "fmi2EnterContinuousTimeMode"));
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component comp, fmi2Boolean no_prior,
                                       fmi2Boolean *enter_event, fmi2Boolean *terminate) {
    (void)no_prior;
    int e = 0, t = 0;
    const int st = core_completed_step(C(comp), "fmi2CompletedIntegratorStep", &e, &t);
    if (enter_event) *enter_event = e ? fmi2True : fmi2False;
    if (terminate) *terminate = t ? fmi2True : fmi2False;
    return S(st);
}

fmi2Status fmi2SetTime(fmi2Component comp, fmi2Real t) {
    return S(core_set_time(C(comp), "fmi2SetTime", t));
}

fmi2Status fmi2SetContinuousStates(fmi2Component comp, const fmi2Real x[], size_t n) {
    return S(core_set_states(C(comp), "fmi2SetContinuousStates", x, n));
}

fmi2Status fmi2GetDerivatives(fmi2Component comp, fmi2Real dx[], size_t n) {
    return S(core_get_derivatives(C(comp), "fmi2GetDerivatives", dx, n));
}

fmi2Status fmi2GetEventIndicators(fmi2Component comp, fmi2Real g[], size_t n) {
    return S(core_get_event_indicators(C(comp), "fmi2GetEventIndicators", g, n));
}

fmi2Status fmi2GetContinuousStates(fmi2Component comp, fmi2Real x[], size_t n) {
    return S(core_get_states(C(comp), "fmi2GetContinuousStates", x, n));
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component comp, fmi2Real x[], size_t n) {
    return S(core_get_nominals(C(comp), "fmi2GetNominalsOfContinuousStates", x, n));
}
