/*
 * CVODE driver for the impact oscillator (SUNDIALS 6): the stepper STEPPER_CVODE (solver_cvode.h,
 * stepper.h), called by the FMI core through stepper.c when solver = 0.
 *
 * Between events the model is smooth (the contact mode is a discrete state, so the right-hand
 * side never switches inside a CVODE segment). Events are found by CVODE's root finding on two
 * indicators: the wall (g0) and the velocity (g1). The second is the grazing guard: a contact
 * that enters and leaves the wall within one internal step leaves g0 with the same sign at both
 * step ends, so CVODE cannot see it; its turning point, however, changes the sign of v and is
 * found. If the wall indicator has the wrong sign at that turning point, the crossing lies in the
 * last step, and is located on CVODE's interpolant.
 *
 * Totality. CVODE runs in one-step mode, so every step end is seen: the wall indicator is
 * checked there (and at every turning point and communication point), and a state on the wrong
 * side of the wall is never returned: the crossing is located between the last point known to
 * be on the right side (at latest the start of the step) and the offending point.
 *
 * Time grid. CVODE's steps never depend on the communication points: it steps past them and
 * the state at a communication point is read from its interpolant (CVodeGetDky). Setting each
 * communication point as a stop time instead made the result depend on the importer's time
 * arithmetic: a point a few ulps past a step end gave a ~1e-14 "sliver" step, after which the
 * variable-step Adams history (step ratios ~1e-12) lost up to 1e-4 in u.
 */
#include "solver_cvode.h"

#include "sens.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

/* Re-origin the local time at this (integer, so exact) local time, so that tau stays O(1)
 * (the forcing phase and the root-finding tolerance both scale with |tau|). It is a stop
 * time of CVODE's own, the same for every communication grid; each one is a restart. */
static const double REORIGIN_AT = 64.0;
/* Solver steps must not straddle two turning points of u, or the guard's sign change on v is
 * lost too; a fifth of the shortest period in the problem (forcing: 1) is safe. */
static const double MAX_STEP = 0.05;
/* SUNDIALS 6.4.1 decides "sign change" in its root finding by the product glo*ghi < 0, which
 * underflows to 0 for |glo ghi| < 1e-324: a mass restarted ON_WALL = 1e-300 off the wall
 * (model.c) that crosses by 1e-24 was not seen (r = 0 and chatter failures; LLNL/sundials#57).
 * Root values are therefore floored to this magnitude, keeping their sign: the products stay
 * >= 1e-300 and the located times are unchanged (the search works on signs). */
#ifndef IMPACT_NO_ROOT_FLOOR
static const double ROOT_FLOOR = 1e-150;
#else /* tests only (CMake IMPACT_NO_ROOT_FLOOR): the second defence, rescue(), must then act */
static const double ROOT_FLOOR = 0.0;
#endif

_Static_assert(SENS_NEQ <= 8, "Cvode.y_next and y_stop hold SENS_NEQ components");

/* CVODE's memory and the driver's own state (the stepper's impl); the time, the pending jump,
 * the counters and the budget are the stepper's clock (stepper.h). */
typedef struct {
    StepClock *k; /* the clock of the stepper this memory belongs to */
    void *cvode;
    void *ctx;  /* SUNContext */
    void *y;    /* N_Vector */
    void *tmp;  /* N_Vector: interpolation */
    void *A;    /* SUNMatrix */
    void *LS;   /* SUNLinearSolver */
    int n;      /* equations: 2, or SENS_NEQ with the sensitivities (sens.h) */
    /* CVODE's own (local) time: the end of its last step, >= tau. The state at tau is taken
     * from CVODE's interpolant of the step [tn - hu, tn]. */
    double tn;
    /* Latest local time in [tn - hu, tn] at which the wall indicator was seen on its mode's
     * side (a step end, a turning point, the restart point). */
    double tau_good;
    int at_stop;     /* CVODE stopped at the re-origin time t_stop, with state y_stop */
    double t_stop, y_stop[8];
    /* A crossing located ahead of tau (inside CVODE's last step), its jump not applied yet. */
    int has_next;
    double t_next, y_next[8]; /* 8: room for SENS_NEQ (sens.h) */
} Cvode;

#define CV(s) ((s)->cvode)
#define YV(s) ((N_Vector)(s)->y)

/* With sensitivities the state is (u, v, J, S) of sens.h (SENS_NEQ components), else (u, v). */
static int rhs(realtype t, N_Vector y, N_Vector ydot, void *user_data) {
    if (N_VGetLength(y) == SENS_NEQ)
        sens_rhs((const ModelData *)user_data, t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
    else
        model_derivatives((const ModelData *)user_data, t, N_VGetArrayPointer(y),
                          N_VGetArrayPointer(ydot));
    /* A non-finite derivative (a trial state far outside the valid range) is reported as a
     * recoverable failure: CVODE retries with a smaller step, and stops with a message if it
     * persists, instead of carrying inf/NaN into its history. */
    const double *dy = N_VGetArrayPointer(ydot);
    for (sunindextype i = 0; i < N_VGetLength(ydot); ++i)
        if (!isfinite(dy[i])) return 1;
    return 0;
}

static int jac(realtype t, N_Vector y, N_Vector fy, SUNMatrix J, void *user_data, N_Vector t1,
               N_Vector t2, N_Vector t3) {
    (void)fy; (void)t1; (void)t2; (void)t3;
    if (N_VGetLength(y) == SENS_NEQ) {
        double big[SENS_NEQ][SENS_NEQ];
        sens_jacobian((const ModelData *)user_data, t, N_VGetArrayPointer(y), big);
        for (int i = 0; i < SENS_NEQ; ++i)
            for (int j = 0; j < SENS_NEQ; ++j) SM_ELEMENT_D(J, i, j) = big[i][j];
        return 0;
    }
    double a[2][2];
    model_jacobian((const ModelData *)user_data, t, N_VGetArrayPointer(y), a);
    SM_ELEMENT_D(J, 0, 0) = a[0][0];
    SM_ELEMENT_D(J, 0, 1) = a[0][1];
    SM_ELEMENT_D(J, 1, 0) = a[1][0];
    SM_ELEMENT_D(J, 1, 1) = a[1][1];
    return 0;
}

static double floored(double g) {
    return (g != 0.0 && fabs(g) < ROOT_FLOOR) ? copysign(ROOT_FLOOR, g) : g;
}

static int roots(realtype t, N_Vector y, realtype *g, void *user_data) {
    model_event_indicators((const ModelData *)user_data, t, N_VGetArrayPointer(y), g);
    for (int i = 0; i < MODEL_N_EVENTS; ++i) g[i] = floored(g[i]);
    return 0;
}

static void error_handler(int code, const char *module, const char *function, char *msg,
                          void *data) {
    Cvode *s = (Cvode *)data;
    snprintf(s->k->msg, sizeof s->k->msg, "%s/%s (flag %d): %s", module, function, code, msg);
}

/* Allocates CVODE for n equations in the existing context. */
static int create_cvode(Cvode *s, ModelData *m, int n) {
    SUNContext ctx = (SUNContext)s->ctx;
    s->n = n;
    s->y = N_VNew_Serial(n, ctx);
    s->tmp = N_VNew_Serial(n, ctx);
    s->cvode = CVodeCreate(CV_ADAMS, ctx);
    if (!s->y || !s->tmp || !s->cvode) goto fail;
    CVodeSetErrHandlerFn(CV(s), error_handler, s);
    N_VConst(0.0, YV(s));
    NV_Ith_S(YV(s), 0) = m->u;
    NV_Ith_S(YV(s), 1) = m->v;
    if (CVodeInit(CV(s), rhs, 0.0, YV(s)) != CV_SUCCESS) goto fail;
    if (CVodeRootInit(CV(s), MODEL_N_EVENTS, roots) != CV_SUCCESS) goto fail;
    s->A = SUNDenseMatrix(n, n, ctx);
    s->LS = SUNLinSol_Dense(YV(s), (SUNMatrix)s->A, ctx);
    if (!s->A || !s->LS) goto fail;
    if (CVodeSetLinearSolver(CV(s), (SUNLinearSolver)s->LS, (SUNMatrix)s->A) != CV_SUCCESS) goto fail;
    CVodeSetJacFn(CV(s), jac);
    CVodeSetUserData(CV(s), m);
    CVodeSetMaxStep(CV(s), MAX_STEP);
    CVodeSetNoInactiveRootWarn(CV(s));
    s->k->restart = 1;
    return 0;
fail:
    return -1;
}

static void free_cvode(Cvode *s) {
    if (s->cvode) CVodeFree(&s->cvode);
    if (s->LS) SUNLinSolFree((SUNLinearSolver)s->LS);
    if (s->A) SUNMatDestroy((SUNMatrix)s->A);
    if (s->y) N_VDestroy(YV(s));
    if (s->tmp) N_VDestroy((N_Vector)s->tmp);
    s->cvode = s->LS = s->A = s->y = s->tmp = NULL;
}

static void cvode_free(Stepper *st) {
    Cvode *s = (Cvode *)st->impl;
    if (!s) return;
    free_cvode(s);
    if (s->ctx) {
        SUNContext ctx = (SUNContext)s->ctx;
        SUNContext_Free(&ctx);
    }
    free(s);
    st->impl = NULL;
}

static int cvode_create(Stepper *st, ModelData *m) {
    Cvode *s = calloc(1, sizeof *s);
    st->impl = s;
    st->clk.msg[0] = '\0';
    if (!s) {
        snprintf(st->clk.msg, sizeof st->clk.msg, "could not allocate CVODE");
        return -1;
    }
    s->k = &st->clk;
    SUNContext ctx;
    if (SUNContext_Create(NULL, &ctx) != 0 || (s->ctx = ctx, create_cvode(s, m, 2) != 0)) {
        if (!st->clk.msg[0]) snprintf(st->clk.msg, sizeof st->clk.msg, "could not allocate CVODE");
        cvode_free(st);
        return -1;
    }
    return 0;
}

static void cvode_start(Stepper *st, double t) { clock_start(&st->clk, t); }

/* True where the wall indicator at (tau, y) lies on the far side of its mode's root direction:
 * the model must not be left there (a free mass inside the rigid wall, ...). */
static int wrong_side(const ModelData *m, double tau, const double y[2]) {
    if (m->wall == WALL_NONE) return 0;
    double g[MODEL_N_EVENTS];
    int dir[MODEL_N_EVENTS];
    model_event_indicators(m, tau, y, g);
    model_root_directions(m, dir);
    return dir[0] > 0 ? g[0] > 0.0 : g[0] < 0.0;
}

/* Restarts CVODE at (tau, m->u, m->v) in the model's current mode, moving the integer time
 * origin up to the current period first. */
static int reinit(Cvode *s, ModelData *m) {
    StepClock *k = s->k;
    /* the variational equations ride along only when asked for (no cost otherwise) */
    const int n = m->sensitivities ? SENS_NEQ : 2;
    if (n != s->n) {
        free_cvode(s);
        if (create_cvode(s, m, n) != 0) {
            snprintf(k->msg, sizeof k->msg, "could not allocate CVODE for %d equations", n);
            return -1;
        }
    }
    clock_reorigin(k, m);
    if (model_release_now(m, k->tau)) k->events++;
    if (s->n == SENS_NEQ) {
        sens_pack(m, N_VGetArrayPointer(YV(s)));
    } else {
        NV_Ith_S(YV(s), 0) = m->u;
        NV_Ith_S(YV(s), 1) = m->v;
    }
    if (CVodeReInit(CV(s), k->tau, YV(s)) != CV_SUCCESS ||
        CVodeSStolerances(CV(s), m->rtol, m->atol) != CV_SUCCESS ||
        CVodeSetStopTime(CV(s), REORIGIN_AT) != CV_SUCCESS) {
        if (!k->msg[0]) snprintf(k->msg, sizeof k->msg, "could not restart CVODE");
        return -1;
    }
    int dir[MODEL_N_EVENTS];
    model_root_directions(m, dir);
    CVodeSetRootDirection(CV(s), dir);
    s->tn = s->tau_good = k->tau;
    s->has_next = 0;
    s->at_stop = 0;
    k->restart = 0;
    return 0;
}

/* The state on CVODE's interpolant of its last step, at local time t (all s->n components). */
static int interpolate(Cvode *s, double t, double y[SENS_NEQ]) {
    N_Vector tmp = (N_Vector)s->tmp;
    if (CVodeGetDky(CV(s), t, 0, tmp) != CV_SUCCESS) return -1;
    for (int i = 0; i < s->n; ++i) y[i] = NV_Ith_S(tmp, i);
    return 0;
}

/* Copies the s->n components of a state. */
static void copy_state(const Cvode *s, double *dst, const double *src) {
    memcpy(dst, src, sizeof(double) * (size_t)s->n);
}

/* Puts the state y (s->n components) into the model. */
static void set_model_state(const Cvode *s, ModelData *m, const double *y) {
    if (s->n == SENS_NEQ) sens_unpack(m, y);
    m->u = y[0];
    m->v = y[1];
    if (m->mode == MODE_STICK) {
        /* A sticking mass is on the wall by definition, as in the closed form's stuck_state.
         * CVODE's u' = w' gathers rounding: an ulp below the wall's own position, the next input
         * change (even the master writing the wall's current value) read as a wall that went
         * away, released the mass at rest and counted a new impact on every other step. */
        m->u = model_wall_position(m, s->k->tau);
        m->v = model_wall_velocity(m);
    }
}

/* The wall indicator lies on its mode's side at lo and on the far side at hi (both in CVODE's
 * last step). Locates the crossing by Illinois regula falsi on the interpolant, deciding by
 * signs (never by products, which underflow); stores it as the next event, on the far side of
 * the wall so that the event applies. */
static int locate_crossing(Cvode *s, const ModelData *m, double lo, double hi) {
    double ylo[SENS_NEQ], yhi[SENS_NEQ], g[MODEL_N_EVENTS];
    if (interpolate(s, lo, ylo) != 0 || interpolate(s, hi, yhi) != 0) return -1;
    if (!wrong_side(m, hi, yhi)) return -1; /* not bracketed */
    model_event_indicators(m, hi, yhi, g);
    double ghi = g[0];
    model_event_indicators(m, lo, ylo, g);
    /* lo was seen on the right side (a step end or a restart); the interpolant may put it a
     * round-off across (a start at rest on the wall): its sign is the right side's, then */
    double glo = wrong_side(m, lo, ylo) ? copysign(0.0, -ghi) : g[0];
    int side = 0;
    for (int it = 0; it < 400 && hi - lo > 4e-16 * fmax(1.0, fabs(hi)); ++it) {
        double t = lo + (hi - lo) * (glo / (glo - ghi)); /* glo, ghi of opposite signs */
        if (!(t > lo && t < hi)) t = lo + 0.5 * (hi - lo);
        double y[SENS_NEQ];
        if (interpolate(s, t, y) != 0) return -1;
        model_event_indicators(m, t, y, g);
        if (wrong_side(m, t, y)) {
            hi = t; ghi = g[0];
            copy_state(s, yhi, y);
            if (side == +1) glo *= 0.5;
            side = +1;
        } else {
            lo = t; glo = g[0];
            if (side == -1) ghi *= 0.5;
            side = -1;
        }
    }
    s->has_next = 1;
    s->t_next = hi;
    copy_state(s, s->y_next, yhi);
    return 0;
}

/* The latest point known to be on the right side, in CVODE's last step and not after t. */
static double last_good_before(Cvode *s, double t) {
    realtype hu = 0.0;
    CVodeGetLastStep(CV(s), &hu);
    const double start = s->tn - hu;
    return (s->tau_good <= t && s->tau_good >= start) ? s->tau_good : start;
}

static int over_budget(Cvode *s, const ModelData *m, int events) {
    return clock_over_budget(s->k, m, events, SOLVER_MAX_STEPS_PER_CALL, "CVODE steps", s->tn);
}

/* A rescue counts as a step against the doStep's budget: a rescue that never located its
 * crossing (a bug) would otherwise repeat without end instead of failing. */
static int rescue(Cvode *s, const ModelData *m, double t) {
    StepClock *k = s->k;
    k->steps_used += 1.0;
    if (over_budget(s, m, 0)) return -1;
    if (locate_crossing(s, m, last_good_before(s, t), t) != 0) {
        snprintf(k->msg, sizeof k->msg,
                 "could not locate a wall crossing stepped over before t = %.17g",
                 k->origin + t);
        return -1;
    }
    k->guard_hits++;
    return 0;
}

static int cvode_apply_pending(Stepper *st, ModelData *m) {
    return clock_apply_pending(&st->clk, m);
}

/* Applies the event stored by locate_crossing or CVODE's root return, at its time. */
static int take_event(Cvode *s, ModelData *m, int stop_at_event) {
    StepClock *k = s->k;
    k->tau = s->t_next;
    set_model_state(s, m, s->y_next); /* J, S at the crossing too */
    s->has_next = 0;
    k->restart = 1;
    k->events_used += 1.0; /* counted once, whoever applies the jump */
    if (over_budget(s, m, 1)) return -1;
    if (stop_at_event) { /* FMI 3.0 early return: the jump is the importer's event mode */
        k->pending = 1;
        return 1;
    }
    double y[2] = {m->u, m->v};
    sens_event_update(m, k->tau, y);
    m->u = y[0];
    m->v = y[1];
    k->events++;
    return reinit(s, m);
}

/* One CVODE step (counted against the budget), and what its end tells: a located crossing (the
 * next event), the re-origin stop, or a point on the wrong side of the wall (rescued). */
static int one_step(Cvode *s, ModelData *m) {
    StepClock *k = s->k;
    k->steps_used += 1.0;
    if (over_budget(s, m, 0)) return -1;
    realtype tret, tn;
    /* tout only sets the first step size after a restart: keep it off the grid too */
    const int flag = CVode(CV(s), s->tn + 1.0, YV(s), &tret, CV_ONE_STEP);
    if (flag < 0) {
        if (!k->msg[0]) snprintf(k->msg, sizeof k->msg, "CVode failed with flag %d", flag);
        return -1;
    }
    CVodeGetCurrentTime(CV(s), &tn);
    s->tn = tn;
    const double *y = N_VGetArrayPointer(YV(s));
    if (flag == CV_TSTOP_RETURN) { /* y = y(tstop), tn within round-off of it */
        s->at_stop = 1;
        s->t_stop = tret;
        copy_state(s, s->y_stop, y);
    }
    if (!isfinite(y[0]) || !isfinite(y[1])) {
        snprintf(k->msg, sizeof k->msg, "the state is no longer finite at t = %.17g",
                 k->origin + tret);
        return -1;
    }
    if (flag == CV_ROOT_RETURN) {
        int info[MODEL_N_EVENTS];
        CVodeGetRootInfo(CV(s), info);
        if (info[0] != 0) { /* CVODE located the crossing: y is on the far side */
            s->has_next = 1;
            s->t_next = tret;
            copy_state(s, s->y_next, y);
            return 0;
        }
        if (wrong_side(m, tret, y)) return rescue(s, m, tret); /* a turning point beyond the wall */
        s->tau_good = tret; /* a turning point on the right side of the wall */
        return 0;
    }
    /* a step end: CVODE's root finding may not see a crossing of a few ulps */
    if (wrong_side(m, tret, y)) return rescue(s, m, tret);
    s->tau_good = tret;
    return 0;
}

static int cvode_advance_to(Stepper *st, ModelData *m, double t_end, int stop_at_event) {
    Cvode *s = (Cvode *)st->impl;
    StepClock *k = &st->clk;
    k->msg[0] = '\0';
    if (!(k->continuing && t_end == k->budget_end))
        clock_begin_budget(k, m, t_end, SOLVER_MAX_STEPS_PER_CALL);
    k->continuing = 0;
    clock_apply_pending(k, m);
    if (t_end < stepper_time(st)) {
        snprintf(k->msg, sizeof k->msg, "cannot integrate backwards to t = %.17g", t_end);
        return -1;
    }
    if (k->restart && reinit(s, m) != 0) return -1;

    for (;;) {
        const double tau_end = t_end - k->origin; /* the origin moves at restarts */
        if (s->has_next && s->t_next <= tau_end) { /* an event before the end */
            const int rc = take_event(s, m, stop_at_event);
            if (rc != 0) {
                k->continuing = rc == 1;
                return rc;
            }
            continue;
        }
        if (tau_end <= k->tau) return 0; /* h = 0, or below the resolution of t */
        /* CVODE's last step covers the end: interpolate */
        if (s->tn >= tau_end || (s->at_stop && tau_end < s->t_stop)) {
            double y[SENS_NEQ];
            if (interpolate(s, tau_end, y) != 0) {
                snprintf(k->msg, sizeof k->msg, "could not interpolate at t = %.17g", t_end);
                return -1;
            }
            if (wrong_side(m, tau_end, y)) { /* never returned: find the crossing before it */
                if (rescue(s, m, tau_end) != 0) return -1;
                continue;
            }
            k->tau = tau_end;
            set_model_state(s, m, y);
            return 0;
        }
        if (s->at_stop) { /* the re-origin time: restart there, the same for every grid */
            k->tau = s->t_stop;
            set_model_state(s, m, s->y_stop);
            if (reinit(s, m) != 0) return -1;
            continue;
        }
        if (one_step(s, m) != 0) return -1;
    }
}

const StepperOps STEPPER_CVODE = {
    "CVODE", cvode_create, cvode_free, cvode_start, cvode_advance_to, cvode_apply_pending,
};
