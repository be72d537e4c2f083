/*
 * The closed-form solver (parameter solver = 1): the linear contact law makes the ODE linear on
 * each side of the wall, so between wall events the state is the exact solution
 *     y(tau) = q(tau) + P(tau - tau_a) (y_a - q(tau_a))
 * (q the particular solution of the mode, P its propagator, docs/theory.md section 2), and the wall
 * crossings are found by a certified search that cannot step over a contact, however shallow
 * (see closed_form.c). Same events, jumps, counters and sensitivities as the CVODE stepper.
 *
 * One implementation of the stepper interface (stepper.h): stepper.c chooses STEPPER_CLOSED_FORM
 * for solver = 1 and the FMI core calls it only through that interface; it works on the
 * stepper's clock alone and uses no CVODE memory. bench/cf_driver.c calls it the same way.
 */
#ifndef IMPACT_CLOSED_FORM_H
#define IMPACT_CLOSED_FORM_H

#include "model.h"
#include "stepper.h"

/* Why the closed form cannot run this model (NULL: it can): it needs the linear contact law.
 * Its advance_to refuses such a model with this message. */
const char *closed_form_unsupported(const ModelData *m);

extern const StepperOps STEPPER_CLOSED_FORM;

#endif
