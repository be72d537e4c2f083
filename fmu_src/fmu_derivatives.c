/*
 * Exact partial derivatives through the FMI API: core_directional_derivative (fmi2 and
 * fmi3GetDirectionalDerivative) and core_adjoint_derivative (fmi3GetAdjointDerivative), called by
 * the glue (fmi2.c, fmi3.c) in every interface. The partials themselves are the model's
 * (model_partials: the right-hand side of the contact mode now, differentiated); this unit maps
 * value references to its rows and columns and forms J s (directional) or s^T J (adjoint).
 *
 * Knowns: the continuous states u, v and the inputs F_ext, u_wall, v_wall (FMI 2.0 3.2.1 and
 * 4.2.1, FMI 3.0 2.2.11: states and inputs; the parameters are no knowns here). Unknowns: der(u),
 * der(v), the outputs and, in FMI 3.0, the event indicator. The outputs u and v are the states
 * themselves; the discrete outputs (impacts, in_contact, v_impact, t_impact, J_*, S_*) change
 * only at events and at step ends, so their partials are 0 (their ModelStructure dependencies are
 * empty).
 *
 * Initialization Mode (FMI 2.0 2.1.9, FMI 3.0 2.2.11): the unknowns are the Real InitialUnknowns,
 * the knowns the Real variables their dependencies name (parameters and inputs); the partials are
 * those of the values read there, at the start values set so far (model_initial_partials).
 */
#include <math.h>
#include <string.h>

#include "fmu_vars.h"

/* The column of known vr, or -1 (Initialization Mode: init_known_column). */
static int known_column(unsigned vr) {
    switch (vr) {
    case VR_U: return PK_U;
    case VR_V: return PK_V;
    case VR_F_EXT: return PK_F_EXT;
    case VR_U_WALL: return PK_U_WALL;
    case VR_V_WALL: return PK_V_WALL;
    default: return -1;
    }
}

/* Row i of the partials of unknown vr into row[] (MODEL_N_KNOWNS); 0 if vr is no unknown. */
static int unknown_row(const CoreInstance *c, unsigned vr,
                       const double P[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS],
                       const double Pout[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS],
                       double row[MODEL_N_KNOWNS]) {
    const VarDef *d = vars_find(c, vr);
    if (!d || d->type != VT_REAL) return 0; /* the unknowns are Real variables */
    memset(row, 0, sizeof(double) * MODEL_N_KNOWNS);
    switch (vr) {
    case VR_DER_U: memcpy(row, P[PU_DER_U], sizeof(double) * MODEL_N_KNOWNS); return 1;
    case VR_DER_V: memcpy(row, P[PU_DER_V], sizeof(double) * MODEL_N_KNOWNS); return 1;
    case VR_WALL_INDICATOR:
        memcpy(row, P[PU_WALL_INDICATOR], sizeof(double) * MODEL_N_KNOWNS);
        return 1;
    case VR_F_CONTACT: memcpy(row, Pout[PU_F_CONTACT], sizeof(double) * MODEL_N_KNOWNS); return 1;
    case VR_U: row[PK_U] = 1.0; return 1;
    case VR_V: row[PK_V] = 1.0; return 1;
    default: return d->kind == K_OUTPUT; /* discrete outputs: a zero row */
    }
}

/* The partials of a running instance now (Initialization Mode: initial_partials): P for the
 * right-hand side and the indicator (what their getters read), Pout
 * for F_contact, which in Co-Simulation feeds through from an input that jumped (its getter
 * reports the state the input-jump rule gives: model_contact_output_now). */
static void partials_now(const CoreInstance *c, double P[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS],
                         double Pout[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS]) {
    const double tau = core_local_tau(c);
    model_partials(&c->m, tau, P);
    memcpy(Pout, P, sizeof(double) * MODEL_N_UNKNOWNS * MODEL_N_KNOWNS);
    if (c->inputs_changed && !c->is_me) {
        ModelData t;
        memcpy(&t, &c->m, sizeof t);
        double y[2] = {t.u, t.v};
        model_input_jump(&t, tau, y);
        t.u = y[0];
        t.v = y[1];
        model_partials(&t, tau, Pout);
    }
}

/* Initialization Mode: the column of known vr among the Real parameters and inputs the
 * InitialUnknowns depend on, or -1. */
static int init_known_column(unsigned vr) {
    switch (vr) {
    case VR_NU: return IK_NU;
    case VR_OMEGA: return IK_OMEGA;
    case VR_SIGMA: return IK_SIGMA;
    case VR_GAMMA: return IK_GAMMA;
    case VR_U0: return IK_U0;
    case VR_V0: return IK_V0;
    case VR_HC_ALPHA: return IK_ALPHA_HC;
    case VR_F_EXT: return IK_F_EXT;
    case VR_U_WALL: return IK_U_WALL;
    case VR_V_WALL: return IK_V_WALL;
    default: return -1;
    }
}

#define INIT_ZERO_ROW MODEL_N_INIT_UNKNOWNS /* a Real initial unknown that depends on no known */

/* Initialization Mode: the row of unknown vr among the Real InitialUnknowns, INIT_ZERO_ROW for one
 * without dependencies, or -1. */
static int init_unknown_row(unsigned vr) {
    switch (vr) {
    case VR_F_G: return IU_F_G;
    case VR_PHI: return IU_PHI;
    case VR_KAPPA: return IU_KAPPA;
    case VR_U: return IU_U;
    case VR_V: return IU_V;
    case VR_DER_U: return IU_DER_U;
    case VR_DER_V: return IU_DER_V;
    case VR_F_CONTACT: return IU_F_CONTACT;
    case VR_V_IMPACT: case VR_T_IMPACT: case VR_J_UU: case VR_J_UV: case VR_J_VU: case VR_J_VV:
    case VR_S_U: case VR_S_V: return INIT_ZERO_ROW;
    default: return -1;
    }
}

enum {
    MAX_KNOWNS = (int)MODEL_N_INIT_KNOWNS > (int)MODEL_N_KNOWNS ? (int)MODEL_N_INIT_KNOWNS
                                                                : (int)MODEL_N_KNOWNS
};

/* The partials of the instance now: Initialization Mode's (I) or those of a running instance
 * (P, Pout: partials_now). */
typedef struct {
    int init;
    double P[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS], Pout[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS];
    double I[MODEL_N_INIT_UNKNOWNS + 1][MODEL_N_INIT_KNOWNS]; /* the last row: INIT_ZERO_ROW */
} Partials;

/* Initialization Mode: the partials at the state the start values give now (core_view), never at
 * the instance's own model, which holds the defaults' state until Initialization Mode is left. */
static void initial_partials(const CoreInstance *c, Partials *p) {
    CoreInstance buf;
    const CoreInstance *start = core_view(c, &buf);
    memset(p->I, 0, sizeof p->I);
    model_initial_partials(&start->m, core_local_tau(start), p->I);
}

static void partials_of(const CoreInstance *c, Partials *p) {
    p->init = c->state == ST_INIT;
    if (p->init) initial_partials(c, p);
    else partials_now(c, p->P, p->Pout);
}

static int column(const Partials *p, unsigned vr) {
    return p->init ? init_known_column(vr) : known_column(vr);
}

/* Row of unknown vr over the columns (MAX_KNOWNS); 0 if vr is no unknown of the mode. */
static int row_of(const CoreInstance *c, const Partials *p, unsigned vr, double row[MAX_KNOWNS]) {
    if (!p->init) return unknown_row(c, vr, p->P, p->Pout, row);
    const int i = init_unknown_row(vr);
    if (i < 0) return 0;
    memcpy(row, p->I[i], sizeof(double) * MODEL_N_INIT_KNOWNS);
    return 1;
}

/* CORE_OK if every known and unknown is one of the mode's (else the error, naming the first that
 * is not), and every seed finite (else the error naming it). */
static int check_refs(CoreInstance *c, const char *fn, const unsigned unknowns[], size_t nu,
                      const unsigned knowns[], size_t nk, const double seed[], int adjoint) {
    if ((nu && !unknowns) || (nk && !knowns)) return core_fail(c, fn, "NULL argument");
    const int init = c->state == ST_INIT;
    for (size_t j = 0; j < nk; ++j)
        if ((init ? init_known_column(knowns[j]) : known_column(knowns[j])) < 0)
            return core_fail(c, fn, "value reference %u (%s) is not a known%s", knowns[j],
                             core_variable_name(knowns[j]),
                             init ? " in Initialization Mode: the knowns there are the Real "
                                    "parameters and inputs the InitialUnknowns depend on (nu, "
                                    "Omega, sigma, Gamma, u0, v0, alpha_hc, F_ext, u_wall, v_wall)"
                                  : ": the knowns are the states u, v and the inputs F_ext, "
                                    "u_wall, v_wall");
    Partials zero;
    memset(&zero, 0, sizeof zero);
    zero.init = init;
    double row[MAX_KNOWNS];
    for (size_t i = 0; i < nu; ++i)
        if (!row_of(c, &zero, unknowns[i], row))
            return core_fail(c, fn, "value reference %u (%s) is not an unknown%s", unknowns[i],
                             core_variable_name(unknowns[i]),
                             init ? " in Initialization Mode: the unknowns there are the Real "
                                    "InitialUnknowns"
                                  : c->fmi3 ? ": the unknowns are der(u), der(v), the outputs and "
                                              "the event indicator wall_indicator"
                                            : ": the unknowns are der(u), der(v), the outputs");
    const size_t ns = adjoint ? nu : nk;
    for (size_t k = 0; k < ns; ++k)
        if (!isfinite(seed[k]))
            return core_fail(c, fn, "seed[%zu] = %g for the %s %s is not finite", k, seed[k],
                             adjoint ? "unknown" : "known",
                             core_variable_name(adjoint ? unknowns[k] : knowns[k]));
    return CORE_OK;
}

int core_directional_derivative(CoreInstance *c, const char *fn, const unsigned unknowns[],
                                size_t nu, const unsigned knowns[], size_t nk,
                                const double seed[], double out[]) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if ((nk && !seed) || (nu && !out)) return core_fail(c, fn, "NULL argument");
    const int st = check_refs(c, fn, unknowns, nu, knowns, nk, seed, 0);
    if (st != CORE_OK) return st;
    Partials p;
    partials_of(c, &p);
    double row[MAX_KNOWNS];
    for (size_t i = 0; i < nu; ++i) { /* out_i = sum_j dz_i/dx_j seed_j */
        row_of(c, &p, unknowns[i], row);
        double s = 0.0;
        for (size_t j = 0; j < nk; ++j) s += row[column(&p, knowns[j])] * seed[j];
        if (!isfinite(s)) return core_fail(c, fn, "derivative of %s not finite",
                                           core_variable_name(unknowns[i]));
        out[i] = s;
    }
    return CORE_OK;
}

int core_adjoint_derivative(CoreInstance *c, const char *fn, const unsigned unknowns[],
                            size_t nu, const unsigned knowns[], size_t nk, const double seed[],
                            double out[]) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    /* here the seed runs over the unknowns and out over the knowns */
    if ((nk && !out) || (nu && !seed)) return core_fail(c, fn, "NULL argument");
    const int st = check_refs(c, fn, unknowns, nu, knowns, nk, seed, 1);
    if (st != CORE_OK) return st;
    Partials p;
    partials_of(c, &p);
    double row[MAX_KNOWNS];
    for (size_t j = 0; j < nk; ++j) out[j] = 0.0;
    for (size_t i = 0; i < nu; ++i) { /* out_j = sum_i seed_i dz_i/dx_j */
        row_of(c, &p, unknowns[i], row);
        for (size_t j = 0; j < nk; ++j) out[j] += seed[i] * row[column(&p, knowns[j])];
    }
    for (size_t j = 0; j < nk; ++j)
        if (!isfinite(out[j])) return core_fail(c, fn, "adjoint derivative of %s not finite",
                                                core_variable_name(knowns[j]));
    return CORE_OK;
}
