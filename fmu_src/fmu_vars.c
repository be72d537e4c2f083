/*
 * The FMU's variables: the table of value references (VARS, one row per variable: name, type,
 * kind, where it is stored in ModelData or which getter computes it, and its valid range), and the
 * FMI calls on them: core_get, core_set, core_set_input_derivatives (fmu_core.h), called by the
 * glue (fmi2.c, fmi3.c). The snapshot unit (fmu_snapshot.c) checks restored values against
 * the same ranges (fmu_vars.h). What a computed value is physically is the model's (model.h).
 */
#include "fmu_vars.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define NO_FIELD ((size_t)-1)
#define FIELD(f) offsetof(ModelData, f)

/* The getters of computed values (and of inputs, read back as their value now, a ramp given by
 * input derivatives included): the model computes them at the instance's local time. */
static double get_in_contact(const CoreInstance *c) { return model_in_contact(&c->m); }
static double get_J_uu(const CoreInstance *c) { return model_sensitivity(&c->m, 0); }
static double get_J_uv(const CoreInstance *c) { return model_sensitivity(&c->m, 1); }
static double get_J_vu(const CoreInstance *c) { return model_sensitivity(&c->m, 2); }
static double get_J_vv(const CoreInstance *c) { return model_sensitivity(&c->m, 3); }
static double get_S_u(const CoreInstance *c) { return model_sensitivity(&c->m, 4); }
static double get_S_v(const CoreInstance *c) { return model_sensitivity(&c->m, 5); }
static double get_der_u(const CoreInstance *c) {
    return model_derivative(&c->m, core_local_tau(c), 0);
}
static double get_der_v(const CoreInstance *c) {
    return model_derivative(&c->m, core_local_tau(c), 1);
}
static double get_indicator(const CoreInstance *c) {
    return model_wall_indicator(&c->m, core_local_tau(c));
}
static double get_time(const CoreInstance *c) { return core_time(c); }
static double get_contact_force(const CoreInstance *c) {
    return model_contact_output_now(&c->m, core_local_tau(c), c->inputs_changed && !c->is_me);
}
static double get_F_ext(const CoreInstance *c) {
    return model_external_force(&c->m, core_local_tau(c));
}
static double get_u_wall(const CoreInstance *c) {
    return model_wall_position(&c->m, core_local_tau(c));
}
static double get_v_wall(const CoreInstance *c) { return c->m.v_wall; }

/* Valid ranges: chosen so that every derived quantity (F_g, kappa, the forcing, the wall
 * force) stays finite with many orders of magnitude to spare; README "Valid ranges". */
static const VarDef VARS[] = {
#include "variables_table.inc" /* generated from fmu_src/variables.py */
};
#define N_VARS (sizeof VARS / sizeof VARS[0])

const VarDef *vars_table(size_t *n) {
    *n = N_VARS;
    return VARS;
}

const VarDef *vars_find(const CoreInstance *c, unsigned vr) {
    for (size_t i = 0; i < N_VARS; ++i)
        if (VARS[i].vr == vr) return VARS[i].fmi3_only && !c->fmi3 ? NULL : &VARS[i];
    return NULL;
}

const char *core_variable_name(unsigned vr) {
    for (size_t i = 0; i < N_VARS; ++i)
        if (VARS[i].vr == vr) return VARS[i].name;
    return "?";
}

static const char *const TYPE_NAMES[] = {"Real", "Integer", "Boolean"};

int vars_settable(const VarDef *d) {
    return d->kind == K_FIXED || d->kind == K_TUNABLE || d->kind == K_INPUT;
}

const char *vars_check_value(const VarDef *d, double x, char *buf, size_t n) {
    if (!isfinite(x)) return "must be a finite number";
    if (d->type != VT_REAL && x != floor(x)) return "must be an integer";
    const int below = d->lo_open ? !(x > d->lo) : !(x >= d->lo);
    if (below || !(x <= d->hi)) {
        snprintf(buf, n, "must lie in %c%g, %g]", d->lo_open ? '(' : '[', d->lo, d->hi);
        return buf;
    }
    return NULL;
}

double vars_field_get(const ModelData *m, const VarDef *d) {
    const char *p = (const char *)m + d->off;
    if (d->type == VT_REAL) {
        double x;
        memcpy(&x, p, sizeof x);
        return x;
    }
    int i;
    memcpy(&i, p, sizeof i);
    return i;
}

static void field_set(ModelData *m, const VarDef *d, double x) {
    char *p = (char *)m + d->off;
    if (d->type == VT_REAL) {
        memcpy(p, &x, sizeof x);
    } else {
        const int i = (int)x;
        memcpy(p, &i, sizeof i);
    }
}

int core_get(CoreInstance *c, const char *fn, CoreVarType t, const unsigned vr[], size_t n,
             double out[]) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (n > 0 && (!vr || !out)) return core_fail(c, fn, "NULL argument");
    CoreInstance buf;
    const CoreInstance *v = core_view(c, &buf);
    for (size_t i = 0; i < n; ++i) {
        const VarDef *d = vars_find(c, vr[i]);
        if (!d || d->type != t)
            return core_fail(c, fn, "value reference %u is not a%s %s variable", vr[i],
                             t == VT_INTEGER ? "n" : "", TYPE_NAMES[t]);
        out[i] = d->get ? d->get(v) : vars_field_get(&v->m, d);
    }
    return CORE_OK;
}

int core_set(CoreInstance *c, const char *fn, CoreVarType t, const unsigned vr[], size_t n,
             const double in[]) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (n > 0 && (!vr || !in)) return core_fail(c, fn, "NULL argument");
    for (size_t i = 0; i < n; ++i) {
        const VarDef *d = vars_find(c, vr[i]);
        if (!d || d->type != t || !vars_settable(d))
            return core_fail(c, fn, "value reference %u is not a settable %s variable", vr[i],
                             TYPE_NAMES[t]);
        const int early = (c->state & (ST_INSTANTIATED | ST_INIT)) != 0;
        if (!early && !(d->kind == K_INPUT ||
                        (d->kind == K_TUNABLE && (c->state & c->tunable_states))))
            return core_fail(c, fn, "%s (value reference %u) cannot be set now: only sigma is "
                             "tunable after initialisation", d->name, vr[i]);
        char buf[200];
        const char *why = vars_check_value(d, in[i], buf, sizeof buf);
        /* a value valid alone may still overflow a derived quantity of the running model */
        ModelData trial;
        memcpy(&trial, &c->m, sizeof trial);
        if (!why && d->kind != K_INPUT) {
            field_set(&trial, d, in[i]);
            model_update_derived(&trial);
            if (!early) why = model_check_derived(&trial, buf, sizeof buf);
        }
        if (why) {
            if (t == VT_REAL)
                return core_fail(c, fn, "%s = %g rejected: %s (value kept at its previous "
                                 "setting)", d->name, in[i], why);
            return core_fail(c, fn, "%s = %.17g rejected: %s", d->name, in[i], why);
        }
        if (d->kind == K_INPUT) {
            const double tau = core_local_tau(c);
            const double before = d->get(c);
            model_rebase_inputs(&c->m, tau);
            field_set(&c->m, d, in[i]);
            /* a jump: in Co-Simulation between steps; in Model Exchange only in Event Mode (the
             * standards let an importer change inputs discontinuously only there; in
             * Continuous-Time Mode an input is a continuous signal) */
            if (in[i] != before && !early && (!c->is_me || c->state == ST_EVENT)) {
                c->inputs_changed = 1;
                if (!c->is_me) c->st.clk.restart = 1; /* the right-hand side changed here */
            }
        } else {
            memcpy(&c->m, &trial, sizeof trial);
            /* a new sigma changes the right-hand side from now on: CVODE restarts here */
            if (c->state & ST_RUN) c->st.clk.restart = 1;
        }
    }
    return CORE_OK;
}

int core_set_input_derivatives(CoreInstance *c, const char *fn, const unsigned vr[], size_t n,
                               const int order[], const double value[]) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (c->is_me) return core_fail(c, fn, "a Model Exchange instance has no input derivatives");
    if (n > 0 && (!vr || !order || !value)) return core_fail(c, fn, "NULL argument");
    int status = CORE_OK;
    for (size_t i = 0; i < n; ++i) {
        if (vr[i] != VR_F_EXT && vr[i] != VR_U_WALL && vr[i] != VR_V_WALL)
            return core_fail(c, fn, "value reference %u is not a Real input", vr[i]);
        if (order[i] < 1) return core_fail(c, fn, "order %d: must be >= 1", order[i]);
        if (!isfinite(value[i]))
            return core_fail(c, fn, "derivative of order %d of %s = %g rejected: not finite",
                             order[i], core_variable_name(vr[i]), value[i]);
        if (vr[i] == VR_V_WALL) { /* the wall moves at constant velocity over a step */
            if (value[i] != 0.0) {
                core_log(c, CORE_WARNING, "logStatusWarning", "%s: derivative of order %d of "
                         "v_wall ignored (the wall is unaccelerated over a step)", fn, order[i]);
                status = CORE_WARNING;
            }
            continue;
        }
        const double bound = vr[i] == VR_F_EXT ? MODEL_MAX_DF_EXT : MODEL_MAX_DU_WALL;
        if (!isfinite(value[i]) || !(fabs(value[i]) <= bound))
            return core_fail(c, fn, "d%s/dt = %g rejected: must be finite with |.| <= %g",
                             core_variable_name(vr[i]), value[i], bound);
        if (order[i] > 1) { /* the inputs are integrated as linear ramps: order 1 is used */
            if (value[i] != 0.0)
                core_log(c, CORE_WARNING, "logStatusWarning", "%s: derivative of order %d of "
                         "%s ignored (maxInputDerivativeOrder is 1)", fn, order[i],
                         core_variable_name(vr[i]));
            status = value[i] != 0.0 ? CORE_WARNING : status;
            continue;
        }
        model_rebase_inputs(&c->m, core_local_tau(c));
        double *slot = vr[i] == VR_F_EXT ? &c->m.dF_ext : &c->m.du_wall;
        if (*slot != value[i]) {
            *slot = value[i];
            if (c->state == ST_STEP) {
                c->inputs_changed = 1;
                c->st.clk.restart = 1;
            }
        }
    }
    return status;
}
