/*
 * ImpactOscillator physics: parameters, right-hand side, Jacobian, event indicators and the
 * jumps at the wall. Equation numbers refer to Molenaar, de Weger & van de Water (2001) and to
 * ../shared/paper/FORMULAS.md.
 */
#include "model.h"

#include <math.h>
#include <stdio.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Chatter on the rigid wall: once an impact leaves less than this velocity (relative to the
 * incoming one, floored at 1) and the wall force pushes inwards, the impacts would accumulate
 * in finite time; the mass is taken to stick instead (Zeno truncation). */
static const double STICK_VELOCITY = 1e-9;

/* Where an event leaves the mass on the wall, u is put a hair on the side of its new mode rather
 * than at 0: CVODE deactivates a root function that is exactly zero at the restart and takes its
 * reference sign only after the first step, so a contact or flight shorter than that first step
 * (chatter, grazing) would be stepped over. */
static const double ON_WALL = 1e-300;

static const char *const NAMES[VR_COUNT] = {
    "nu", "Omega", "sigma", "r", "Gamma", "wall", "u0", "v0", "rtol", "atol",
    "F_g", "phi", "kappa", "u", "v", "impacts", "in_contact",
    "contact", "alpha_hc", "der(u)", "der(v)", "wall_indicator", "time",
};

const char *model_variable_name(int vr) {
    return (vr >= 0 && vr < VR_COUNT) ? NAMES[vr] : "?";
}

void model_set_defaults(ModelData *m) {
    /* The paper's Figure 9 case: (alpha, gamma) = (0.99, 0.01), r = 0.9, Gamma = 10. */
    m->nu = 4.605170185988091;
    m->Omega = 0.3059238689620112;
    m->sigma = 0.2;
    m->r = 0.9;
    m->Gamma = 10.0;
    m->wall = WALL_COMPLIANT;
    /* Start at rest, u = -1: valid for every wall model. */
    m->u0 = -1.0;
    m->v0 = 0.0;
    m->rtol = 1e-12;
    m->atol = 1e-14;
    m->contact = CONTACT_LINEAR;
    /* Hunt-Crossley: an impact at speed v_in leaves roughly r ~ 1 - (2/3) alpha v_in, so 0.15
     * gives r ~ 0.9 at v_in ~ 1 */
    m->alpha_hc = 0.15;
    /* CVODE needs >= 20 steps per unit time (its maximal step 0.05) and ~100-1000 at the
     * defaults; chatter ends in sticking after ~100 impacts. */
    m->max_events_per_time = 1e5;
    m->max_steps_per_time = 2e5;
    m->mode = MODE_FREE;
    m->impacts = 0;
    model_update_derived(m);
    m->u = m->u0;
    m->v = m->v0;
}

void model_update_derived(ModelData *m) {
    const double w2 = 4.0 * M_PI * M_PI;
    m->Omega2 = m->Omega * m->Omega;
    /* (5): F_g = sqrt((Omega^2 - 4 pi^2)^2 + 4 pi^2 nu^2), phi = arccos((Omega^2 - 4 pi^2)/F_g) */
    m->F_g = hypot(m->Omega2 - w2, 2.0 * M_PI * m->nu);
    m->phi = (m->F_g > 0.0) ? acos((m->Omega2 - w2) / m->F_g) : 0.0;
    m->kappa2 = m->Gamma * m->Omega2;
    m->kappa = sqrt(fabs(m->kappa2));
}

const char *model_check_real(int vr, double x) {
    if (!isfinite(x)) return "must be a finite number";
    switch (vr) {
    case VR_NU: return x < 0.0 ? "must be >= 0 (damping)" : NULL;
    case VR_OMEGA: return x <= 0.0 ? "must be > 0" : NULL;
    case VR_SIGMA: return x <= -1.0 ? "must be > -1 (forcing amplitude (1+sigma) F_g > 0)" : NULL;
    case VR_R: return (x < 0.0 || x > 1.0) ? "must lie in [0, 1]" : NULL;
    case VR_GAMMA: return x < 0.0 ? "must be >= 0" : NULL;
    case VR_U0: case VR_V0: return NULL;
    case VR_RTOL: return (x <= 0.0 || x >= 1.0) ? "must lie in (0, 1)" : NULL;
    case VR_ATOL: return x <= 0.0 ? "must be > 0" : NULL;
    case VR_HC_ALPHA: return x < 0.0 ? "must be >= 0 (dissipation)" : NULL;
    default: return "is not a settable Real variable";
    }
}

const char *model_check_integer(int vr, int x) {
    if (vr == VR_CONTACT)
        return (x < CONTACT_LINEAR || x > CONTACT_HUNT_CROSSLEY)
                   ? "must be 0 (linear), 1 (Hertz) or 2 (Hunt-Crossley)" : NULL;
    if (vr != VR_WALL) return "is not a settable Integer variable";
    return (x < WALL_NONE || x > WALL_RIGID) ? "must be 0 (none), 1 (compliant) or 2 (rigid)"
                                             : NULL;
}

const char *model_check_consistency(const ModelData *m, char *buf, size_t n) {
    if (m->wall == WALL_COMPLIANT && !(m->Gamma > 0.0)) {
        snprintf(buf, n, "Gamma = %g: a compliant wall needs Gamma > 0", m->Gamma);
        return buf;
    }
    if (m->wall == WALL_RIGID && (m->u0 > 0.0 || (m->u0 == 0.0 && m->v0 > 0.0))) {
        snprintf(buf, n, "u0 = %g, v0 = %g starts inside the rigid wall (need u0 < 0, or u0 = 0 "
                 "with v0 <= 0)", m->u0, m->v0);
        return buf;
    }
    return NULL;
}

static double forcing(const ModelData *m, double tau) {
    /* tau is local time; the origin is an integer, so this is cos(2 pi t + phi) to full precision */
    return (1.0 + m->sigma) * m->F_g * cos(2.0 * M_PI * tau + m->phi);
}

double model_wall_force(const ModelData *m, double tau) {
    /* u = v = 0: the spring pulls back with Omega^2, the drive pushes with forcing(tau) */
    return forcing(m, tau) - m->Omega2;
}

void model_initialize_state(ModelData *m, double tau0) {
    m->u = m->u0;
    m->v = m->v0;
    m->impacts = 0;
    m->mode = MODE_FREE;
    if (m->wall == WALL_COMPLIANT && (m->u0 > 0.0 || (m->u0 == 0.0 && m->v0 > 0.0)))
        m->mode = MODE_CONTACT; /* a start inside the wall is a state, not an entry: no jump */
    else if (m->wall == WALL_RIGID && m->u0 == 0.0 && m->v0 == 0.0 &&
             model_wall_force(m, tau0) > 0.0)
        m->mode = MODE_STICK;
}

double model_contact_force(const ModelData *m, double u, double v) {
    if (m->contact == CONTACT_LINEAR) return m->kappa2 * u; /* (40); smooth across u = 0 */
    if (!(u > 0.0)) return 0.0; /* Hertz laws: C^1 continuation by 0 outside the wall */
    const double h = m->kappa2 * u * sqrt(u); /* kappa^2 u^{3/2} */
    return m->contact == CONTACT_HERTZ ? h : h * (1.0 + m->alpha_hc * v);
}

void model_derivatives(const ModelData *m, double tau, const double y[2], double dy[2]) {
    if (m->mode == MODE_STICK) {
        dy[0] = 0.0;
        dy[1] = 0.0;
        return;
    }
    double k = m->Omega2 * (y[0] + 1.0);
    if (m->mode == MODE_CONTACT) k += model_contact_force(m, y[0], y[1]); /* the wall */
    dy[0] = y[1];
    dy[1] = forcing(m, tau) - m->nu * y[1] - k;
}

void model_jacobian(const ModelData *m, const double y[2], double J[2][2]) {
    if (m->mode == MODE_STICK) {
        J[0][0] = J[0][1] = J[1][0] = J[1][1] = 0.0;
        return;
    }
    J[0][0] = 0.0;
    J[0][1] = 1.0;
    J[1][0] = -m->Omega2;
    J[1][1] = -m->nu;
    if (m->mode != MODE_CONTACT) return;
    if (m->contact == CONTACT_LINEAR) {
        J[1][0] -= m->kappa2;
    } else if (y[0] > 0.0) {
        const double s = sqrt(y[0]);
        const double damp = m->contact == CONTACT_HUNT_CROSSLEY ? m->alpha_hc : 0.0;
        J[1][0] -= 1.5 * m->kappa2 * s * (1.0 + damp * y[1]);
        J[1][1] -= m->kappa2 * y[0] * s * damp;
    }
}

void model_event_indicators(const ModelData *m, double tau, const double y[2],
                            double g[MODEL_N_EVENTS]) {
    if (m->wall == WALL_NONE) {
        g[0] = g[1] = 1.0; /* never crosses */
        return;
    }
    if (m->mode == MODE_STICK) {
        g[0] = model_wall_force(m, tau); /* release when it stops pushing */
        g[1] = 1.0;
        return;
    }
    g[0] = y[0]; /* the wall u = 0 */
    /* The grazing guard: a contact that enters and leaves within one solver step leaves u < 0
     * at both step ends, but its turning point (v = 0) is still bracketed. */
    g[1] = y[1];
}

void model_root_directions(const ModelData *m, int dir[MODEL_N_EVENTS]) {
    switch (m->mode) {
    case MODE_CONTACT: dir[0] = -1; dir[1] = +1; break; /* leaving; minimum of u inside */
    case MODE_STICK: dir[0] = -1; dir[1] = 0; break;    /* force falls below zero */
    default: dir[0] = +1; dir[1] = -1; break;           /* entering; maximum of u outside */
    }
}

int model_missed_crossing(const ModelData *m, const double y[2]) {
    if (m->wall == WALL_NONE) return 0;
    if (m->mode == MODE_FREE) return y[0] > 0.0;
    if (m->mode == MODE_CONTACT) return y[0] < 0.0;
    return 0;
}

int model_release_now(ModelData *m, double tau) {
    if (m->mode == MODE_STICK && model_wall_force(m, tau) <= 0.0) {
        m->mode = MODE_FREE;
        return 1;
    }
    return 0;
}

EventResult model_event_update(ModelData *m, double tau, double y[2], int which) {
    if (which == 1) return EVENT_NONE; /* a turning point on the right side: nothing happens */

    switch (m->mode) {
    case MODE_FREE:
        /* entering the wall: u = 0 (the root), v > 0 */
        m->impacts += 1;
        if (m->wall == WALL_COMPLIANT) {
            /* footnote 2: the linear wall passes the mass on with v -> r v. The Hertz laws
             * enter continuously (Hunt-Crossley dissipates inside the wall instead). */
            if (m->contact == CONTACT_LINEAR) y[1] *= m->r;
            y[0] = ON_WALL;
            m->mode = MODE_CONTACT;
        } else {
            const double vc = y[1];
            y[0] = -ON_WALL;
            y[1] = -m->r * vc; /* (11) */
            if (fabs(y[1]) <= STICK_VELOCITY * fmax(1.0, fabs(vc)) &&
                model_wall_force(m, tau) > 0.0) {
                y[0] = 0.0;
                y[1] = 0.0;
                m->mode = MODE_STICK;
            }
        }
        return EVENT_JUMP;
    case MODE_CONTACT:
        y[0] = -ON_WALL; /* leaving the compliant wall: no jump in v */
        m->mode = MODE_FREE;
        return EVENT_JUMP;
    case MODE_STICK:
        y[0] = -ON_WALL;
        y[1] = 0.0;
        m->mode = MODE_FREE;
        return EVENT_JUMP;
    }
    return EVENT_NONE;
}

int model_is_tunable(int vr) { return vr == VR_SIGMA; }

const char *model_get_real(const ModelData *m, int vr, double *x) {
    switch (vr) {
    case VR_NU: *x = m->nu; break;
    case VR_OMEGA: *x = m->Omega; break;
    case VR_SIGMA: *x = m->sigma; break;
    case VR_R: *x = m->r; break;
    case VR_GAMMA: *x = m->Gamma; break;
    case VR_U0: *x = m->u0; break;
    case VR_V0: *x = m->v0; break;
    case VR_RTOL: *x = m->rtol; break;
    case VR_ATOL: *x = m->atol; break;
    case VR_F_G: *x = m->F_g; break;
    case VR_PHI: *x = m->phi; break;
    case VR_KAPPA: *x = m->kappa; break;
    case VR_HC_ALPHA: *x = m->alpha_hc; break;
    case VR_U: *x = m->u; break;
    case VR_V: *x = m->v; break;
    default: return "is not a Real variable";
    }
    return NULL;
}

const char *model_get_integer(const ModelData *m, int vr, int *x) {
    switch (vr) {
    case VR_WALL: *x = m->wall; break;
    case VR_CONTACT: *x = m->contact; break;
    case VR_IMPACTS: *x = m->impacts; break;
    default: return "is not an Integer variable";
    }
    return NULL;
}

const char *model_get_boolean(const ModelData *m, int vr, int *x) {
    if (vr != VR_IN_CONTACT) return "is not a Boolean variable";
    *x = m->mode != MODE_FREE;
    return NULL;
}

const char *model_set_real(ModelData *m, int vr, double x) {
    const char *why = model_check_real(vr, x);
    if (why) return why;
    switch (vr) {
    case VR_NU: m->nu = x; break;
    case VR_OMEGA: m->Omega = x; break;
    case VR_SIGMA: m->sigma = x; break;
    case VR_R: m->r = x; break;
    case VR_GAMMA: m->Gamma = x; break;
    case VR_U0: m->u0 = x; break;
    case VR_V0: m->v0 = x; break;
    case VR_RTOL: m->rtol = x; break;
    case VR_ATOL: m->atol = x; break;
    case VR_HC_ALPHA: m->alpha_hc = x; break;
    }
    model_update_derived(m);
    return NULL;
}

const char *model_set_integer(ModelData *m, int vr, int x) {
    const char *why = model_check_integer(vr, x);
    if (why) return why;
    if (vr == VR_CONTACT) m->contact = x;
    else m->wall = x;
    return NULL;
}

int model_me_event_update(ModelData *m, double tau, double y[2]) {
    if (model_release_now(m, tau)) { /* sticking: the holding force has gone */
        y[0] = 0.0;
        y[1] = 0.0;
        return 1;
    }
    if (m->wall == WALL_NONE || m->mode == MODE_STICK) return 0;
    /* the importer stops on the far side of g0 = u = 0 (or on it) */
    const int crossed = m->mode == MODE_FREE ? (y[0] > 0.0 || (y[0] == 0.0 && y[1] > 0.0))
                                             : (y[0] < 0.0 || (y[0] == 0.0 && y[1] < 0.0));
    if (!crossed) return 0;
    model_event_update(m, tau, y, 0);
    return 1;
}

const char *model_get_real_at(const ModelData *m, double tau, int vr, double *x) {
    if (vr == VR_DER_U || vr == VR_DER_V) {
        const double y[2] = {m->u, m->v};
        double dy[2];
        model_derivatives(m, tau, y, dy);
        *x = dy[vr == VR_DER_V];
        return NULL;
    }
    if (vr == VR_WALL_INDICATOR) {
        const double y[2] = {m->u, m->v};
        double g[MODEL_N_EVENTS];
        model_event_indicators(m, tau, y, g);
        *x = g[0];
        return NULL;
    }
    return model_get_real(m, vr, x);
}
