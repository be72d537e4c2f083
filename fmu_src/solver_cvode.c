/*
 * CVODE driver for the impact oscillator (SUNDIALS 6).
 *
 * Between events the model is smooth (the contact mode is a discrete state, so the right-hand
 * side never switches inside a CVODE segment). Events are found by CVODE's root finding on two
 * indicators: the wall (g0) and the velocity (g1). The second is the grazing guard: a contact
 * that enters and leaves the wall within one internal step leaves g0 with the same sign at both
 * step ends, so CVODE cannot see it; its turning point, however, changes the sign of v and is
 * found. If the wall indicator has the wrong sign at that turning point, the crossing lies in the
 * last step, and is located on CVODE's interpolant.
 */
#include "solver.h"

#include "closed_form.h"
#include "sens.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

/* Re-origin the local time once it passes this, so that tau stays O(1) (the forcing phase and
 * the root-finding tolerance both scale with |tau|). Each re-origin is one CVODE restart. */
static const double REORIGIN_AFTER = 64.0;
/* Solver steps must not straddle two turning points of u, or the guard's sign change on v is
 * lost too; a fifth of the shortest period in the problem (forcing: 1) is safe. */
static const double MAX_STEP = 0.05;
/* Bounds on the work of one doStep (per unit of time advanced): errors, never hangs. */
static const double MAX_STEPS_PER_UNIT_TIME = 2e5;
static const double MAX_EVENTS_PER_UNIT_TIME = 1e5;

#define CV(s) ((s)->cvode)
#define YV(s) ((N_Vector)(s)->y)

/* With sensitivities the state is (u, v, J, S) of sens.h (SENS_NEQ components), else (u, v). */
static int rhs(realtype t, N_Vector y, N_Vector ydot, void *user_data) {
    if (N_VGetLength(y) == SENS_NEQ)
        sens_rhs((const ModelData *)user_data, t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
    else
        model_derivatives((const ModelData *)user_data, t, N_VGetArrayPointer(y),
                          N_VGetArrayPointer(ydot));
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

static int roots(realtype t, N_Vector y, realtype *g, void *user_data) {
    model_event_indicators((const ModelData *)user_data, t, N_VGetArrayPointer(y), g);
    return 0;
}

static void error_handler(int code, const char *module, const char *function, char *msg,
                          void *data) {
    Solver *s = (Solver *)data;
    snprintf(s->msg, sizeof s->msg, "%s/%s (flag %d): %s", module, function, code, msg);
}

/* Allocates CVODE for n equations in the existing context. */
static int create_cvode(Solver *s, ModelData *m, int n) {
    SUNContext ctx = (SUNContext)s->ctx;
    s->n = n;
    s->y = N_VNew_Serial(n, ctx);
    s->cvode = CVodeCreate(CV_ADAMS, ctx);
    if (!s->y || !s->cvode) goto fail;
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
    s->needs_reinit = 1;
    return 0;
fail:
    return -1;
}

static void free_cvode(Solver *s) {
    if (s->cvode) CVodeFree(&s->cvode);
    if (s->LS) SUNLinSolFree((SUNLinearSolver)s->LS);
    if (s->A) SUNMatDestroy((SUNMatrix)s->A);
    if (s->y) N_VDestroy(YV(s));
    s->cvode = s->LS = s->A = s->y = NULL;
}

int solver_create(Solver *s, ModelData *m) {
    memset(s, 0, sizeof *s);
    SUNContext ctx;
    if (SUNContext_Create(NULL, &ctx) != 0 || (s->ctx = ctx, create_cvode(s, m, 2) != 0)) {
        if (!s->msg[0]) snprintf(s->msg, sizeof s->msg, "could not allocate CVODE");
        solver_free(s);
        return -1;
    }
    return 0;
}

void solver_free(Solver *s) {
    free_cvode(s);
    if (s->ctx) {
        SUNContext ctx = (SUNContext)s->ctx;
        SUNContext_Free(&ctx);
    }
    s->cvode = s->LS = s->A = s->y = s->ctx = NULL;
}

void solver_start(Solver *s, double t) {
    s->origin = floor(t);
    s->tau = t - s->origin;
    s->needs_reinit = 1;
}

double solver_time(const Solver *s) { return s->origin + s->tau; }

/* Restarts CVODE at (tau, m->u, m->v) in the model's current mode, moving the integer time
 * origin up to the current period first. */
static int reinit(Solver *s, ModelData *m) {
    /* the variational equations ride along only when asked for (no cost otherwise) */
    const int n = m->sensitivities ? SENS_NEQ : 2;
    if (n != s->n) {
        free_cvode(s);
        if (create_cvode(s, m, n) != 0) {
            snprintf(s->msg, sizeof s->msg, "could not allocate CVODE for %d equations", n);
            return -1;
        }
    }
    const double k = floor(s->tau);
    s->origin += k;
    s->tau -= k;
    model_shift_time(m, k); /* the model's input ramps and impact times follow the origin */
    if (model_release_now(m, s->tau)) s->events++;
    if (s->n == SENS_NEQ) {
        sens_pack(m, N_VGetArrayPointer(YV(s)));
    } else {
        NV_Ith_S(YV(s), 0) = m->u;
        NV_Ith_S(YV(s), 1) = m->v;
    }
    if (CVodeReInit(CV(s), s->tau, YV(s)) != CV_SUCCESS ||
        CVodeSStolerances(CV(s), m->rtol, m->atol) != CV_SUCCESS) {
        return -1;
    }
    int dir[MODEL_N_EVENTS];
    model_root_directions(m, dir);
    CVodeSetRootDirection(CV(s), dir);
    s->tau_good = s->tau;
    s->needs_reinit = 0;
    return 0;
}

/* The wall indicator g0 along CVODE's interpolant of the last step (y: all s->n components). */
static int indicator_at(Solver *s, const ModelData *m, double t, double y[SENS_NEQ], double *g0) {
    N_Vector tmp = N_VNew_Serial(s->n, (SUNContext)s->ctx);
    int flag = CVodeGetDky(CV(s), t, 0, tmp);
    for (int i = 0; i < s->n; ++i) y[i] = NV_Ith_S(tmp, i);
    N_VDestroy(tmp);
    double g[MODEL_N_EVENTS];
    model_event_indicators(m, t, y, g);
    *g0 = g[0];
    return flag;
}

/* A turning point (time t_turn) showed that the wall was crossed and re-crossed inside the last
 * step. Locates the first crossing by Illinois regula falsi on the interpolant; on return *tc and
 * yc hold the crossing (on the far side of the wall, so the event applies). */
static int locate_missed_crossing(Solver *s, const ModelData *m, double t_turn, double *tc,
                                  double yc[SENS_NEQ]) {
    realtype tn, hu;
    CVodeGetCurrentTime(CV(s), &tn);
    CVodeGetLastStep(CV(s), &hu);
    double lo = fmax(s->tau_good, tn - hu), hi = t_turn;
    double ylo[SENS_NEQ], yhi[SENS_NEQ], glo, ghi;
    if (indicator_at(s, m, lo, ylo, &glo) != CV_SUCCESS ||
        indicator_at(s, m, hi, yhi, &ghi) != CV_SUCCESS)
        return -1;
    /* g0 keeps its mode's sign before the crossing: compare against the far side's sign */
    const double far = ghi;
    if (glo * far > 0.0) return -1; /* not bracketed: should not happen */
    int side = 0;
    for (int it = 0; it < 200 && hi - lo > 4e-16 * fmax(1.0, fabs(hi)); ++it) {
        double t = (lo * ghi - hi * glo) / (ghi - glo);
        if (!(t > lo && t < hi)) t = 0.5 * (lo + hi);
        double y[SENS_NEQ], g;
        indicator_at(s, m, t, y, &g);
        if (g * far > 0.0) {
            hi = t; ghi = g;
            memcpy(yhi, y, sizeof(double) * s->n);
            if (side == +1) glo *= 0.5;
            side = +1;
        } else {
            lo = t; glo = g;
            if (side == -1) ghi *= 0.5;
            side = -1;
        }
    }
    *tc = hi;
    memcpy(yc, yhi, sizeof(double) * s->n);
    return 0;
}

int solver_apply_pending(Solver *s, ModelData *m) {
    if (!s->pending) return 0;
    double y[2] = {m->u, m->v};
    sens_event_update(m, s->tau, y);
    m->u = y[0];
    m->v = y[1];
    s->events++;
    s->pending = 0;
    s->needs_reinit = 1;
    return 1;
}

int solver_advance(Solver *s, ModelData *m, double t_end) {
    return solver_advance_ex(s, m, t_end, 0);
}

int solver_advance_ex(Solver *s, ModelData *m, double t_end, int stop_at_event) {
    s->msg[0] = '\0';
    if (m->solver == SOLVER_CLOSED_FORM) return closed_form_advance(s, m, t_end, stop_at_event);
    solver_apply_pending(s, m);
    if (s->needs_reinit || s->tau > REORIGIN_AFTER) {
        if (reinit(s, m) != 0) return -1;
    }
    double tau_end = t_end - s->origin;
    if (tau_end < s->tau) {
        snprintf(s->msg, sizeof s->msg, "cannot integrate backwards to t = %.17g", t_end);
        return -1;
    }
    const double span = fmax(1.0, ceil(tau_end - s->tau));
    const long max_events = (long)(MAX_EVENTS_PER_UNIT_TIME * span);
    CVodeSetMaxNumSteps(CV(s), (long)(MAX_STEPS_PER_UNIT_TIME * span));
    long events = 0;

    while (s->tau < tau_end) {
        CVodeSetStopTime(CV(s), tau_end);
        realtype tret;
        const int flag = CVode(CV(s), tau_end, YV(s), &tret, CV_NORMAL);
        if (flag < 0) {
            if (!s->msg[0]) snprintf(s->msg, sizeof s->msg, "CVode failed with flag %d", flag);
            return -1;
        }
        double *y = N_VGetArrayPointer(YV(s));
        s->tau = tret;
        if (s->n == SENS_NEQ) sens_unpack(m, y);
        m->u = y[0];
        m->v = y[1];
        if (flag != CV_ROOT_RETURN) continue; /* CV_TSTOP_RETURN: tret == tau_end */

        int info[MODEL_N_EVENTS];
        CVodeGetRootInfo(CV(s), info);
        if (info[0] == 0 && !model_missed_crossing(m, tret, y)) {
            s->tau_good = tret; /* a turning point on the right side of the wall */
            continue;
        }
        double yc[SENS_NEQ], tc = tret;
        memcpy(yc, y, sizeof(double) * s->n);
        if (info[0] == 0) {
            if (locate_missed_crossing(s, m, tret, &tc, yc) != 0) {
                snprintf(s->msg, sizeof s->msg,
                         "could not locate a wall crossing stepped over before t = %.17g",
                         s->origin + tret);
                return -1;
            }
            s->guard_hits++;
        }
        if (s->n == SENS_NEQ) sens_unpack(m, yc); /* J, S at the crossing */
        if (stop_at_event) { /* FMI 3.0 early return: the jump is the importer's event mode */
            s->tau = tc;
            m->u = yc[0];
            m->v = yc[1];
            s->pending = 1;
            s->needs_reinit = 1;
            return 1;
        }
        sens_event_update(m, tc, yc);
        s->tau = tc;
        m->u = yc[0];
        m->v = yc[1];
        s->events++;
        if (++events > max_events) {
            snprintf(s->msg, sizeof s->msg,
                     "more than %ld wall events before t = %.17g (chatter that does not end?)",
                     max_events, s->origin + tc);
            return -1;
        }
        if (reinit(s, m) != 0) return -1;
        tau_end = t_end - s->origin; /* the origin may have moved */
    }
    return 0;
}
