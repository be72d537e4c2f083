/*
 * The Co-Simulation stepping loop: core_do_step (fmu_core.h), called by fmi2DoStep (fmi2.c) and
 * fmi3DoStep (fmi3.c, with early return and intermediate update). It moves the model only through
 * the stepper (stepper.h) and asks the model about inputs that jumped, ramps and outputs.
 */
#include <math.h>

#include "fmu_core.h"
#include "sens.h"

/* Applies the documented rule for inputs that jumped since the last step (model.c,
 * model_input_jump) at the current point. */
static void apply_input_jump(CoreInstance *c) {
    if (!c->inputs_changed) return;
    c->inputs_changed = 0;
    stepper_apply_pending(&c->st, &c->m);
    double y[2] = {c->m.u, c->m.v};
    const int impacts = c->m.impacts;
    if (model_input_jump(&c->m, core_local_tau(c), y)) {
        c->m.u = y[0];
        c->m.v = y[1];
        core_log(c, CORE_OK, "logEvents", "inputs changed at t = %.17g: state set to u = %.17g,"
                 " v = %.17g%s", core_time(c), y[0], y[1],
                 c->m.impacts != impacts ? " (an impact with the moved wall)" : "");
    }
    c->st.clk.restart = 1;
}

/* After a step: the ramps of the input derivatives end here (the inputs hold their values at
 * the end of the step until set again). */
static void end_ramps(CoreInstance *c) {
    if (model_end_ramps(&c->m, c->st.clk.tau)) c->st.clk.restart = 1;
}

static int outputs_finite(const CoreInstance *c) {
    return model_outputs_finite(&c->m, core_local_tau(c), c->inputs_changed && !c->is_me,
                                CORE_MAX_STATE);
}

/* The step [t, t + h] is one the FMU can take now: CORE_OK, or the error of fn. */
static int check_step(CoreInstance *c, const char *fn, double t, double h) {
    /* both standards: communicationStepSize > 0 (h = 0 and h = -0.0 are refused) */
    if (!isfinite(t) || !isfinite(h) || !(h > 0.0))
        return core_fail(c, fn, "bad communication step (t = %g, h = %g): h must be finite and "
                         "> 0", t, h);
    if (!(fabs(t + h) <= CORE_MAX_TIME))
        return core_fail(c, fn, "the step's end t + h = %g is beyond the FMU's time range "
                         "|t| <= %g", t + h, CORE_MAX_TIME);
    const double now = stepper_time(&c->st);
    if (fabs(t - now) > 1e-9 * fmax(1.0, fabs(now)))
        return core_fail(c, fn, "currentCommunicationPoint %.17g differs from the FMU's time "
                         "%.17g", t, now);
    return CORE_OK;
}

/* Advances to t_end stopping at every wall event: the importer's intermediateUpdate (if any) is
 * called there, and the step returns early at the first event with stop_at_event, or where the
 * callback asks for it (earlyReturnAllowed); else the jump is applied and the step goes on. */
static int advance_by_events(CoreInstance *c, const char *fn, double t_end, int stop_at_event,
                             CoreIntermediateFn intermediate, int *event_needed,
                             int *early_return) {
    for (;;) {
        const int rc = stepper_advance_to(&c->st, &c->m, t_end, 1);
        if (rc < 0) {
            return core_fail(c, fn, "integration failed: %s", c->st.clk.msg);
        }
        if (rc == 0) return CORE_OK; /* reached t_end */
        const double te = stepper_time(&c->st);
        int requested = 0;
        if (intermediate) {
            /* FMI 3.0 Intermediate Update Mode: the table allows no call in it (no variable is
             * declared intermediateUpdate); a refused call leaves the instance in Terminated
             * and this doStep fails with it. */
            c->state = ST_INTERMEDIATE;
            requested = intermediate(c, te);
            if (c->state != ST_INTERMEDIATE)
                return core_fail(c, fn, "a call inside intermediateUpdate at t = %.17g failed "
                                 "(see above): the step is abandoned", te);
            c->state = ST_STEP;
        }
        if (stop_at_event || (c->early_return_allowed && requested)) {
            /* With event mode the jump waits for the discrete-state update; without, it is
             * applied here (outputs after the event). */
            if (c->event_mode_used) {
                if (event_needed) *event_needed = 1;
            } else {
                stepper_apply_pending(&c->st, &c->m);
            }
            if (early_return) *early_return = te < t_end;
            core_log(c, CORE_OK, "logEvents", "%s: early return at the wall event t = %.17g",
                     fn, te);
            return CORE_OK;
        }
        stepper_apply_pending(&c->st, &c->m);
    }
}

int core_do_step(CoreInstance *c, const char *fn, double t, double h, int stop_at_event,
                 CoreIntermediateFn intermediate, int *event_needed, int *early_return,
                 double *last_time) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (c->is_me) return core_fail(c, fn, "a Model Exchange instance");
    if (event_needed) *event_needed = 0;
    if (early_return) *early_return = 0;
    if (check_step(c, fn, t, h) != CORE_OK) return CORE_ERROR;
    apply_input_jump(c);
    /* a wall velocity without an input derivative: the wall moves linearly over the step */
    if (model_begin_wall_ramp(&c->m, c->st.clk.tau)) c->st.clk.restart = 1;
    if (c->m.sensitivities) { /* derivatives w.r.t. the state at t */
        sens_reset(&c->m);
        c->st.clk.restart = 1; /* CVODE carries J, S in its own history: restart it with J = I */
    }
    const double t_end = t + h;
    const long events_before = c->st.clk.events, guard_before = c->st.clk.guard_hits;

    if (!stop_at_event && !intermediate) {
        if (stepper_advance_to(&c->st, &c->m, t_end, 0) != 0) {
            return core_fail(c, fn, "integration failed: %s", c->st.clk.msg);
        }
    } else if (advance_by_events(c, fn, t_end, stop_at_event, intermediate, event_needed,
                                 early_return) != CORE_OK) {
        return CORE_ERROR;
    }
    end_ramps(c);
    if (last_time) *last_time = stepper_time(&c->st);
    if (!outputs_finite(c)) {
        return core_fail(c, fn, "the state left the valid range (u = %g, v = %g at t = %.17g)",
                         c->m.u, c->m.v, stepper_time(&c->st));
    }
    if (c->st.clk.events != events_before)
        core_log(c, CORE_OK, "logEvents", "%s: %ld wall events in (%.17g, %.17g], %ld of them "
                 "recovered by the rescue of a stepped-over crossing", fn,
                 c->st.clk.events - events_before, t, stepper_time(&c->st),
                 c->st.clk.guard_hits - guard_before);
    return CORE_OK;
}
