/*
 * The FMI core's instance (fmu_core.h): its life cycle (core_instantiate, core_setup,
 * core_enter_init, core_exit_init, core_terminate, core_reset, core_free), logging, and
 * core_allowed, the state check every entry point makes first (the table itself is
 * fmu_states.c). Called by the glue (fmi2.c, fmi3.c); the other concerns are fmu_vars.c,
 * fmu_snapshot.c, fmu_cs.c and fmu_me.c.
 */
#include "fmu_core.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------ */
/* Logging and the state check */

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

int core_error_state(const CoreInstance *c) { return c->fmi3 ? ST_TERMINATED : ST_ERROR; }

static void take_start_state(CoreInstance *v);

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
     * in Terminated (fmi3SetFMUState, fmi3Reset, fmi3FreeInstance). Failing in Initialization
     * Mode, the getters go on answering what they answered there (core_view): that state is
     * made the instance's own. */
    if (c->state == ST_INIT) take_start_state(c);
    c->state = core_error_state(c);
    return CORE_ERROR;
}

int core_allowed(CoreInstance *c, const char *fn) {
    if (!c) return 0;
    char why[400];
    if (core_state_allows(c->iface, c->event_mode_used, c->state, fn, why, sizeof why)) return 1;
    core_fail(c, fn ? fn : "?", "%s", why);
    return 0;
}

/* The state the start values give at the start time, in v itself (its clock and model). */
static void take_start_state(CoreInstance *v) {
    const double origin = floor(v->start_time), tau = v->start_time - origin;
    v->st.clk.origin = v->m.origin = origin;
    v->st.clk.tau = v->m.in_tau = tau;
    v->me_time = v->start_time;
    model_update_derived(&v->m);
    model_initialize_state(&v->m, tau);
}

const CoreInstance *core_view(const CoreInstance *c, CoreInstance *buf) {
    if (c->state != ST_INIT) return c;
    memcpy(buf, c, sizeof *buf);
    take_start_state(buf);
    return buf;
}

double core_local_tau(const CoreInstance *c) {
    return c->is_me ? c->me_time - floor(c->me_time) : c->st.clk.tau;
}

double core_time(const CoreInstance *c) { return c->is_me ? c->me_time : stepper_time(&c->st); }

int core_select_stepper(CoreInstance *c, const char *fn) {
    if (stepper_select(&c->st, &c->m) != 0) return core_fail(c, fn, "%s", c->st.clk.msg);
    return CORE_OK;
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
    c->tunable_states = c->fmi3 ? (ST_STEP | ST_EVENT) : (c->is_me ? ST_EVENT : ST_STEP);
    c->name = calloc_fn ? calloc_fn(1, strlen(name) + 1) : calloc(1, strlen(name) + 1);
    if (c->name) strcpy(c->name, name);
    model_set_defaults(&c->m);
    if (stepper_select(&c->st, &c->m) != 0) {
        if (log) log(env, name, CORE_ERROR, "logStatusError", c->st.clk.msg);
        core_free(c);
        return NULL;
    }
    c->state = ST_INSTANTIATED;
    return c;
}

void core_release(CoreInstance *c, void *p) {
    if (!p) return;
    if (c->free_fn) c->free_fn(p);
    else free(p);
}

void *core_alloc(CoreInstance *c, size_t n) {
    return c->calloc_fn ? c->calloc_fn(1, n) : calloc(1, n);
}

void core_free(CoreInstance *c) {
    if (!c) return;
    stepper_free(&c->st);
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
    c->state = ST_INIT;
    return CORE_OK;
}

int core_exit_init(CoreInstance *c, const char *fn) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    char buf[300];
    model_update_derived(&c->m);
    const char *why = model_check_consistency(&c->m, buf, sizeof buf);
    if (!why) why = model_check_derived(&c->m, buf, sizeof buf);
    if (why) return core_fail(c, fn, "%s", why);
    if (core_select_stepper(c, fn) != CORE_OK) return CORE_ERROR;
    stepper_start(&c->st, c->start_time);
    c->m.origin = c->st.clk.origin;
    c->m.in_tau = c->st.clk.tau;
    model_initialize_state(&c->m, c->st.clk.tau);
    c->st.clk.events = c->st.clk.guard_hits = 0;
    c->st.clk.pending = 0;
    c->inputs_changed = 0;
    c->me_time = c->start_time;
    c->me_wall = model_wall_position(&c->m, c->st.clk.tau);
    c->state = (c->is_me || c->event_mode_used) ? ST_EVENT : ST_STEP;
    return CORE_OK;
}

int core_terminate(CoreInstance *c, const char *fn) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    c->state = ST_TERMINATED;
    return CORE_OK;
}

int core_reset(CoreInstance *c, const char *fn) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    /* The stepper's memory is kept: the next run re-initialises it instead of reallocating (or
     * replaces it, if the next run's solver differs). */
    model_set_defaults(&c->m);
    c->start_time = 0.0;
    c->me_time = 0.0;
    stepper_start(&c->st, 0.0); /* time 0, origin 0 = the model's; a restart, nothing pending */
    c->inputs_changed = 0;
    c->state = ST_INSTANTIATED;
    return CORE_OK;
}
