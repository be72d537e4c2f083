/*
 * CVODE stepper (solver_cvode.c): integrates the model of model.h between communication points,
 * locating every wall crossing with CVODE's root finding and applying the model's jumps at the
 * located times. One implementation of the stepper interface (stepper.h), chosen by stepper.c
 * for solver = 0; the FMI core reaches it only through that interface.
 *
 * CVODE runs in one-step mode on its own step sequence, which does not depend on the
 * communication points: it steps past a communication point and the state there is read from
 * CVODE's interpolant. The only stop times are the model's own (wall events, and an integer
 * re-origin time), so the result does not depend on how the importer computes its time grid.
 *
 * Work: an advance is bounded by m->max_steps_per_time and m->max_events_per_time (per unit of
 * time, at least one unit) and by SOLVER_MAX_STEPS_PER_CALL; exceeding a bound is an error whose
 * message names it.
 */
#ifndef IMPACT_SOLVER_H
#define IMPACT_SOLVER_H

#include "stepper.h"

/* Hard cap on the CVODE steps of one doStep, whatever max_steps_per_time says (a few seconds
 * of work): no call runs for minutes. */
#define SOLVER_MAX_STEPS_PER_CALL 2e6

extern const StepperOps STEPPER_CVODE;

#endif
