/*
 * Exact partial derivatives through the FMI API: core_directional_derivative (fmi2 and
 * fmi3GetDirectionalDerivative) and core_adjoint_derivative (fmi3GetAdjointDerivative), called by
 * the glue (fmi2_cs.c, fmi3.c) in every interface. The partials themselves are the model's
 * (model_partials: the right-hand side of the contact mode now, differentiated); this unit maps
 * value references to its rows and columns and forms J s (directional) or s^T J (adjoint).
 *
 * Knowns: the continuous states u, v and the inputs F_ext, u_wall (FMI 2.0 3.2.1 and 4.2.1, FMI 3.0
 * 2.2.11: states and inputs; the parameters are no knowns here). Unknowns: der(u), der(v), the
 * outputs and, in FMI 3.0, the event indicator. The outputs u and v are the states themselves;
 * the discrete outputs (impacts, in_contact, v_impact, t_impact, J_*, S_*) change only at events
 * and at step ends, so their partials are 0 (their ModelStructure dependencies are empty).
 */
#include <math.h>
#include <string.h>

#include "fmu_vars.h"

/* The column of known vr, or -1. */
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

/* The partials now: P for the right-hand side and the indicator (what their getters read), Pout
 * for F_contact, which in Co-Simulation feeds through from an input that jumped (its getter
 * reports the state the input-jump rule gives: model_contact_output_now). */
static void partials_now(const CoreInstance *c, double P[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS],
                         double Pout[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS]) {
    CoreInstance buf;
    c = core_view(c, &buf); /* Initialization Mode: at the state the start values give */
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

/* CORE_OK if every known and unknown is one (else the error, naming the first that is not). */
static int check_refs(CoreInstance *c, const char *fn, const unsigned unknowns[], size_t nu,
                      const unsigned knowns[], size_t nk) {
    if ((nu && !unknowns) || (nk && !knowns)) return core_fail(c, fn, "NULL argument");
    for (size_t j = 0; j < nk; ++j)
        if (known_column(knowns[j]) < 0)
            return core_fail(c, fn, "value reference %u (%s) is not a known: the knowns are the "
                             "states u, v and the inputs F_ext, u_wall, v_wall", knowns[j],
                             core_variable_name(knowns[j]));
    double P[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS], row[MODEL_N_KNOWNS];
    memset(P, 0, sizeof P);
    for (size_t i = 0; i < nu; ++i)
        if (!unknown_row(c, unknowns[i], P, P, row))
            return core_fail(c, fn, "value reference %u (%s) is not an unknown: the unknowns are "
                             "der(u), der(v), the outputs%s", unknowns[i],
                             core_variable_name(unknowns[i]),
                             c->fmi3 ? " and the event indicator wall_indicator" : "");
    return CORE_OK;
}

int core_directional_derivative(CoreInstance *c, const char *fn, const unsigned unknowns[],
                                size_t nu, const unsigned knowns[], size_t nk,
                                const double seed[], double out[]) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if ((nk && !seed) || (nu && !out)) return core_fail(c, fn, "NULL argument");
    const int st = check_refs(c, fn, unknowns, nu, knowns, nk);
    if (st != CORE_OK) return st;
    double P[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS], Pout[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS];
    double row[MODEL_N_KNOWNS];
    partials_now(c, P, Pout);
    for (size_t i = 0; i < nu; ++i) { /* out_i = sum_j dz_i/dx_j seed_j */
        unknown_row(c, unknowns[i], P, Pout, row);
        double s = 0.0;
        for (size_t j = 0; j < nk; ++j) s += row[known_column(knowns[j])] * seed[j];
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
    const int st = check_refs(c, fn, unknowns, nu, knowns, nk);
    if (st != CORE_OK) return st;
    double P[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS], Pout[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS];
    double row[MODEL_N_KNOWNS];
    partials_now(c, P, Pout);
    for (size_t j = 0; j < nk; ++j) out[j] = 0.0;
    for (size_t i = 0; i < nu; ++i) { /* out_j = sum_i seed_i dz_i/dx_j */
        unknown_row(c, unknowns[i], P, Pout, row);
        for (size_t j = 0; j < nk; ++j) out[j] += seed[i] * row[known_column(knowns[j])];
    }
    for (size_t j = 0; j < nk; ++j)
        if (!isfinite(out[j])) return core_fail(c, fn, "adjoint derivative of %s not finite",
                                                core_variable_name(knowns[j]));
    return CORE_OK;
}
