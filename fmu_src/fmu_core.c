/*
 * The FMI core shared by FMI 2.0 and 3.0, Co-Simulation and Model Exchange (see fmu_core.h).
 * Everything the standard asks of an instance lives here once; fmi2_cs.c and fmi3.c translate.
 */
#include "fmu_core.h"
#include "sens.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------ */
/* Logging and state machine */

/* The standards' state machines as data: for each FMI function, the states in which it may be
 * called, per interface. Taken from FMI 2.0.4 sections 3.2.3 (Model Exchange) and 4.2.4
 * (Co-Simulation) and FMI 3.0 sections 3.2 (Model Exchange) and 4.2 (Co-Simulation, with and
 * without eventModeUsed, Intermediate Update Mode), narrowed where this FMU declares less
 * (no clocks, no structural parameters, no providesEvaluateDiscreteStates, no variable with
 * intermediateUpdate = true). docs/fmi-state-machine.md is rendered from this table
 * (scripts/state_table_doc.py; tests/test_fmi_state_doc.py keeps them equal), and
 * tests/test_fmi_conformance.py checks every (state, function) pair against a table written
 * independently from the standards' text (tests/fmi_standard.py).
 *
 * States: I Instantiated, N Initialization Mode, S Step Mode (FMI 2.0: stepComplete), E Event
 * Mode, C Continuous-Time Mode, T Terminated, X Error (FMI 2.0; FMI 3.0 enters Terminated on
 * fmi3Error), U Intermediate Update Mode (no call allowed: nothing is declared for it).
 * Columns: Co-Simulation, Model Exchange, FMI 3.0 Co-Simulation with eventModeUsed.
 * Keep one row per line: the documentation is parsed from it. */
typedef struct {
    const char *fn;
    int cs, me, cs_event;
} StateRow;

#define I CS_INSTANTIATED
#define N CS_INIT
#define S CS_STEP
#define E CS_EVENT
#define C CS_CONT
#define T CS_TERMINATED
#define X CS_ERROR
/* STATE_TABLE_BEGIN */
static const StateRow STATE_TABLE[] = {
    {"fmi2SetDebugLogging", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2SetupExperiment", I, I, 0},
    {"fmi2EnterInitializationMode", I, I, 0},
    {"fmi2ExitInitializationMode", N, N, 0},
    {"fmi2Terminate", S, E|C, 0},
    {"fmi2Reset", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2FreeInstance", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2GetReal", N|S|T|X, N|E|C|T|X, 0},
    {"fmi2GetInteger", N|S|T|X, N|E|C|T|X, 0},
    {"fmi2GetBoolean", N|S|T|X, N|E|C|T|X, 0},
    {"fmi2GetString", N|S|T|X, N|E|C|T|X, 0},
    {"fmi2SetReal", I|N|S, I|N|E|C, 0},
    {"fmi2SetInteger", I|N|S, I|N|E, 0},
    {"fmi2SetBoolean", I|N|S, I|N|E, 0},
    {"fmi2SetString", I|N|S, I|N|E, 0},
    {"fmi2GetFMUstate", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2SetFMUstate", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2FreeFMUstate", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2SerializedFMUstateSize", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2SerializeFMUstate", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2DeSerializeFMUstate", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2GetDirectionalDerivative", N|S|T|X, N|E|C|T|X, 0},
    {"fmi2SetRealInputDerivatives", I|N|S, 0, 0},
    {"fmi2GetRealOutputDerivatives", S|T|X, 0, 0},
    {"fmi2DoStep", S, 0, 0},
    {"fmi2CancelStep", 0, 0, 0},
    {"fmi2GetStatus", S|T, 0, 0},
    {"fmi2GetRealStatus", S|T, 0, 0},
    {"fmi2GetIntegerStatus", S|T, 0, 0},
    {"fmi2GetBooleanStatus", S|T, 0, 0},
    {"fmi2GetStringStatus", S|T, 0, 0},
    {"fmi2EnterEventMode", 0, E|C, 0},
    {"fmi2NewDiscreteStates", 0, E, 0},
    {"fmi2EnterContinuousTimeMode", 0, E, 0},
    {"fmi2CompletedIntegratorStep", 0, C, 0},
    {"fmi2SetTime", 0, C, 0},
    {"fmi2SetContinuousStates", 0, C, 0},
    {"fmi2GetDerivatives", 0, E|C|T|X, 0},
    {"fmi2GetEventIndicators", 0, N|E|C|T|X, 0},
    {"fmi2GetContinuousStates", 0, N|E|C|T|X, 0},
    {"fmi2GetNominalsOfContinuousStates", 0, I|E|C|T|X, 0},
    {"fmi3SetDebugLogging", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3EnterInitializationMode", I, I, I},
    {"fmi3ExitInitializationMode", N, N, N},
    {"fmi3EnterEventMode", 0, E|C, S},
    {"fmi3Terminate", S, E|C, S|E},
    {"fmi3Reset", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3FreeInstance", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3GetFloat32", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetFloat64", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetInt8", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetUInt8", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetInt16", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetUInt16", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetInt32", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetUInt32", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetInt64", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetUInt64", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetBoolean", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetString", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetBinary", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3SetFloat32", I|N|S, I|N|E|C, I|N|S|E},
    {"fmi3SetFloat64", I|N|S, I|N|E|C, I|N|S|E},
    {"fmi3SetInt8", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetUInt8", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetInt16", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetUInt16", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetInt32", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetUInt32", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetInt64", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetUInt64", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetBoolean", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetString", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetBinary", I|N|S, I|N|E, I|N|S|E},
    {"fmi3GetClock", 0, E, E},
    {"fmi3SetClock", 0, E, E},
    {"fmi3GetIntervalDecimal", 0, E, E},
    {"fmi3GetIntervalFraction", 0, E, E},
    {"fmi3GetShiftDecimal", 0, E, E},
    {"fmi3GetShiftFraction", 0, E, E},
    {"fmi3SetIntervalDecimal", 0, E, E},
    {"fmi3SetIntervalFraction", 0, E, E},
    {"fmi3SetShiftDecimal", 0, E, E},
    {"fmi3SetShiftFraction", 0, E, E},
    {"fmi3GetNumberOfVariableDependencies", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3GetVariableDependencies", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3GetFMUState", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3SetFMUState", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3FreeFMUState", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3SerializedFMUStateSize", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3SerializeFMUState", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3DeserializeFMUState", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3GetDirectionalDerivative", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetAdjointDerivative", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3EnterConfigurationMode", I|S, I|E, I|S|E},
    {"fmi3ExitConfigurationMode", 0, 0, 0},
    {"fmi3EvaluateDiscreteStates", 0, 0, 0},
    {"fmi3UpdateDiscreteStates", 0, E, E},
    {"fmi3EnterContinuousTimeMode", 0, E, 0},
    {"fmi3CompletedIntegratorStep", 0, C, 0},
    {"fmi3SetTime", 0, E|C, 0},
    {"fmi3SetContinuousStates", 0, C, 0},
    {"fmi3GetContinuousStateDerivatives", 0, N|E|C|T, 0},
    {"fmi3GetEventIndicators", 0, N|E|C|T, 0},
    {"fmi3GetContinuousStates", 0, N|E|C|T, 0},
    {"fmi3GetNominalsOfContinuousStates", 0, N|E|C|T, 0},
    {"fmi3GetNumberOfEventIndicators", 0, I|N|E|C|T, 0},
    {"fmi3GetNumberOfContinuousStates", 0, I|N|E|C|T, 0},
    {"fmi3EnterStepMode", 0, 0, E},
    {"fmi3GetOutputDerivatives", S|T, 0, S|E|T},
    {"fmi3DoStep", S, 0, S},
    {"fmi3ActivateModelPartition", 0, 0, 0},
};
/* STATE_TABLE_END */
#undef I
#undef N
#undef S
#undef E
#undef C
#undef T
#undef X

void core_log(CoreInstance *c, int status, const char *category, const char *fmt, ...) {
    if (!c || !c->log) return;
    /* with logging off, only errors reach the importer (their message is the only account of
     * why a call failed) */
    if (status < CORE_ERROR && !c->logging) return;
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    c->log(c->env, c->name, status, category, buf);
}

int core_set_logging(CoreInstance *c, const char *fn, int on, size_t n,
                     const char *const categories[]) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (n > 0 && !categories) return core_fail(c, fn, "%zu categories but a NULL array", n);
    for (size_t i = 0; i < n; ++i) {
        const char *k = categories[i];
        if (!k || (strcmp(k, "logStatusError") && strcmp(k, "logStatusWarning") &&
                   strcmp(k, "logEvents")))
            return core_fail(c, fn, "category %s is not one of the modelDescription's "
                             "LogCategories", k ? k : "(NULL)");
    }
    c->logging = on != 0;
    return CORE_OK;
}

int core_error_state(const CoreInstance *c) { return c->fmi3 ? CS_TERMINATED : CS_ERROR; }

int core_fail(CoreInstance *c, const char *fn, const char *fmt, ...) {
    char buf[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    if (!c) return CORE_ERROR;
    core_log(c, CORE_ERROR, "logStatusError", "%s: %s", fn, buf);
    /* FMI 2.0 (2.1.3): after fmi2Error the simulation cannot be continued (Error state, left by
     * fmi2SetFMUstate, fmi2Reset or fmi2FreeInstance); FMI 3.0 (2.2.3, 4.2): the instance is
     * in Terminated (fmi3SetFMUState, fmi3Reset, fmi3FreeInstance). */
    c->state = core_error_state(c);
    return CORE_ERROR;
}

int core_allowed_states(CoreInterface iface, int event_mode, const char *fn) {
    if (!fn) return -1;
    for (size_t i = 0; i < sizeof STATE_TABLE / sizeof STATE_TABLE[0]; ++i) {
        const StateRow *r = &STATE_TABLE[i];
        if (strcmp(r->fn, fn) != 0) continue;
        if (iface == IF_FMI2_ME || iface == IF_FMI3_ME) return r->me;
        return iface == IF_FMI3_CS && event_mode ? r->cs_event : r->cs;
    }
    return -1;
}

static const char *state_name(int state) {
    switch (state) {
    case CS_INSTANTIATED: return "Instantiated";
    case CS_INIT: return "Initialization Mode";
    case CS_STEP: return "Step Mode";
    case CS_EVENT: return "Event Mode";
    case CS_CONT: return "Continuous-Time Mode";
    case CS_TERMINATED: return "Terminated";
    case CS_ERROR: return "Error";
    case CS_INTERMEDIATE: return "Intermediate Update Mode";
    default: return "an unknown state";
    }
}

int core_allowed(CoreInstance *c, const char *fn) {
    if (!c) return 0;
    const int states = core_allowed_states(c->iface, c->event_mode_used, fn);
    if (states < 0) {
        core_fail(c, fn ? fn : "?", "not in the FMU's state table (an FMU bug)");
        return 0;
    }
    if (c->state & states) return 1;
    static const char *const IFACE[] = {"?", "FMI 2.0 Co-Simulation", "FMI 2.0 Model Exchange",
                                        "FMI 3.0 Co-Simulation", "FMI 3.0 Model Exchange"};
    core_fail(c, fn, "not allowed in %s (%s%s; docs/fmi-state-machine.md)",
              state_name(c->state), IFACE[c->iface],
              c->iface == IF_FMI3_CS ? (c->event_mode_used ? " with eventModeUsed"
                                                            : " without eventModeUsed") : "");
    return 0;
}

static double local_tau(const CoreInstance *c) {
    return c->is_me ? c->me_time - floor(c->me_time) : c->s.tau;
}

double core_time(const CoreInstance *c) { return c->is_me ? c->me_time : solver_time(&c->s); }

/* ------------------------------------------------------------------------------------------ */
/* The variable table: one entry per value reference. */

typedef enum {
    K_FIXED = 'f',      /* parameter, settable before initialisation ends */
    K_TUNABLE = 't',    /* parameter, also settable after (c->tunable_states) */
    K_INPUT = 'i',      /* input, settable in every state but Terminated/Error */
    K_CALCULATED = 'c', /* calculated parameter */
    K_OUTPUT = 'o',
    K_LOCAL = 'l',
    K_INDEPENDENT = 'x', /* FMI 3.0 time */
} Kind;

#define NO_FIELD ((size_t)-1)
#define FIELD(f) offsetof(ModelData, f)

typedef struct {
    unsigned vr;
    const char *name;
    CoreVarType type;
    Kind kind;
    size_t off;      /* offset of its double (Real) or int (Integer/Boolean) in ModelData */
    double lo, hi;   /* valid range of a settable value (also checked on snapshots) */
    int lo_open;     /* lo excluded */
    double (*get)(const CoreInstance *c); /* computed values (off == NO_FIELD) */
    int fmi3_only;
} VarDef;

static double get_in_contact(const CoreInstance *c) { return c->m.mode != MODE_FREE; }
/* Sensitivities of the last doStep (sens.h); J = I, S = 0 (as set at initialisation) when they
 * are not computed, so that every output stays finite. */
static double get_sens(const CoreInstance *c, int i) {
    return i < 4 ? c->m.sJ[i / 2][i % 2] : c->m.sS[i - 4];
}
static double get_J_uu(const CoreInstance *c) { return get_sens(c, 0); }
static double get_J_uv(const CoreInstance *c) { return get_sens(c, 1); }
static double get_J_vu(const CoreInstance *c) { return get_sens(c, 2); }
static double get_J_vv(const CoreInstance *c) { return get_sens(c, 3); }
static double get_S_u(const CoreInstance *c) { return get_sens(c, 4); }
static double get_S_v(const CoreInstance *c) { return get_sens(c, 5); }
static double get_der(const CoreInstance *c, int i) {
    const double y[2] = {c->m.u, c->m.v};
    double dy[2];
    model_derivatives(&c->m, local_tau(c), y, dy);
    return dy[i];
}
static double get_der_u(const CoreInstance *c) { return get_der(c, 0); }
static double get_der_v(const CoreInstance *c) { return get_der(c, 1); }
static double get_indicator(const CoreInstance *c) {
    const double y[2] = {c->m.u, c->m.v};
    double g[MODEL_N_EVENTS];
    model_event_indicators(&c->m, local_tau(c), y, g);
    return g[0];
}
static double get_time(const CoreInstance *c) { return core_time(c); }
static double get_contact_force(const CoreInstance *c) {
    if (c->inputs_changed && !c->is_me) {
        /* F_contact feeds through from u_wall (ModelStructure): with a new wall position not
         * yet stepped over, report the force of the state the wall-jump rule gives now. */
        ModelData m;
        memcpy(&m, &c->m, sizeof m);
        double y[2] = {m.u, m.v};
        model_input_jump(&m, local_tau(c), y);
        m.u = y[0];
        m.v = y[1];
        return model_contact_output(&m, local_tau(c));
    }
    return model_contact_output(&c->m, local_tau(c));
}
/* Inputs read back as their value now (a ramp given by input derivatives included). */
static double get_F_ext(const CoreInstance *c) {
    return model_external_force(&c->m, local_tau(c));
}
static double get_u_wall(const CoreInstance *c) {
    return model_wall_position(&c->m, local_tau(c));
}

/* Valid ranges: chosen so that every derived quantity (F_g, kappa, the forcing, the wall
 * force) stays finite with many orders of magnitude to spare; README "Valid ranges". */
static const VarDef VARS[] = {
#include "variables_table.inc" /* generated from fmu_src/variables.py */
};
#define N_VARS (sizeof VARS / sizeof VARS[0])

/* Bounds on the input derivatives (slopes per unit time). */
static const double MAX_DF_EXT = 1e12, MAX_DU_WALL = 1e6;

static const VarDef *find_var(const CoreInstance *c, unsigned vr) {
    for (size_t i = 0; i < N_VARS; ++i)
        if (VARS[i].vr == vr) return VARS[i].fmi3_only && !c->fmi3 ? NULL : &VARS[i];
    return NULL;
}

const char *core_variable_name(unsigned vr) {
    for (size_t i = 0; i < N_VARS; ++i)
        if (VARS[i].vr == vr) return VARS[i].name;
    return "?";
}

static const char *const TYPE_NAMES[] = {"Real", "Integer", "Boolean"};

static int settable(const VarDef *d) {
    return d->kind == K_FIXED || d->kind == K_TUNABLE || d->kind == K_INPUT;
}

/* Why x is not a valid value of d (NULL if it is); buf receives the message. */
static const char *check_value(const VarDef *d, double x, char *buf, size_t n) {
    if (!isfinite(x)) return "must be a finite number";
    if (d->type != VT_REAL && x != floor(x)) return "must be an integer";
    const int below = d->lo_open ? !(x > d->lo) : !(x >= d->lo);
    if (below || !(x <= d->hi)) {
        snprintf(buf, n, "must lie in %c%g, %g]", d->lo_open ? '(' : '[', d->lo, d->hi);
        return buf;
    }
    return NULL;
}

static double field_get(const ModelData *m, const VarDef *d) {
    const char *p = (const char *)m + d->off;
    if (d->type == VT_REAL) {
        double x;
        memcpy(&x, p, sizeof x);
        return x;
    }
    int i;
    memcpy(&i, p, sizeof i);
    return i;
}

static void field_set(ModelData *m, const VarDef *d, double x) {
    char *p = (char *)m + d->off;
    if (d->type == VT_REAL) {
        memcpy(p, &x, sizeof x);
    } else {
        const int i = (int)x;
        memcpy(p, &i, sizeof i);
    }
}

/* Folds the input ramps into the input values at local time tau (the reference point moves
 * to tau; the values there are unchanged). */
static void rebase_inputs(ModelData *m, double tau) {
    if (m->dF_ext != 0.0) m->F_ext = model_external_force(m, tau);
    if (m->du_wall != 0.0) m->u_wall = model_wall_position(m, tau);
    m->in_tau = tau;
}

int core_get(CoreInstance *c, const char *fn, CoreVarType t, const unsigned vr[], size_t n,
             double out[]) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (n > 0 && (!vr || !out)) return core_fail(c, fn, "NULL argument");
    for (size_t i = 0; i < n; ++i) {
        const VarDef *d = find_var(c, vr[i]);
        if (!d || d->type != t)
            return core_fail(c, fn, "value reference %u is not a%s %s variable", vr[i],
                             t == VT_INTEGER ? "n" : "", TYPE_NAMES[t]);
        out[i] = d->get ? d->get(c) : field_get(&c->m, d);
    }
    return CORE_OK;
}

/* Checks the quantities derived from several parameters (kappa, the forcing amplitude) of a
 * parameter set that is in use (after initialisation). */
static const char *check_derived(const ModelData *m, char *buf, size_t n) {
    if (!(m->kappa <= 1e8)) {
        snprintf(buf, n, "kappa = sqrt(Gamma) Omega = %g would exceed 1e8", m->kappa);
        return buf;
    }
    const double amp = (1.0 + m->sigma) * m->F_g;
    if (!isfinite(m->phi) || !(fabs(amp) <= 1e15)) {
        snprintf(buf, n, "the forcing amplitude (1 + sigma) F_g = %g would exceed 1e15", amp);
        return buf;
    }
    return NULL;
}

int core_set(CoreInstance *c, const char *fn, CoreVarType t, const unsigned vr[], size_t n,
             const double in[]) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (n > 0 && (!vr || !in)) return core_fail(c, fn, "NULL argument");
    for (size_t i = 0; i < n; ++i) {
        const VarDef *d = find_var(c, vr[i]);
        if (!d || d->type != t || !settable(d))
            return core_fail(c, fn, "value reference %u is not a settable %s variable", vr[i],
                             TYPE_NAMES[t]);
        const int early = (c->state & (CS_INSTANTIATED | CS_INIT)) != 0;
        if (!early && !(d->kind == K_INPUT ||
                        (d->kind == K_TUNABLE && (c->state & c->tunable_states))))
            return core_fail(c, fn, "%s (value reference %u) cannot be set now: only sigma is "
                             "tunable after initialisation", d->name, vr[i]);
        char buf[200];
        const char *why = check_value(d, in[i], buf, sizeof buf);
        /* a value valid alone may still overflow a derived quantity of the running model */
        ModelData trial;
        memcpy(&trial, &c->m, sizeof trial);
        if (!why && d->kind != K_INPUT) {
            field_set(&trial, d, in[i]);
            model_update_derived(&trial);
            if (!early) why = check_derived(&trial, buf, sizeof buf);
        }
        if (why) {
            if (t == VT_REAL)
                return core_fail(c, fn, "%s = %g rejected: %s (value kept at its previous "
                                 "setting)", d->name, in[i], why);
            return core_fail(c, fn, "%s = %.17g rejected: %s", d->name, in[i], why);
        }
        if (d->kind == K_INPUT) {
            const double tau = local_tau(c);
            const double before = d->get(c);
            rebase_inputs(&c->m, tau);
            field_set(&c->m, d, in[i]);
            /* a jump: in Co-Simulation between steps; in Model Exchange only in Event Mode (the
             * standards let an importer change inputs discontinuously only there; in
             * Continuous-Time Mode an input is a continuous signal) */
            if (in[i] != before && !early && (!c->is_me || c->state == CS_EVENT)) {
                c->inputs_changed = 1;
                if (!c->is_me) c->s.needs_reinit = 1; /* the right-hand side changed here */
            }
        } else {
            memcpy(&c->m, &trial, sizeof trial);
            /* a new sigma changes the right-hand side from now on: CVODE restarts here */
            if (c->state & CS_RUN) c->s.needs_reinit = 1;
        }
    }
    return CORE_OK;
}

int core_set_input_derivatives(CoreInstance *c, const char *fn, const unsigned vr[], size_t n,
                               const int order[], const double value[]) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (c->is_me) return core_fail(c, fn, "a Model Exchange instance has no input derivatives");
    if (n > 0 && (!vr || !order || !value)) return core_fail(c, fn, "NULL argument");
    int status = CORE_OK;
    for (size_t i = 0; i < n; ++i) {
        if (vr[i] != VR_F_EXT && vr[i] != VR_U_WALL)
            return core_fail(c, fn, "value reference %u is not a Real input", vr[i]);
        if (order[i] < 1) return core_fail(c, fn, "order %d: must be >= 1", order[i]);
        const double bound = vr[i] == VR_F_EXT ? MAX_DF_EXT : MAX_DU_WALL;
        if (!isfinite(value[i]) || !(fabs(value[i]) <= bound))
            return core_fail(c, fn, "d%s/dt = %g rejected: must be finite with |.| <= %g",
                             core_variable_name(vr[i]), value[i], bound);
        if (order[i] > 1) { /* the inputs are integrated as linear ramps: order 1 is used */
            if (value[i] != 0.0)
                core_log(c, CORE_WARNING, "logStatusWarning", "%s: derivative of order %d of "
                         "%s ignored (maxInputDerivativeOrder is 1)", fn, order[i],
                         core_variable_name(vr[i]));
            status = value[i] != 0.0 ? CORE_WARNING : status;
            continue;
        }
        rebase_inputs(&c->m, local_tau(c));
        double *slot = vr[i] == VR_F_EXT ? &c->m.dF_ext : &c->m.du_wall;
        if (*slot != value[i]) {
            *slot = value[i];
            if (c->state == CS_STEP) {
                c->inputs_changed = 1;
                c->s.needs_reinit = 1;
            }
        }
    }
    return status;
}

/* ------------------------------------------------------------------------------------------ */
/* Life cycle */

CoreInstance *core_instantiate(const char *name, CoreInterface iface, void *env, CoreLogFn log,
                               CoreCallocFn calloc_fn, CoreFreeFn free_fn, int logging) {
    if (!name || !name[0]) name = "ImpactOscillator";
    CoreInstance *c = calloc_fn ? calloc_fn(1, sizeof(CoreInstance))
                                : calloc(1, sizeof(CoreInstance));
    if (!c) return NULL;
    c->calloc_fn = calloc_fn;
    c->free_fn = free_fn;
    c->env = env;
    c->log = log;
    c->logging = logging;
    c->iface = iface;
    c->is_me = iface == IF_FMI2_ME || iface == IF_FMI3_ME;
    c->fmi3 = iface == IF_FMI3_CS || iface == IF_FMI3_ME;
    /* FMI 3.0: Step and Event Mode; FMI 2.0 Co-Simulation: stepComplete; FMI 2.0 Model Exchange:
     * Event Mode only (Continuous-Time Mode takes continuous inputs alone). */
    c->tunable_states = c->fmi3 ? (CS_STEP | CS_EVENT) : (c->is_me ? CS_EVENT : CS_STEP);
    c->name = calloc_fn ? calloc_fn(1, strlen(name) + 1) : calloc(1, strlen(name) + 1);
    if (c->name) strcpy(c->name, name);
    model_set_defaults(&c->m);
    if (solver_create(&c->s, &c->m) != 0) {
        if (log) log(env, name, CORE_ERROR, "logStatusError", c->s.msg);
        core_free(c);
        return NULL;
    }
    c->state = CS_INSTANTIATED;
    return c;
}

static void core_release(CoreInstance *c, void *p) {
    if (!p) return;
    if (c->free_fn) c->free_fn(p);
    else free(p);
}

static void *core_alloc(CoreInstance *c, size_t n) {
    return c->calloc_fn ? c->calloc_fn(1, n) : calloc(1, n);
}

void core_free(CoreInstance *c) {
    if (!c) return;
    solver_free(&c->s);
    core_release(c, c->name);
    core_release(c, c);
}

int core_setup(CoreInstance *c, const char *fn, int tol_defined, double tol, double start) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (!isfinite(start) || !(fabs(start) <= CORE_MAX_TIME))
        return core_fail(c, fn, "startTime = %g: must be finite with |startTime| <= %g", start,
                         CORE_MAX_TIME);
    /* The importer's tolerance tightens (never loosens) the FMU's own rtol, down to its
     * smallest valid value. */
    if (tol_defined && isfinite(tol) && tol > 0.0 && tol < c->m.rtol)
        c->m.rtol = fmax(tol, 1e-15);
    c->start_time = start;
    return CORE_OK;
}

int core_enter_init(CoreInstance *c, const char *fn) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    c->state = CS_INIT;
    return CORE_OK;
}

int core_exit_init(CoreInstance *c, const char *fn) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    char buf[300];
    model_update_derived(&c->m);
    const char *why = model_check_consistency(&c->m, buf, sizeof buf);
    if (!why) why = check_derived(&c->m, buf, sizeof buf);
    if (why) return core_fail(c, fn, "%s", why);
    solver_start(&c->s, c->start_time);
    c->m.origin = c->s.origin;
    c->m.in_tau = c->s.tau;
    model_initialize_state(&c->m, c->s.tau);
    c->s.events = c->s.guard_hits = 0;
    c->s.pending = 0;
    c->inputs_changed = 0;
    c->me_time = c->start_time;
    c->state = (c->is_me || c->event_mode_used) ? CS_EVENT : CS_STEP;
    return CORE_OK;
}

int core_terminate(CoreInstance *c, const char *fn) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    c->state = CS_TERMINATED;
    return CORE_OK;
}

int core_reset(CoreInstance *c, const char *fn) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    /* CVODE's memory is kept: the next run re-initialises it instead of reallocating. */
    model_set_defaults(&c->m);
    c->start_time = 0.0;
    c->me_time = 0.0;
    solver_start(&c->s, 0.0); /* time 0, origin 0 = the model's */
    c->s.needs_reinit = 1;
    c->s.pending = 0;
    c->inputs_changed = 0;
    c->state = CS_INSTANTIATED;
    return CORE_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* FMU state snapshots.
 *
 * The in-memory FMU state and its serialised form are the same bytes: a header (magic, format
 * version, interface tag, size), the instance's data, and a 64-bit FNV-1a checksum over all of
 * it. Restoring checks the header, the checksum and then every field (ranges as for set, the
 * FMI state word against the states this interface can be saved in, mode against wall model,
 * finite and bounded states and times); a bad one is refused with a message and the instance is
 * left exactly as it was. Extending it: add the field to Snapshot (before checksum), copy it in
 * snapshot_take/snapshot_restore, check it in snapshot_check, bump SNAPSHOT_VERSION. */

#define SNAPSHOT_MAGIC 0x494d504fu /* "IMPO" */
#define SNAPSHOT_VERSION 3u /* 3: ModelData carries sensitivities, solver, J, S (issue 11) */

typedef struct {
    uint32_t magic, version, iface, size;
    int32_t state;
    int32_t inputs_changed;
    double start_time, me_time;
    ModelData m;
    double origin, tau;
    long events, guard_hits;
    int32_t pending;
    int32_t reserved;
    uint64_t checksum; /* over every byte before it */
} Snapshot;

static uint64_t fnv1a(const void *p, size_t n) {
    const unsigned char *b = (const unsigned char *)p;
    uint64_t h = 1469598103934665603ull;
    for (size_t i = 0; i < n; ++i) {
        h ^= b[i];
        h *= 1099511628211ull;
    }
    return h;
}

static uint64_t snapshot_sum(const Snapshot *s) { return fnv1a(s, offsetof(Snapshot, checksum)); }

static void snapshot_take(CoreInstance *c, Snapshot *s) {
    memset(s, 0, sizeof *s);
    s->magic = SNAPSHOT_MAGIC;
    s->version = SNAPSHOT_VERSION;
    s->iface = (uint32_t)c->iface;
    s->size = (uint32_t)sizeof *s;
    s->state = c->state;
    s->inputs_changed = c->inputs_changed;
    s->start_time = c->start_time;
    s->me_time = c->me_time;
    memcpy(&s->m, &c->m, sizeof s->m);
    s->origin = c->s.origin;
    s->tau = c->s.tau;
    s->events = c->s.events;
    s->guard_hits = c->s.guard_hits;
    s->pending = c->s.pending;
    s->checksum = snapshot_sum(s);
    /* CVODE's step history is not part of the snapshot; restarting the live instance here too
     * makes "continue" and "restore, then continue" follow the very same computation. */
    c->s.needs_reinit = 1;
}

static int finite_within(double x, double bound) { return isfinite(x) && fabs(x) <= bound; }

/* NULL if the snapshot may be restored into c, else why not (in buf). */
static const char *snapshot_check(const CoreInstance *c, const Snapshot *s, char *buf,
                                  size_t n) {
    if (s->magic != SNAPSHOT_MAGIC) return "not a state of this FMU (bad magic word)";
    if (s->version != SNAPSHOT_VERSION || s->size != sizeof *s) {
        snprintf(buf, n, "state format version %u, size %u: this FMU reads version %u, size %zu",
                 (unsigned)s->version, (unsigned)s->size, SNAPSHOT_VERSION, sizeof *s);
        return buf;
    }
    if (s->checksum != snapshot_sum(s)) return "checksum mismatch (the state is corrupted)";
    static const char *const IF_NAMES[] = {"?", "FMI 2.0 Co-Simulation",
                                           "FMI 2.0 Model Exchange", "FMI 3.0 Co-Simulation",
                                           "FMI 3.0 Model Exchange"};
    if (s->iface != (uint32_t)c->iface) {
        snprintf(buf, n, "a state of an %s instance cannot be set into an %s instance",
                 s->iface <= 4 ? IF_NAMES[s->iface] : "unknown", IF_NAMES[c->iface]);
        return buf;
    }
    int savable = CS_INSTANTIATED | CS_INIT | CS_TERMINATED;
    if (!c->fmi3) savable |= CS_ERROR; /* fmi2GetFMUstate is allowed in Error */
    savable |= c->is_me ? (CS_EVENT | CS_CONT) : CS_STEP;
    if (!c->is_me && c->event_mode_used) savable |= CS_EVENT;
    const int st = s->state;
    if (!(st & savable) || (st & (st - 1))) {
        snprintf(buf, n, "FMI state word %d is not a state this instance can be restored to", st);
        return buf;
    }
    for (size_t i = 0; i < N_VARS; ++i) {
        const VarDef *d = &VARS[i];
        if (!settable(d)) continue;
        const char *why = check_value(d, field_get(&s->m, d), buf, n);
        if (why) {
            char tmp[200];
            snprintf(tmp, sizeof tmp, "field %s %s", d->name, why);
            snprintf(buf, n, "%s", tmp);
            return buf;
        }
    }
    const ModelData *m = &s->m;
    ModelData trial;
    memcpy(&trial, m, sizeof trial);
    model_update_derived(&trial);
    if (check_derived(&trial, buf, n)) return buf;
    if (m->mode < MODE_FREE || m->mode > MODE_STICK ||
        (m->mode == MODE_CONTACT && m->wall != WALL_COMPLIANT) ||
        (m->mode == MODE_STICK && m->wall != WALL_RIGID))
        return "contact mode inconsistent with the wall model";
    if (m->impacts < 0 || s->events < 0 || s->guard_hits < 0) return "negative event counter";
    if (!finite_within(m->u, CORE_MAX_STATE) || !finite_within(m->v, CORE_MAX_STATE))
        return "continuous state (u, v) not finite or beyond 1e15";
    for (int i = 0; i < 6; ++i)
        if (!isfinite(i < 4 ? m->sJ[i / 2][i % 2] : m->sS[i - 4]))
            return "sensitivities (J_uu ... S_v) not finite";
    if (!finite_within(m->dF_ext, MAX_DF_EXT) || !finite_within(m->du_wall, MAX_DU_WALL) ||
        !finite_within(m->in_tau, 2 * CORE_MAX_TIME) || !isfinite(m->v_impact) ||
        !finite_within(m->t_impact, 2 * CORE_MAX_TIME))
        return "input derivatives or impact record not finite or out of range";
    if (m->dF_ext != 0.0 || m->du_wall != 0.0) {
        /* Ramps: only Co-Simulation takes input derivatives, and the inputs they give at the
         * state's own time must lie in the inputs' ranges, as a value set there would (each
         * field within its bound still allows a slope of 1e6 from a reference time 2e9 away) */
        if (c->is_me) return "input derivatives in a Model Exchange state";
        const unsigned vrs[2] = {VR_F_EXT, VR_U_WALL};
        for (int i = 0; i < 2; ++i) {
            const VarDef *d = find_var(c, vrs[i]);
            const double x = i == 0 ? model_external_force(m, s->tau) : model_wall_position(m, s->tau);
            const char *why = check_value(d, x, buf, n);
            if (why) {
                char tmp[200];
                snprintf(tmp, sizeof tmp, "ramped input %s = %g at the state's time %s", d->name, x, why);
                snprintf(buf, n, "%s", tmp);
                return buf;
            }
        }
    }
    if (!finite_within(s->start_time, CORE_MAX_TIME) ||
        !finite_within(s->me_time, 2 * CORE_MAX_TIME))
        return "start or Model Exchange time not finite or beyond 1e9";
    if (!finite_within(s->origin, 2 * CORE_MAX_TIME) || s->origin != floor(s->origin) ||
        !(s->tau >= 0.0) || !finite_within(s->tau, 2 * CORE_MAX_TIME))
        return "solver time (origin, local time) not finite, out of range or not integral";
    /* the model's time origin follows the solver's while a Co-Simulation runs (model.h) */
    if (!c->is_me && (st & (CS_STEP | CS_EVENT | CS_TERMINATED)) && m->origin != s->origin)
        return "the model's and the solver's time origins differ";
    if (s->pending != 0 && (s->pending != 1 || c->is_me)) return "bad pending-event flag";
    if (s->inputs_changed != 0 && s->inputs_changed != 1) return "bad input flag";
    return NULL;
}

static void snapshot_restore(CoreInstance *c, const Snapshot *s) {
    c->state = s->state;
    c->inputs_changed = s->inputs_changed;
    c->start_time = s->start_time;
    c->me_time = s->me_time;
    memcpy(&c->m, &s->m, sizeof c->m);
    model_update_derived(&c->m); /* recomputed, never trusted */
    c->s.origin = s->origin;
    c->s.tau = s->tau;
    c->s.events = s->events;
    c->s.guard_hits = s->guard_hits;
    c->s.pending = s->pending;
    c->s.needs_reinit = 1;
}


int core_get_state(CoreInstance *c, const char *fn, void **state) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (!state) return core_fail(c, fn, "NULL argument");
    Snapshot *s = *state ? (Snapshot *)*state : core_alloc(c, sizeof(Snapshot));
    if (!s) return core_fail(c, fn, "out of memory");
    snapshot_take(c, s);
    *state = s;
    return CORE_OK;
}

int core_set_state(CoreInstance *c, const char *fn, const void *state) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (!state) return core_fail(c, fn, "NULL state");
    char buf[300];
    const char *why = snapshot_check(c, (const Snapshot *)state, buf, sizeof buf);
    if (why) return core_fail(c, fn, "state refused, instance unchanged: %s", why);
    snapshot_restore(c, (const Snapshot *)state);
    return CORE_OK;
}

int core_free_state(CoreInstance *c, const char *fn, void **state) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (state && *state) {
        core_release(c, *state);
        *state = NULL;
    }
    return CORE_OK;
}

int core_serialized_size(CoreInstance *c, const char *fn, const void *state, size_t *size) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (!size || !state || ((const Snapshot *)state)->magic != SNAPSHOT_MAGIC)
        return core_fail(c, fn, "not a state of this FMU");
    *size = sizeof(Snapshot);
    return CORE_OK;
}

int core_serialize(CoreInstance *c, const char *fn, const void *state, unsigned char *bytes,
                   size_t size) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (!bytes || size < sizeof(Snapshot) || !state ||
        ((const Snapshot *)state)->magic != SNAPSHOT_MAGIC)
        return core_fail(c, fn, "bad state or buffer too small");
    memcpy(bytes, state, sizeof(Snapshot));
    return CORE_OK;
}

int core_deserialize(CoreInstance *c, const char *fn, const unsigned char *bytes, size_t size,
                     void **state) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (!bytes || !state || size != sizeof(Snapshot))
        return core_fail(c, fn, "%zu bytes are not a serialised state of this FMU (expected "
                         "%zu)", size, sizeof(Snapshot));
    Snapshot tmp;
    memcpy(&tmp, bytes, sizeof tmp);
    char buf[300];
    const char *why = snapshot_check(c, &tmp, buf, sizeof buf);
    if (why) return core_fail(c, fn, "not a valid serialised state of this instance: %s", why);
    Snapshot *s = *state ? (Snapshot *)*state : core_alloc(c, sizeof(Snapshot));
    if (!s) return core_fail(c, fn, "out of memory");
    memcpy(s, &tmp, sizeof tmp);
    *state = s;
    return CORE_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* Co-Simulation */

/* Applies the documented rule for inputs that jumped since the last step (model.c,
 * model_input_jump) at the current point. */
static void apply_input_jump(CoreInstance *c) {
    if (!c->inputs_changed) return;
    c->inputs_changed = 0;
    solver_apply_pending(&c->s, &c->m);
    double y[2] = {c->m.u, c->m.v};
    const int impacts = c->m.impacts;
    if (model_input_jump(&c->m, local_tau(c), y)) {
        c->m.u = y[0];
        c->m.v = y[1];
        core_log(c, CORE_OK, "logEvents", "inputs changed at t = %.17g: state set to u = %.17g,"
                 " v = %.17g%s", core_time(c), y[0], y[1],
                 c->m.impacts != impacts ? " (an impact with the moved wall)" : "");
    }
    c->s.needs_reinit = 1;
}

/* After a step: the ramps of the input derivatives end here (the inputs hold their values at
 * the end of the step until set again). */
static void end_ramps(CoreInstance *c) {
    if (c->m.dF_ext == 0.0 && c->m.du_wall == 0.0) return;
    rebase_inputs(&c->m, c->s.tau);
    c->m.dF_ext = c->m.du_wall = 0.0;
    c->s.needs_reinit = 1;
}

static int outputs_finite(const CoreInstance *c) {
    return finite_within(c->m.u, CORE_MAX_STATE) && finite_within(c->m.v, CORE_MAX_STATE) &&
           isfinite(get_contact_force(c)) && isfinite(c->m.v_impact);
}

int core_do_step(CoreInstance *c, const char *fn, double t, double h, int stop_at_event,
                 CoreIntermediateFn intermediate, int *event_needed, int *early_return,
                 double *last_time) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (c->is_me) return core_fail(c, fn, "a Model Exchange instance");
    if (event_needed) *event_needed = 0;
    if (early_return) *early_return = 0;
    /* both standards: communicationStepSize > 0 (h = 0 and h = -0.0 are refused) */
    if (!isfinite(t) || !isfinite(h) || !(h > 0.0))
        return core_fail(c, fn, "bad communication step (t = %g, h = %g): h must be finite and "
                         "> 0", t, h);
    if (!(fabs(t + h) <= CORE_MAX_TIME))
        return core_fail(c, fn, "the step's end t + h = %g is beyond the FMU's time range "
                         "|t| <= %g", t + h, CORE_MAX_TIME);
    const double now = solver_time(&c->s);
    if (fabs(t - now) > 1e-9 * fmax(1.0, fabs(now)))
        return core_fail(c, fn, "currentCommunicationPoint %.17g differs from the FMU's time "
                         "%.17g", t, now);
    apply_input_jump(c);
    if (c->m.sensitivities) { /* derivatives w.r.t. the state at t */
        sens_reset(&c->m);
        c->s.needs_reinit = 1; /* CVODE carries J, S in its own history: restart it with J = I */
    }
    const double t_end = t + h;
    const long events_before = c->s.events, guard_before = c->s.guard_hits;

    if (!stop_at_event && !intermediate) {
        if (solver_advance(&c->s, &c->m, t_end) != 0) {
            return core_fail(c, fn, "integration failed: %s", c->s.msg);
        }
    } else {
        for (;;) {
            const int rc = solver_advance_ex(&c->s, &c->m, t_end, 1);
            if (rc < 0) {
                return core_fail(c, fn, "integration failed: %s", c->s.msg);
            }
            if (rc == 0) break; /* reached t_end */
            const double te = solver_time(&c->s);
            int requested = 0;
            if (intermediate) {
                /* FMI 3.0 Intermediate Update Mode: the table allows no call in it (no variable is
                 * declared intermediateUpdate); a refused call leaves the instance in Terminated
                 * and this doStep fails with it. */
                c->state = CS_INTERMEDIATE;
                requested = intermediate(c, te);
                if (c->state != CS_INTERMEDIATE)
                    return core_fail(c, fn, "a call inside intermediateUpdate at t = %.17g failed "
                                     "(see above): the step is abandoned", te);
                c->state = CS_STEP;
            }
            if (stop_at_event || (c->early_return_allowed && requested)) {
                /* With event mode the jump waits for the discrete-state update; without, it is
                 * applied here (outputs after the event). */
                if (c->event_mode_used) {
                    if (event_needed) *event_needed = 1;
                } else {
                    solver_apply_pending(&c->s, &c->m);
                }
                if (early_return) *early_return = te < t_end;
                core_log(c, CORE_OK, "logEvents", "%s: early return at the wall event t = %.17g",
                         fn, te);
                break;
            }
            solver_apply_pending(&c->s, &c->m);
        }
    }
    end_ramps(c);
    if (last_time) *last_time = solver_time(&c->s);
    if (!outputs_finite(c)) {
        return core_fail(c, fn, "the state left the valid range (u = %g, v = %g at t = %.17g)",
                         c->m.u, c->m.v, solver_time(&c->s));
    }
    if (c->s.events != events_before)
        core_log(c, CORE_OK, "logEvents", "%s: %ld wall events in (%.17g, %.17g], %ld of them "
                 "recovered by the rescue of a stepped-over crossing", fn, c->s.events - events_before, t,
                 solver_time(&c->s), c->s.guard_hits - guard_before);
    return CORE_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* Model Exchange, and the event mode of FMI 3.0 Co-Simulation */

#define ME_ONLY(c, fn)                                                                        \
    do {                                                                                      \
        if (!core_allowed(c, fn)) return CORE_ERROR;                                  \
        if (!(c)->is_me) return core_fail(c, fn, "instance was not instantiated for Model "   \
                                          "Exchange");                                        \
    } while (0)

int core_enter_event_mode(CoreInstance *c, const char *fn) {
    if (!core_allowed(c, fn)) return CORE_ERROR; /* NULL instance first, then the table */
    c->state = CS_EVENT;
    return CORE_OK;
}

int core_update_discrete(CoreInstance *c, const char *fn, int *values_changed) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    int changed;
    const int impacts = c->m.impacts;
    if (c->is_me) {
        double y[2] = {c->m.u, c->m.v};
        c->m.origin = floor(c->me_time);
        /* An input that jumped since the last update (u_wall, F_ext) gets the rule Co-Simulation
         * applies (model_input_jump, README "Inputs that jump"): a compliant wall stepping past
         * the mass switches the contact mode and leaves the mass where it is. Only then is a
         * remaining wall crossing an event. */
        changed = c->inputs_changed ? model_input_jump(&c->m, local_tau(c), y) : 0;
        c->inputs_changed = 0;
        changed |= model_me_event_update(&c->m, local_tau(c), y);
        c->m.u = y[0];
        c->m.v = y[1];
        if (changed) c->s.events++;
    } else {
        changed = solver_apply_pending(&c->s, &c->m); /* the jump of an early return */
    }
    if (changed)
        core_log(c, CORE_OK, "logEvents", "%s: wall event at t = %.17g%s", fn, core_time(c),
                 c->m.impacts != impacts ? " (impact)" : "");
    if (values_changed) *values_changed = changed;
    return CORE_OK;
}

int core_enter_continuous_mode(CoreInstance *c, const char *fn) {
    ME_ONLY(c, fn);
    c->state = CS_CONT;
    return CORE_OK;
}

int core_enter_step_mode(CoreInstance *c, const char *fn) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (c->is_me) return core_fail(c, fn, "a Model Exchange instance");
    solver_apply_pending(&c->s, &c->m); /* an importer that skipped the discrete update */
    c->state = CS_STEP;
    return CORE_OK;
}

int core_completed_step(CoreInstance *c, const char *fn, int *enter_event, int *terminate) {
    ME_ONLY(c, fn);
    if (enter_event) *enter_event = 0;
    if (terminate) *terminate = 0;
    return CORE_OK;
}

int core_set_time(CoreInstance *c, const char *fn, double t) {
    ME_ONLY(c, fn);
    if (!finite_within(t, CORE_MAX_TIME))
        return core_fail(c, fn, "time = %g: must be finite with |t| <= %g", t, CORE_MAX_TIME);
    c->me_time = t;
    c->m.origin = floor(t);
    return CORE_OK;
}

int core_set_states(CoreInstance *c, const char *fn, const double x[], size_t n) {
    ME_ONLY(c, fn);
    if (n != 2 || !x) return core_fail(c, fn, "expected 2 states, got %zu", n);
    if (!finite_within(x[0], CORE_MAX_STATE) || !finite_within(x[1], CORE_MAX_STATE))
        return core_fail(c, fn, "states (%g, %g) rejected: must be finite with |x| <= %g (state "
                         "kept)", x[0], x[1], CORE_MAX_STATE);
    c->m.u = x[0];
    c->m.v = x[1];
    return CORE_OK;
}


int core_get_states(CoreInstance *c, const char *fn, double x[], size_t n) {
    ME_ONLY(c, fn);
    if (n != 2 || !x) return core_fail(c, fn, "expected 2 states, got %zu", n);
    x[0] = c->m.u;
    x[1] = c->m.v;
    return CORE_OK;
}

int core_get_derivatives(CoreInstance *c, const char *fn, double dx[], size_t n) {
    ME_ONLY(c, fn);
    if (n != 2 || !dx) return core_fail(c, fn, "expected 2 states, got %zu", n);
    const double y[2] = {c->m.u, c->m.v};
    model_derivatives(&c->m, local_tau(c), y, dx);
    if (!isfinite(dx[0]) || !isfinite(dx[1]))
        return core_fail(c, fn, "derivatives not finite at u = %g, v = %g", y[0], y[1]);
    return CORE_OK;
}

int core_get_event_indicators(CoreInstance *c, const char *fn, double g[], size_t n) {
    ME_ONLY(c, fn);
    if (n != MODEL_N_ME_EVENTS || !g)
        return core_fail(c, fn, "expected %d indicators, got %zu", MODEL_N_ME_EVENTS, n);
    g[0] = get_indicator(c);
    return CORE_OK;
}

int core_get_nominals(CoreInstance *c, const char *fn, double x[], size_t n) {
    ME_ONLY(c, fn);
    if (n != 2 || !x) return core_fail(c, fn, "expected 2 states, got %zu", n);
    x[0] = x[1] = 1.0;
    return CORE_OK;
}
