/*
 * Sensitivities: variational equations and saltation matrices (see sens.h for the formulas).
 */
#include "sens.h"

#include <math.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

void sens_reset(ModelData *m) {
    m->sJ[0][0] = m->sJ[1][1] = 1.0;
    m->sJ[0][1] = m->sJ[1][0] = 0.0;
    m->sS[0] = m->sS[1] = 0.0;
}

static void matmul(const double X[2][2], double J[2][2], double S[2]) {
    const double a = X[0][0], b = X[0][1], c = X[1][0], d = X[1][1];
    for (int j = 0; j < 2; ++j) {
        const double x = J[0][j], y = J[1][j];
        J[0][j] = a * x + b * y;
        J[1][j] = c * x + d * y;
    }
    const double x = S[0], y = S[1];
    S[0] = a * x + b * y;
    S[1] = c * x + d * y;
}

void sens_saltation(const ModelData *before, const ModelData *after, double tau,
                    const double ym[2], const double yp[2], double X[2][2]) {
    X[0][0] = X[1][1] = 1.0;
    X[0][1] = X[1][0] = 0.0;
    if (before->mode == MODE_STICK) return; /* release: a time event, the state is fixed */
    if (before->mode == MODE_FREE && after->mode == MODE_FREE && after->impacts == before->impacts)
        return; /* a leaving mass placed back beside the wall (model_event_update): no jump */
    double DR = 1.0; /* DR = diag(1, DR) */
    if (after->mode == MODE_STICK) DR = 0.0; /* R(u, v) = (u, w'): every nearby state sticks */
    if (before->mode == MODE_FREE && after->mode == MODE_CONTACT)
        DR = before->contact == CONTACT_LINEAR ? before->r : 1.0;
    else if (before->mode == MODE_FREE && after->mode == MODE_FREE)
        DR = -before->r; /* rigid impact */
    double fm[2], fp[2];
    model_derivatives(before, tau, ym, fm);
    model_derivatives(after, tau, yp, fp);
    const double hdot = fm[0] - model_wall_velocity(before);
    X[1][1] = DR;
    if (hdot == 0.0) return; /* exact tangency: no crossing transversal to perturb */
    /* (f+ - DR f-) e1^T / hdot; its first component vanishes for every jump of v only */
    X[0][0] += (fp[0] - fm[0]) / hdot;
    X[1][0] += (fp[1] - DR * fm[1]) / hdot;
}

EventResult sens_event_update(ModelData *m, double tau, double y[2]) {
    if (!m->sensitivities) return model_event_update(m, tau, y, 0);
    const ModelData before = *m;
    const double ym[2] = {y[0], y[1]};
    const EventResult res = model_event_update(m, tau, y, 0);
    double X[2][2];
    sens_saltation(&before, m, tau, ym, y, X);
    matmul(X, m->sJ, m->sS);
    return res;
}

static double dforce_dsigma(const ModelData *m, double tau) {
    if (m->mode == MODE_STICK) return 0.0;
    return m->F_g * cos(2.0 * M_PI * tau + m->phi);
}

void sens_rhs(const ModelData *m, double tau, const double y[SENS_NEQ], double dy[SENS_NEQ]) {
    model_derivatives(m, tau, y, dy);
    double A[2][2];
    model_jacobian(m, tau, y, A);
    /* J' = A J (row-major J in y[2..5]) */
    for (int j = 0; j < 2; ++j) {
        dy[2 + j] = A[0][0] * y[2 + j] + A[0][1] * y[4 + j];
        dy[4 + j] = A[1][0] * y[2 + j] + A[1][1] * y[4 + j];
    }
    dy[6] = A[0][0] * y[6] + A[0][1] * y[7];
    dy[7] = A[1][0] * y[6] + A[1][1] * y[7] + dforce_dsigma(m, tau);
}

void sens_jacobian(const ModelData *m, double tau, const double y[SENS_NEQ],
                   double jac[SENS_NEQ][SENS_NEQ]) {
    memset(jac, 0, sizeof(double) * SENS_NEQ * SENS_NEQ);
    double A[2][2];
    model_jacobian(m, tau, y, A);
    /* blocks: (u, v), (J11, J21), (J12, J22), (S1, S2), each with A */
    static const int idx[4][2] = {{0, 1}, {2, 4}, {3, 5}, {6, 7}};
    for (int b = 0; b < 4; ++b)
        for (int i = 0; i < 2; ++i)
            for (int j = 0; j < 2; ++j) jac[idx[b][i]][idx[b][j]] = A[i][j];
}

void sens_pack(const ModelData *m, double y[SENS_NEQ]) {
    y[0] = m->u;
    y[1] = m->v;
    y[2] = m->sJ[0][0];
    y[3] = m->sJ[0][1];
    y[4] = m->sJ[1][0];
    y[5] = m->sJ[1][1];
    y[6] = m->sS[0];
    y[7] = m->sS[1];
}

void sens_unpack(ModelData *m, const double y[SENS_NEQ]) {
    m->u = y[0];
    m->v = y[1];
    m->sJ[0][0] = y[2];
    m->sJ[0][1] = y[3];
    m->sJ[1][0] = y[4];
    m->sJ[1][1] = y[5];
    m->sS[0] = y[6];
    m->sS[1] = y[7];
}

void sens_propagate(ModelData *m, const double P[2][2], const double ds[2]) {
    matmul(P, m->sJ, m->sS);
    m->sS[0] += ds[0];
    m->sS[1] += ds[1];
}
