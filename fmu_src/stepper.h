/*
 * The stepper interface: what the FMI core (fmu_cs.c, fmu_core.c, fmu_snapshot.c) calls to move
 * the model through time, whatever integrates it -- in the manner of scipy's OdeSolver.
 *
 * A Stepper is a clock (StepClock: the time origin and local time, the restart flag, the pending
 * jump, the event counters and the step budget of one doStep), the method's operations
 * (StepperOps: create / start / advance_to / apply_pending / free) and the method's own memory.
 * Each method is one file: solver_cvode.c (STEPPER_CVODE, solver_cvode.h) and closed_form.c
 * (STEPPER_CLOSED_FORM, closed_form.h). stepper_methods.c picks the method for the model's `solver`
 * parameter (stepper_select); stepper.c holds the calls the core makes and the clock's shared
 * operations (re-origin, budget, the jump of a pending event). A third method is a file with its
 * StepperOps and one row in stepper_methods.c's table; the core does not change.
 */
#ifndef IMPACT_STEPPER_H
#define IMPACT_STEPPER_H

#include "model.h"

/* The clock of a stepper: everything about time and work that outlives the method's memory
 * (it is part of the FMU state, fmu_snapshot.c) and that a change of method keeps. */
typedef struct {
    /* Time is origin + tau with an integer origin (see model.h). */
    double origin;
    double tau;
    /* The model changed at tau (inputs, a parameter, a snapshot, a jump): a method with a step
     * history restarts there. */
    int restart;
    /* A wall event located by advance_to(stop_at_event) whose jump is not applied yet: tau is
     * the event time and the model holds the state at the crossing, before the jump. */
    int pending;
    /* Counters since the start, for statistics and tests. */
    long events;
    long guard_hits; /* crossings stepped over and recovered by a rescue (CVODE's side check) */
    /* Work budget of one doStep (a chain of early returns towards the same end shares it). */
    int continuing;
    double budget_end, steps_bound, events_bound;
    double steps_used, events_used;
    char msg[512]; /* why the last call failed */
} StepClock;

typedef struct Stepper Stepper;

/* One integration method. Every operation gets the stepper (its clock and memory) and the
 * model; integer results: 0 success, -1 failure with st->clk.msg set. */
typedef struct {
    const char *name;
    /* Allocates the method's memory (st->impl) for `m`, which it may keep a pointer to. */
    int (*create)(Stepper *st, ModelData *m);
    /* Releases st->impl (NULL allowed). */
    void (*free)(Stepper *st);
    /* Puts the clock at absolute time t (the method restarts there at its next advance). */
    void (*start)(Stepper *st, double t);
    /* Integrates to absolute time t_end. With stop_at_event it stops at the first wall event in
     * (now, t_end] and returns 1: the clock is at the event time, the model holds the state at
     * the crossing before the jump, and clk.pending is set (the jump: apply_pending, or the
     * start of the next advance). With m->sensitivities the model's J and S ride along and every
     * jump goes through sens_event_update (its saltation matrix). */
    int (*advance_to)(Stepper *st, ModelData *m, double t_end, int stop_at_event);
    /* Applies a pending event's jump (no-op without one); returns 1 if there was one. */
    int (*apply_pending)(Stepper *st, ModelData *m);
} StepperOps;

struct Stepper {
    const StepperOps *ops; /* NULL: no method yet (or its creation failed) */
    StepClock clk;
    void *impl;            /* the method's own memory */
};

/* -- what the core calls ------------------------------------------------------------------- */
/* Makes st run the method of m->solver, creating it (and freeing another) when it changes; the
 * clock is kept. Returns 0, or -1 with st->clk.msg set (stepper_methods.c). */
int stepper_select(Stepper *st, ModelData *m);
void stepper_free(Stepper *st);
void stepper_start(Stepper *st, double t);
int stepper_advance_to(Stepper *st, ModelData *m, double t_end, int stop_at_event);
int stepper_apply_pending(Stepper *st, ModelData *m);
double stepper_time(const Stepper *st);

/* -- what the methods share ------------------------------------------------------------------ */
/* The clock at absolute time t: integer origin, local time in [0, 1), restart, nothing pending. */
void clock_start(StepClock *k, double t);
/* Moves the integer origin up to the current period (the model's ramps and impact times follow
 * it); returns the shift. */
double clock_reorigin(StepClock *k, ModelData *m);
/* The jump of a pending event, with its saltation matrix; returns 1 if there was one. */
int clock_apply_pending(StepClock *k, ModelData *m);
/* Sets the work bound of a doStep from now to t_end, in double (a span of 1e300 must not
 * overflow a long: the bound saturates at cap). */
void clock_begin_budget(StepClock *k, const ModelData *m, double t_end, double cap);
/* 1, with k->msg naming the bound, if the steps (events = 0; `unit` names them) or the wall
 * events (events = 1) used exceed the budget; t_local is where, in local time. */
int clock_over_budget(StepClock *k, const ModelData *m, int events, double cap, const char *unit,
                      double t_local);

#endif
