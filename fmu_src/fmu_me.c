/*
 * Model Exchange, and the event mode of FMI 3.0 Co-Simulation: core_enter_event_mode,
 * core_update_discrete, core_enter_continuous_mode, core_enter_step_mode, core_set_time,
 * core_set_states, core_get_states, core_get_derivatives, core_get_event_indicators,
 * core_get_nominals, core_completed_step (fmu_core.h), called by the glue (fmi2.c, fmi3.c).
 * In Model Exchange the importer integrates; the model gives derivatives, the event indicator
 * and the jumps (model.h). In Co-Simulation event mode the jump is the stepper's pending one.
 */
#include <math.h>

#include "fmu_core.h"

static int finite_within(double x, double bound) { return isfinite(x) && fabs(x) <= bound; }

#define ME_ONLY(c, fn)                                                                        \
    do {                                                                                      \
        if (!core_allowed(c, fn)) return CORE_ERROR;                                  \
        if (!(c)->is_me) return core_fail(c, fn, "instance was not instantiated for Model "   \
                                          "Exchange");                                        \
    } while (0)

int core_enter_event_mode(CoreInstance *c, const char *fn) {
    if (!core_allowed(c, fn)) return CORE_ERROR; /* NULL instance first, then the table */
    c->state = ST_EVENT;
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
        /* An input that jumped in Event Mode makes the right-hand side jump too, whether or not the
         * rule moves the state: reported as valuesOfContinuousStatesChanged, the one flag on which
         * an importer such as fmusim re-initialises its integrator (FMPy does at every event);
         * they read back the same state. */
        changed = c->inputs_changed ? (model_input_jump(&c->m, core_local_tau(c), y), 1) : 0;
        c->inputs_changed = 0;
        const int mode = c->m.mode;
        const double tau = core_local_tau(c), w = model_wall_position(&c->m, tau);
        MeEventResult r = model_me_event_update(&c->m, tau, y);
        if (r == ME_EVENT_INSIDE_RIGID && fabs(w - c->me_wall) > model_me_event_tolerance(&c->m, tau))
            r = model_input_jump(&c->m, tau, y) ? ME_EVENT_JUMP : ME_EVENT_NONE; /* the wall jumped */
        c->me_wall = w;
        if (r == ME_EVENT_INSIDE_RIGID)
            return core_fail(c, fn, "state (u, v) = (%.17g, %.17g) is %g inside the rigid wall at "
                             "u_wall = %g, beyond the event tolerance %g: no contact mode holds a "
                             "mass there (locate the crossing of the event indicator)", y[0],
                             y[1], y[0] - model_wall_position(&c->m, core_local_tau(c)),
                             model_wall_position(&c->m, core_local_tau(c)),
                             model_me_event_tolerance(&c->m, core_local_tau(c)));
        if (r == ME_EVENT_KEPT)
            core_log(c, CORE_WARNING, "logStatusWarning", "%s: state (u, v) = (%.17g, %.17g) is "
                     "beyond the event tolerance %g of the wall: kept, and the instance takes the "
                     "mode it is in (%s; no jump applied)", fn, y[0], y[1],
                     model_me_event_tolerance(&c->m, core_local_tau(c)),
                     c->m.mode == MODE_FREE ? "in flight" : "in contact");
        changed |= r != ME_EVENT_NONE || c->m.mode != mode;
        c->m.u = y[0];
        c->m.v = y[1];
        if (changed) c->st.clk.events++;
    } else {
        changed = stepper_apply_pending(&c->st, &c->m); /* the jump of an early return */
    }
    if (changed)
        core_log(c, CORE_OK, "logEvents", "%s: wall event at t = %.17g%s", fn, core_time(c),
                 c->m.impacts != impacts ? " (impact)" : "");
    if (values_changed) *values_changed = changed;
    return CORE_OK;
}

int core_enter_continuous_mode(CoreInstance *c, const char *fn) {
    ME_ONLY(c, fn);
    c->state = ST_CONT;
    return CORE_OK;
}

int core_enter_step_mode(CoreInstance *c, const char *fn) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (c->is_me) return core_fail(c, fn, "a Model Exchange instance");
    stepper_apply_pending(&c->st, &c->m); /* an importer that skipped the discrete update */
    c->state = ST_STEP;
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
    if (n != MODEL_N_STATES || !x)
        return core_fail(c, fn, "expected %d states, got %zu", MODEL_N_STATES, n);
    if (!finite_within(x[0], CORE_MAX_STATE) || !finite_within(x[1], CORE_MAX_STATE))
        return core_fail(c, fn, "states (%g, %g) rejected: must be finite with |x| <= %g (state "
                         "kept)", x[0], x[1], CORE_MAX_STATE);
    model_set_states(&c->m, x);
    return CORE_OK;
}

int core_get_states(CoreInstance *c, const char *fn, double x[], size_t n) {
    ME_ONLY(c, fn);
    if (n != MODEL_N_STATES || !x)
        return core_fail(c, fn, "expected %d states, got %zu", MODEL_N_STATES, n);
    CoreInstance buf;
    model_get_states(&core_view(c, &buf)->m, x); /* Initialization Mode: from the start values */
    return CORE_OK;
}

int core_get_derivatives(CoreInstance *c, const char *fn, double dx[], size_t n) {
    ME_ONLY(c, fn);
    if (n != MODEL_N_STATES || !dx)
        return core_fail(c, fn, "expected %d states, got %zu", MODEL_N_STATES, n);
    double y[MODEL_N_STATES];
    CoreInstance buf;
    const CoreInstance *v = core_view(c, &buf);
    model_get_states(&v->m, y);
    model_derivatives(&v->m, core_local_tau(v), y, dx);
    if (!isfinite(dx[0]) || !isfinite(dx[1]))
        return core_fail(c, fn, "derivatives not finite at u = %g, v = %g", y[0], y[1]);
    return CORE_OK;
}

int core_get_event_indicators(CoreInstance *c, const char *fn, double g[], size_t n) {
    ME_ONLY(c, fn);
    if (n != MODEL_N_ME_EVENTS || !g)
        return core_fail(c, fn, "expected %d indicators, got %zu", MODEL_N_ME_EVENTS, n);
    CoreInstance buf;
    const CoreInstance *v = core_view(c, &buf);
    g[0] = model_wall_indicator(&v->m, core_local_tau(v));
    return CORE_OK;
}

int core_get_nominals(CoreInstance *c, const char *fn, double x[], size_t n) {
    ME_ONLY(c, fn);
    if (n != MODEL_N_STATES || !x)
        return core_fail(c, fn, "expected %d states, got %zu", MODEL_N_STATES, n);
    x[0] = x[1] = 1.0;
    return CORE_OK;
}
