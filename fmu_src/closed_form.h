/*
 * The closed-form solver (parameter solver = 1): the linear contact law makes the ODE linear on
 * each side of the wall, so between wall events the state is the exact solution
 *     y(tau) = q(tau) + P(tau - tau_a) (y_a - q(tau_a))
 * (q the particular solution of the mode, P its propagator, docs/theory.md section 2), and the wall
 * crossings are found by a certified search that cannot step over a contact, however shallow
 * (see closed_form.c). Same events, jumps, counters and sensitivities as the CVODE driver; the
 * FMI glue calls closed_form_advance where it would call solver_advance_ex.
 */
#ifndef IMPACT_CLOSED_FORM_H
#define IMPACT_CLOSED_FORM_H

#include "model.h"
#include "solver.h"

/* Why the closed form cannot run this model (NULL: it can): it needs the linear contact law. */
const char *closed_form_unsupported(const ModelData *m);

/* As solver_advance_ex (solver.h): advances s (origin, tau, events, pending, msg) and m to
 * absolute time t_end; with stop_at_event it stops at the first wall event and returns 1 with
 * the jump pending. Returns 0, or -1 with s->msg set. Uses no CVODE memory. */
int closed_form_advance(Solver *s, ModelData *m, double t_end, int stop_at_event);

#endif
