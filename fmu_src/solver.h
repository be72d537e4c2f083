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
    /* Time is origin + tau with an integer origin (see model.h). */
    double origin;
    double tau;
    /* Local time of the last point where the indicators were known to have their mode's sign. */
    double tau_good;
    int needs_reinit;
    /* Counters since the start, for statistics and tests. */
    long events;
    long guard_hits;  /* crossings the grazing guard recovered */
    char msg[512];    /* why the last call failed */
} Solver;

/* Allocates CVODE for `m`; returns 0, or -1 with s->msg set. */
int solver_create(Solver *s, ModelData *m);
void solver_free(Solver *s);
/* Puts the solver at absolute time t with the model's state; CVODE restarts there. */
void solver_start(Solver *s, double t);
/* Integrates to absolute time t_end; returns 0, or -1 with s->msg set. */
int solver_advance(Solver *s, ModelData *m, double t_end);
double solver_time(const Solver *s);

#endif
