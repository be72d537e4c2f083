/*
 * The stepper interface (stepper.h): the calls the FMI core makes, and the clock's operations the
 * methods share (solver_cvode.c, closed_form.c). The table of methods is stepper_methods.c.
 */
#include "stepper.h"

#include <math.h>
#include <stdio.h>

#include "sens.h"

void stepper_free(Stepper *st) {
    if (st->ops) st->ops->free(st);
    st->ops = NULL;
    st->impl = NULL;
}

void stepper_start(Stepper *st, double t) {
    if (st->ops) st->ops->start(st, t);
    else clock_start(&st->clk, t);
}

int stepper_advance_to(Stepper *st, ModelData *m, double t_end, int stop_at_event) {
    if (!st->ops) {
        snprintf(st->clk.msg, sizeof st->clk.msg, "no integration method");
        return -1;
    }
    return st->ops->advance_to(st, m, t_end, stop_at_event);
}

int stepper_apply_pending(Stepper *st, ModelData *m) {
    return st->ops ? st->ops->apply_pending(st, m) : clock_apply_pending(&st->clk, m);
}

double stepper_time(const Stepper *st) { return st->clk.origin + st->clk.tau; }

/* ------------------------------------------------------------------------------------------ */

void clock_start(StepClock *k, double t) {
    k->origin = floor(t);
    k->tau = t - k->origin;
    k->restart = 1;
    k->pending = 0;
    k->continuing = 0;
}

double clock_reorigin(StepClock *k, ModelData *m) {
    const double shift = floor(k->tau);
    k->origin += shift;
    k->tau -= shift;
    model_shift_time(m, shift); /* the model's input ramps and impact times follow the origin */
    return shift;
}

int clock_apply_pending(StepClock *k, ModelData *m) {
    if (!k->pending) return 0;
    double y[2] = {m->u, m->v};
    sens_event_update(m, k->tau, y);
    m->u = y[0];
    m->v = y[1];
    k->events++;
    k->pending = 0;
    k->restart = 1;
    return 1;
}

void clock_begin_budget(StepClock *k, const ModelData *m, double t_end, double cap) {
    const double per = fmax(1.0, t_end - (k->origin + k->tau));
    k->budget_end = t_end;
    k->steps_bound = fmin(cap, m->max_steps_per_time * per);
    k->events_bound = fmin(cap, m->max_events_per_time * per);
    k->steps_used = k->events_used = 0.0;
}

int clock_over_budget(StepClock *k, const ModelData *m, int events, double cap, const char *unit,
                      double t_local) {
    if (events ? k->events_used <= k->events_bound : k->steps_used <= k->steps_bound) return 0;
    const double bound = events ? k->events_bound : k->steps_bound;
    const char *what = events ? "wall events" : unit;
    if (bound >= cap)
        snprintf(k->msg, sizeof k->msg,
                 "more than %.0f %s in this doStep (before t = %.17g): the cap of %.0f per doStep "
                 "(split the step)", bound, what, k->origin + t_local, cap);
    else
        snprintf(k->msg, sizeof k->msg,
                 "more than %.0f %s in this doStep (before t = %.17g): the limit %s = %g per unit "
                 "time%s", bound, what, k->origin + t_local,
                 events ? "max_events_per_time" : "max_steps_per_time",
                 events ? m->max_events_per_time : m->max_steps_per_time,
                 events ? " (chatter that does not end?)" : " (a stiff or extreme parameter?)");
    return 1;
}
