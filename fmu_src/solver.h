/*
 * CVODE driver: integrates the model of model.h between communication points, locating every
 * wall crossing with CVODE's root finding and applying the model's jumps at the located times.
 */
#ifndef IMPACT_SOLVER_H
#define IMPACT_SOLVER_H

#include "model.h"

typedef struct {
    void *cvode;
    void *ctx;  /* SUNContext */
    void *y;    /* N_Vector */
    void *A;    /* SUNMatrix */
    void *LS;   /* SUNLinearSolver */
    int n;      /* equations: 2, or SENS_NEQ with the sensitivities (sens.h) */
    /* Time is origin + tau with an integer origin (see model.h). */
    double origin;
    double tau;
    /* Local time of the last point where the indicators were known to have their mode's sign. */
    double tau_good;
    int needs_reinit;
    /* Counters since the start, for statistics and tests. */
    long events;
    long guard_hits;  /* crossings the grazing guard recovered */
    /* A wall event located by solver_advance_ex(stop_at_event) whose jump is not applied yet:
     * tau is the event time and the model holds the state at the crossing, before the jump. */
    int pending;
    char msg[512];    /* why the last call failed */
} Solver;

/* Allocates CVODE for `m`; returns 0, or -1 with s->msg set. */
int solver_create(Solver *s, ModelData *m);
void solver_free(Solver *s);
/* Puts the solver at absolute time t with the model's state; CVODE restarts there. */
void solver_start(Solver *s, double t);
/* Integrates to absolute time t_end; returns 0, or -1 with s->msg set. */
int solver_advance(Solver *s, ModelData *m, double t_end);
/* As solver_advance, but with stop_at_event it stops at the first wall event in (now, t_end]
 * and returns 1: solver_time() is the event time, the model holds the state at the crossing
 * before the jump, and s->pending is set. The jump is applied by solver_apply_pending (FMI 3.0
 * event mode), or at the start of the next advance. stop_at_event = 0 is solver_advance. */
int solver_advance_ex(Solver *s, ModelData *m, double t_end, int stop_at_event);
/* Applies a pending event's jump (no-op without one); returns 1 if there was one. */
int solver_apply_pending(Solver *s, ModelData *m);
double solver_time(const Solver *s);

#endif
