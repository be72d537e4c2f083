/*
 * CVODE driver: integrates the model of model.h between communication points, locating every
 * wall crossing with CVODE's root finding and applying the model's jumps at the located times.
 *
 * CVODE runs in one-step mode on its own step sequence, which does not depend on the
 * communication points: it steps past a communication point and the state there is read from
 * CVODE's interpolant. The only stop times are the model's own (wall events, and an integer
 * re-origin time), so the result does not depend on how the importer computes its time grid.
 */
#ifndef IMPACT_SOLVER_H
#define IMPACT_SOLVER_H

#include "model.h"

/* Hard cap on the CVODE steps of one doStep, whatever max_steps_per_time says (a few seconds
 * of work): no call runs for minutes. */
#define SOLVER_MAX_STEPS_PER_CALL 2e6

typedef struct {
    void *cvode;
    void *ctx;  /* SUNContext */
    void *y;    /* N_Vector */
    void *tmp;  /* N_Vector: interpolation */
    void *A;    /* SUNMatrix */
    void *LS;   /* SUNLinearSolver */
    int n;      /* equations: 2, or SENS_NEQ with the sensitivities (sens.h) */
    /* Time is origin + tau with an integer origin (see model.h). */
    double origin;
    double tau;
    /* CVODE's own (local) time: the end of its last step, >= tau. The state at tau is taken
     * from CVODE's interpolant of the step [tn - hu, tn]. */
    double tn;
    /* Latest local time in [tn - hu, tn] at which the wall indicator was seen on its mode's
     * side (a step end, a turning point, the restart point). */
    double tau_good;
    int needs_reinit;
    int at_stop;     /* CVODE stopped at the re-origin time t_stop, with state y_stop */
    double t_stop, y_stop[8];
    /* A crossing located ahead of tau (inside CVODE's last step), its jump not applied yet. */
    int has_next;
    double t_next, y_next[8]; /* 8: room for SENS_NEQ (sens.h) */
    /* Counters since the start, for statistics and tests. */
    long events;
    long guard_hits;  /* crossings stepped over and recovered by the rescue (the side check) */
    /* A wall event located by solver_advance_ex(stop_at_event) whose jump is not applied yet:
     * tau is the event time and the model holds the state at the crossing, before the jump. */
    int pending;
    /* Work budget of one doStep (a chain of early returns towards the same end shares it). */
    int continuing;
    double budget_end, steps_bound, events_bound;
    double steps_used, events_used;
    char msg[512];    /* why the last call failed */
} Solver;

/* Allocates CVODE for `m`; returns 0, or -1 with s->msg set. */
int solver_create(Solver *s, ModelData *m);
void solver_free(Solver *s);
/* Puts the solver at absolute time t with the model's state; CVODE restarts there. */
void solver_start(Solver *s, double t);
/* Integrates to absolute time t_end; returns 0, or -1 with s->msg set. The work is bounded by
 * m->max_steps_per_time and m->max_events_per_time (per unit of time, at least one unit) and by
 * SOLVER_MAX_STEPS_PER_CALL; exceeding a bound is an error whose message names it. */
int solver_advance(Solver *s, ModelData *m, double t_end);
/* As solver_advance, but with stop_at_event it stops at the first wall event in (now, t_end]
 * and returns 1: solver_time() is the event time, the model holds the state at the crossing
 * before the jump, and s->pending is set. The jump is applied by solver_apply_pending (FMI 3.0
 * event mode), or at the start of the next advance. stop_at_event = 0 is solver_advance.
 * With m->solver == SOLVER_CLOSED_FORM both hand over to closed_form_advance (closed_form.h):
 * same contract, no CVODE. With m->sensitivities the state carries J and S (sens.h); every
 * jump goes through sens_event_update (its saltation matrix). */
int solver_advance_ex(Solver *s, ModelData *m, double t_end, int stop_at_event);
/* Applies a pending event's jump (no-op without one); returns 1 if there was one. */
int solver_apply_pending(Solver *s, ModelData *m);
double solver_time(const Solver *s);

#endif
