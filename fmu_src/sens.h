/*
 * Sensitivities of the flow: the 2x2 fundamental matrix J = d(u, v)(t)/d(u, v)(t0) and the
 * parameter derivative S = d(u, v)(t)/d sigma, carried through every wall event by its saltation
 * matrix.
 *
 * Between events both obey the variational equations of the smooth mode,
 *     J' = A J,   S' = A S + df/dsigma,   A = df/dy (model_jacobian),
 * df/dsigma = (0, F_g cos(2 pi tau + phi)) (zero while sticking). At a wall event at time t_c,
 * where the indicator h(y, t) = u - w(t) crosses zero and the jump map R takes y- to y+,
 * the perturbations at a fixed time just after the event are those just before it times the
 * saltation matrix (Aizerman & Gantmacher 1958; di Bernardo et al. 2008, section 2.5)
 *     X = DR + (f+ - DR f-) e1^T / (dh/dt along f-),   dh/dt = v- - w',
 * the event time moving with the perturbation (dt_c = -du / (v- - w')). The same matrix maps
 * S (R and h do not depend on sigma). With DR from the event:
 *   compliant entry (linear law: v_rel -> r v_rel)  DR = diag(1, r),
 *   compliant entry, Hertz laws; exit               DR = I (f is continuous: X = I),
 *   rigid impact (v_rel -> -r v_rel)                DR = diag(1, -r),
 *   start of sticking (R(u, v) = (u, w'))          DR = diag(1, 0), f+ = (w', 0): X = 0,
 *   end of sticking (a time event: h = h(t))        X = I.
 * Near grazing v- - w' -> 0 and the entry/impact rows grow like 1/|v-| ~ depth^(-1/2).
 */
#ifndef IMPACT_SENS_H
#define IMPACT_SENS_H

#include "model.h"

/* Number of CVODE components with sensitivities: (u, v), J row-major, S. */
#define SENS_NEQ 8

/* J = I, S = 0 (the start of a doStep). */
void sens_reset(ModelData *m);

/* The saltation matrix of the event that takes `before` (mode, state ym at local time tau) to
 * `after` (state yp). */
void sens_saltation(const ModelData *before, const ModelData *after, double tau,
                    const double ym[2], const double yp[2], double X[2][2]);

/* model_event_update(m, tau, y, 0) and, if m->sensitivities, J <- X J and S <- X S. */
EventResult sens_event_update(ModelData *m, double tau, double y[2]);

/* The augmented right-hand side for CVODE: y = (u, v, J11, J12, J21, J22, S1, S2). */
void sens_rhs(const ModelData *m, double tau, const double y[SENS_NEQ], double dy[SENS_NEQ]);
/* Its Jacobian (row-major SENS_NEQ x SENS_NEQ), exact for the linear law; for the Hertz laws the
 * dependence of A on (u, v) in the J and S rows is left out (a Newton matrix need not be exact). */
void sens_jacobian(const ModelData *m, double tau, const double y[SENS_NEQ],
                   double jac[SENS_NEQ][SENS_NEQ]);
/* Packs (u, v, J, S) of m into y / unpacks y into m. */
void sens_pack(const ModelData *m, double y[SENS_NEQ]);
void sens_unpack(ModelData *m, const double y[SENS_NEQ]);

/* J <- P J, S <- P S + ds (the closed-form propagation over a smooth stretch). */
void sens_propagate(ModelData *m, const double P[2][2], const double ds[2]);

#endif
