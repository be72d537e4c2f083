/*
 * ImpactOscillator physics: parameters, right-hand side, Jacobian, event indicators and the
 * jumps at the wall. Equation numbers refer to Molenaar, de Weger & van de Water (2001) and to
 * docs/theory.md.
 */
#include "model.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Chatter on the rigid wall: once an impact leaves less than this velocity (relative to the
 * incoming one, floored at 1) and the wall force pushes inwards, the impacts would accumulate
 * in finite time; the mass is taken to stick instead (Zeno truncation). */
static const double STICK_VELOCITY = 1e-9;
/* ... or once a rebound's flight would rise less than this many ulps of the wall position. */
static const double STICK_ULPS = 16.0;

/* Where an event leaves the mass on the wall, u is put a hair on the side of its new mode rather
 * than at 0: CVODE deactivates a root function that is exactly zero at the restart and takes its
 * reference sign only after the first step, so a contact or flight shorter than that first step
 * (chatter, grazing) would be stepped over. */
static const double ON_WALL = 1e-300;

void model_set_defaults(ModelData *m) {
    /* Every declared start value (the modelDescription's start), from fmu_src/variables.py. */
#include "model_defaults.inc"
    /* What no variable declares: the discrete state, the input ramps and the origin of local
     * time, the last impact (0 before the first). */
    m->mode = MODE_FREE;
    m->impacts = 0;
    m->dF_ext = m->du_wall = m->in_tau = 0.0;
    m->v_impact = m->t_impact = 0.0;
    m->origin = 0.0;
    m->sJ[0][0] = m->sJ[1][1] = 1.0; /* J = I, S = 0: nothing integrated yet */
    m->sJ[0][1] = m->sJ[1][0] = m->sS[0] = m->sS[1] = 0.0;
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

const char *model_check_consistency(const ModelData *m, char *buf, size_t n) {
    if (m->wall == WALL_COMPLIANT && !(m->Gamma > 0.0)) {
        snprintf(buf, n, "Gamma = %g: a compliant wall needs Gamma > 0", m->Gamma);
        return buf;
    }
    if (m->solver == SOLVER_CLOSED_FORM && m->wall == WALL_COMPLIANT &&
        m->contact != CONTACT_LINEAR) {
        snprintf(buf, n, "solver = 1 (closed form) needs the linear contact law, not contact = %d "
                 "(%s): use solver = 0 (CVODE)", m->contact,
                 m->contact == CONTACT_HERTZ ? "Hertz" : "Hunt-Crossley");
        return buf;
    }
    const double w = m->u_wall;
    if (m->wall == WALL_RIGID && (m->u0 > w || (m->u0 == w && m->v0 > model_wall_velocity(m)))) {
        snprintf(buf, n, "u0 = %g, v0 = %g starts inside the rigid wall at u_wall = %g (need "
                 "u0 < u_wall, or u0 = u_wall moving away from it)", m->u0, m->v0, w);
        return buf;
    }
    /* derived quantities that could overflow although each parameter is in its range */
    if (!(m->kappa <= 1e8)) {
        snprintf(buf, n, "kappa = sqrt(Gamma) Omega = %g exceeds 1e8 (Gamma = %g, Omega = %g)",
                 m->kappa, m->Gamma, m->Omega);
        return buf;
    }
    const double amp = (1.0 + m->sigma) * m->F_g;
    if (!isfinite(m->F_g) || !isfinite(m->phi) || !(fabs(amp) <= 1e15)) {
        snprintf(buf, n, "forcing amplitude (1 + sigma) F_g = %g out of range (|.| <= 1e15)",
                 amp);
        return buf;
    }
    return NULL;
}

static double forcing(const ModelData *m, double tau) {
    /* tau is local time; the origin is an integer, so this is cos(2 pi t + phi) to full precision */
    return (1.0 + m->sigma) * m->F_g * cos(2.0 * M_PI * tau + m->phi);
}

/* --- ports ------------------------------------------------------------------------------- */
/* With held inputs (no input derivatives) every formula below reduces, bit for bit, to the
 * wall at 0 and no external force: w = 0.0 and F = 0.0 enter as exact additions of zero. */

double model_wall_position(const ModelData *m, double tau) {
    return m->du_wall == 0.0 ? m->u_wall : m->u_wall + m->du_wall * (tau - m->in_tau);
}

/* The wall's velocity: the ramp's slope while one runs (an FMI 2.0 input derivative, or v_wall
 * over a Co-Simulation step), else the input v_wall. With neither (0 and 0) it is 0.0, the value
 * every formula had before the wall could move. */
double model_wall_velocity(const ModelData *m) {
    return m->du_wall != 0.0 ? m->du_wall : m->v_wall;
}

double model_external_force(const ModelData *m, double tau) {
    return m->dF_ext == 0.0 ? m->F_ext : m->F_ext + m->dF_ext * (tau - m->in_tau);
}

void model_shift_time(ModelData *m, double k) {
    m->origin += k;
    m->in_tau -= k;
}

/* A point a hair on one side of the wall at w: ON_WALL away from 0, the next double away from
 * any other w (w + 1e-300 would round back to w, and the wall indicator would be exactly 0). */
static double beside_wall(double w, double side) {
    if (w == 0.0) return side * ON_WALL;
    return nextafter(w, side > 0.0 ? INFINITY : -INFINITY);
}

double model_wall_force(const ModelData *m, double tau) {
    /* On the wall (u = w, v = w', w'' = 0): the spring pulls back with Omega^2 (w + 1), the drive
     * and F_ext push, the damper acts on v = w'. With w = w' = F_ext = 0: forcing - Omega^2. */
    return forcing(m, tau) + model_external_force(m, tau) - m->nu * model_wall_velocity(m) -
           m->Omega2 * (model_wall_position(m, tau) + 1.0);
}

void model_initialize_state(ModelData *m, double tau0) {
    const double w = model_wall_position(m, tau0), dw = model_wall_velocity(m);
    m->u = m->u0;
    m->v = m->v0;
    m->impacts = 0;
    m->v_impact = 0.0;
    m->t_impact = 0.0;
    m->mode = MODE_FREE;
    /* at rest on the wall (relative to it) the net force decides, as in mapcheck.exact */
    const int rest_pushed = m->u0 == w && m->v0 == dw && model_wall_force(m, tau0) > 0.0;
    if (m->wall == WALL_COMPLIANT && (m->u0 > w || (m->u0 == w && m->v0 > dw) || rest_pushed))
        m->mode = MODE_CONTACT; /* a start inside the wall is a state, not an entry: no jump */
    else if (m->wall == WALL_RIGID && rest_pushed)
        m->mode = MODE_STICK;
}

double model_contact_force(const ModelData *m, double d, double dv) {
    if (m->contact == CONTACT_LINEAR) return m->kappa2 * d; /* (40); smooth across d = 0 */
    if (!(d > 0.0)) return 0.0; /* Hertz laws: C^1 continuation by 0 outside the wall */
    const double h = m->kappa2 * d * sqrt(d); /* kappa^2 d^{3/2} */
    return m->contact == CONTACT_HERTZ ? h : h * (1.0 + m->alpha_hc * dv);
}

double model_contact_output(const ModelData *m, double tau) {
    switch (m->mode) {
    case MODE_CONTACT:
        return model_contact_force(m, m->u - model_wall_position(m, tau),
                                   m->v - model_wall_velocity(m));
    case MODE_STICK: return model_wall_force(m, tau); /* what holds the mass on the wall */
    default: return 0.0;
    }
}

void model_derivatives(const ModelData *m, double tau, const double y[2], double dy[2]) {
    if (m->mode == MODE_STICK) {
        dy[0] = model_wall_velocity(m); /* carried by the wall */
        dy[1] = 0.0;
        return;
    }
    double k = m->Omega2 * (y[0] + 1.0);
    if (m->mode == MODE_CONTACT) /* the wall */
        k += model_contact_force(m, y[0] - model_wall_position(m, tau),
                                 y[1] - model_wall_velocity(m));
    dy[0] = y[1];
    dy[1] = forcing(m, tau) - m->nu * y[1] - k + model_external_force(m, tau);
}

void model_jacobian(const ModelData *m, double tau, const double y[2], double J[2][2]) {
    if (m->mode == MODE_STICK) {
        J[0][0] = J[0][1] = J[1][0] = J[1][1] = 0.0;
        return;
    }
    J[0][0] = 0.0;
    J[0][1] = 1.0;
    J[1][0] = -m->Omega2;
    J[1][1] = -m->nu;
    if (m->mode != MODE_CONTACT) return;
    const double d = y[0] - model_wall_position(m, tau), dv = y[1] - model_wall_velocity(m);
    if (m->contact == CONTACT_LINEAR) {
        J[1][0] -= m->kappa2;
    } else if (d > 0.0) {
        const double s = sqrt(d);
        const double damp = m->contact == CONTACT_HUNT_CROSSLEY ? m->alpha_hc : 0.0;
        J[1][0] -= 1.5 * m->kappa2 * s * (1.0 + damp * dv);
        J[1][1] -= m->kappa2 * d * s * damp;
    }
}

/* d F / d d and d F / d d' of the contact law's force F(d, d') (model_contact_force). */
static void contact_force_partials(const ModelData *m, double d, double dv, double *Fd,
                                   double *Fdv) {
    *Fd = *Fdv = 0.0;
    if (m->contact == CONTACT_LINEAR) {
        *Fd = m->kappa2;
    } else if (d > 0.0) { /* the Hertz laws are C^1 at d = 0: both partials vanish there */
        const double s = sqrt(d);
        const double damp = m->contact == CONTACT_HUNT_CROSSLEY ? m->alpha_hc : 0.0;
        *Fd = 1.5 * m->kappa2 * s * (1.0 + damp * dv);
        *Fdv = m->kappa2 * d * s * damp;
    }
}

void model_partials(const ModelData *m, double tau, double P[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS]) {
    memset(P, 0, sizeof(double) * MODEL_N_UNKNOWNS * MODEL_N_KNOWNS);
    /* w' is v_wall unless an input derivative of u_wall gives the ramp (model_wall_velocity) */
    const double vw = m->du_wall == 0.0 ? 1.0 : 0.0;
    if (m->mode == MODE_STICK) {
        /* carried by the wall: der(u) = w', der(v) = 0 whatever (u, v); the holding force (and the
         * indicator, the same force) is forcing + F_ext - nu w' - Omega^2 (w + 1) */
        P[PU_DER_U][PK_V_WALL] = vw;
        P[PU_F_CONTACT][PK_F_EXT] = P[PU_WALL_INDICATOR][PK_F_EXT] = 1.0;
        P[PU_F_CONTACT][PK_U_WALL] = P[PU_WALL_INDICATOR][PK_U_WALL] = -m->Omega2;
        P[PU_F_CONTACT][PK_V_WALL] = P[PU_WALL_INDICATOR][PK_V_WALL] = -m->nu * vw;
        return;
    }
    /* der(u) = v; der(v) = forcing - nu v - Omega^2 (u + 1) [- F(u - w, v - w')] + F_ext */
    P[PU_DER_U][PK_V] = 1.0;
    P[PU_DER_V][PK_U] = -m->Omega2;
    P[PU_DER_V][PK_V] = -m->nu;
    P[PU_DER_V][PK_F_EXT] = 1.0;
    if (m->wall != WALL_NONE) { /* g0 = u - w (no wall: the constant 1) */
        P[PU_WALL_INDICATOR][PK_U] = 1.0;
        P[PU_WALL_INDICATOR][PK_U_WALL] = -1.0;
    }
    if (m->mode != MODE_CONTACT) return;
    double Fd, Fdv;
    contact_force_partials(m, m->u - model_wall_position(m, tau), m->v - model_wall_velocity(m),
                           &Fd, &Fdv);
    P[PU_DER_V][PK_U] -= Fd;
    P[PU_DER_V][PK_V] -= Fdv;
    P[PU_DER_V][PK_U_WALL] = Fd;
    P[PU_DER_V][PK_V_WALL] = Fdv * vw;
    P[PU_F_CONTACT][PK_U] = Fd;
    P[PU_F_CONTACT][PK_V] = Fdv;
    P[PU_F_CONTACT][PK_U_WALL] = -Fd;
    P[PU_F_CONTACT][PK_V_WALL] = -Fdv * vw;
}

/* The forcing's partials w.r.t. nu, Omega and sigma at local time tau, and F_g's and phi's
 * (rows of d[3][3]: F_g, phi, forcing; columns nu, Omega, sigma). (5): F_g e^{i phi} = a + i b,
 * a = Omega^2 - 4 pi^2, b = 2 pi nu. */
static void forcing_partials(const ModelData *m, double tau, double d[3][3]) {
    const double a = m->Omega2 - 4.0 * M_PI * M_PI, b = 2.0 * M_PI * m->nu, F2 = m->F_g * m->F_g;
    const double da_dOmega = 2.0 * m->Omega, db_dnu = 2.0 * M_PI;
    d[0][0] = b * db_dnu / m->F_g;         /* dF_g/dnu */
    d[0][1] = a * da_dOmega / m->F_g;      /* dF_g/dOmega */
    d[1][0] = a * db_dnu / F2;             /* dphi/dnu: phi = atan2(b, a) */
    d[1][1] = -b * da_dOmega / F2;         /* dphi/dOmega */
    d[0][2] = d[1][2] = 0.0;
    const double th = 2.0 * M_PI * tau + m->phi, amp = 1.0 + m->sigma;
    for (int j = 0; j < 2; ++j)
        d[2][j] = amp * (d[0][j] * cos(th) - m->F_g * sin(th) * d[1][j]);
    d[2][2] = m->F_g * cos(th);
}

void model_initial_partials(const ModelData *m, double tau0,
                            double P[MODEL_N_INIT_UNKNOWNS][MODEL_N_INIT_KNOWNS]) {
    memset(P, 0, sizeof(double) * MODEL_N_INIT_UNKNOWNS * MODEL_N_INIT_KNOWNS);
    double f[3][3];
    forcing_partials(m, tau0, f);
    P[IU_F_G][IK_NU] = f[0][0];
    P[IU_F_G][IK_OMEGA] = f[0][1];
    P[IU_PHI][IK_NU] = f[1][0];
    P[IU_PHI][IK_OMEGA] = f[1][1];
    /* kappa = sqrt(Gamma) Omega (infinite slope in Gamma at Gamma = 0) */
    P[IU_KAPPA][IK_GAMMA] = 0.5 * m->Omega / sqrt(m->Gamma);
    P[IU_KAPPA][IK_OMEGA] = sqrt(m->Gamma);
    P[IU_U][IK_U0] = 1.0;
    P[IU_V][IK_V0] = 1.0;
    /* der(u) = v0, or w' sticking, which needs v0 = w': v0 either way */
    P[IU_DER_U][IK_V0] = 1.0;
    /* w' is v_wall unless an input derivative of u_wall gives the ramp */
    const double vw = m->du_wall == 0.0 ? 1.0 : 0.0;
    const double w = model_wall_position(m, tau0), dw = model_wall_velocity(m);
    if (m->mode == MODE_STICK) { /* der(v) = 0; F_contact: the holding force (model_wall_force) */
        P[IU_F_CONTACT][IK_NU] = f[2][0] - dw;
        P[IU_F_CONTACT][IK_OMEGA] = f[2][1] - 2.0 * m->Omega * (w + 1.0);
        P[IU_F_CONTACT][IK_SIGMA] = f[2][2];
        P[IU_F_CONTACT][IK_F_EXT] = 1.0;
        P[IU_F_CONTACT][IK_U_WALL] = -m->Omega2;
        P[IU_F_CONTACT][IK_V_WALL] = -m->nu * vw;
        return;
    }
    /* der(v) = forcing - nu v0 - Omega^2 (u0 + 1) [- F_c] + F_ext */
    double *dv = P[IU_DER_V];
    dv[IK_NU] = f[2][0] - m->v;
    dv[IK_OMEGA] = f[2][1] - 2.0 * m->Omega * (m->u + 1.0);
    dv[IK_SIGMA] = f[2][2];
    dv[IK_U0] = -m->Omega2;
    dv[IK_V0] = -m->nu;
    dv[IK_F_EXT] = 1.0;
    if (m->mode != MODE_CONTACT) return;
    /* F_c = kappa^2 g(d, d'), d = u0 - w, d' = v0 - w', kappa^2 = Gamma Omega^2 */
    const double d = m->u - w, ddv = m->v - dw;
    double Fd, Fdv;
    contact_force_partials(m, d, ddv, &Fd, &Fdv);
    const double g = m->kappa2 != 0.0 ? model_contact_force(m, d, ddv) / m->kappa2 : 0.0;
    double *fc = P[IU_F_CONTACT];
    fc[IK_U0] = Fd;
    fc[IK_V0] = Fdv;
    fc[IK_U_WALL] = -Fd;
    fc[IK_V_WALL] = -Fdv * vw;
    fc[IK_GAMMA] = m->Omega2 * g;
    fc[IK_OMEGA] = 2.0 * m->Omega * m->Gamma * g;
    if (m->contact == CONTACT_HUNT_CROSSLEY && d > 0.0)
        fc[IK_ALPHA_HC] = m->kappa2 * d * sqrt(d) * ddv;
    for (int j = 0; j < MODEL_N_INIT_KNOWNS; ++j) dv[j] -= fc[j];
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
    g[0] = y[0] - model_wall_position(m, tau); /* the wall u = w */
    /* The grazing guard: a contact that enters and leaves within one solver step leaves u < w
     * at both step ends, but its turning point (relative velocity 0) is still bracketed. */
    g[1] = y[1] - model_wall_velocity(m);
}

void model_root_directions(const ModelData *m, int dir[MODEL_N_EVENTS]) {
    switch (m->mode) {
    case MODE_CONTACT: dir[0] = -1; dir[1] = +1; break; /* leaving; minimum of u inside */
    case MODE_STICK: dir[0] = -1; dir[1] = 0; break;    /* force falls below zero */
    default: dir[0] = +1; dir[1] = -1; break;           /* entering; maximum of u outside */
    }
}

int model_missed_crossing(const ModelData *m, double tau, const double y[2]) {
    if (m->wall == WALL_NONE) return 0;
    const double d = y[0] - model_wall_position(m, tau);
    if (m->mode == MODE_FREE) return d > 0.0;
    if (m->mode == MODE_CONTACT) return d < 0.0;
    return 0;
}

int model_release_now(ModelData *m, double tau) {
    if (m->mode == MODE_STICK && model_wall_force(m, tau) <= 0.0) {
        m->mode = MODE_FREE;
        return 1;
    }
    return 0;
}

/* STICK_ULPS ulps of a wall at w (0 at w = 0, where u has full relative precision). */
static double wall_resolution(double w) {
    return w == 0.0 ? 0.0 : STICK_ULPS * (nextafter(fabs(w), INFINITY) - fabs(w));
}

/* The rigid wall's impact at relative velocity vc (v - w' before the jump): (11) in the wall's
 * frame, and sticking when the rebound is negligible while the net force pushes in. */
static void rigid_impact(ModelData *m, double tau, double y[2], double w, double dw) {
    const double vc = y[1] - dw;
    y[0] = beside_wall(w, -1.0);
    y[1] = dw == 0.0 ? -m->r * vc : dw - m->r * vc; /* (11) */
    const double push = model_wall_force(m, tau), vr = y[1] - dw;
    /* A wall at w != 0 resolves u only to ulp(w): a rebound rising less than a few ulps (v^2/2
     * push) cannot be represented, its crossings are found late, and the late finds pump energy
     * into a chatter that then never ends. Sticking is the limit of that chatter too. (w = 0:
     * u has full relative precision; only the velocity threshold acts, as before the ports.) */
    const double res = wall_resolution(w);
    if (push > 0.0 &&
        (fabs(vr) <= STICK_VELOCITY * fmax(1.0, fabs(vc)) || vr * vr <= 2.0 * push * res)) {
        y[0] = w;
        y[1] = dw;
        m->mode = MODE_STICK;
    }
}

EventResult model_event_update(ModelData *m, double tau, double y[2], int which) {
    if (which == 1) return EVENT_NONE; /* a turning point on the right side: nothing happens */
    const double w = model_wall_position(m, tau), dw = model_wall_velocity(m);

    switch (m->mode) {
    case MODE_FREE:
        if (m->wall == WALL_RIGID && y[1] - dw <= 0.0 && model_wall_force(m, tau) <= 0.0) {
            /* Not an impact: a mass that leaves the wall (just released from sticking on a moving
             * wall: relative velocity 0, the net force pulling it off) put an ulp beyond it by the
             * integrator's error, which exceeds the separation -|a| t^2 / 2 for a while. It is
             * placed back beside the wall; no impact is counted (one was, at every release). */
            y[0] = beside_wall(w, -1.0);
            return EVENT_JUMP;
        }
        /* entering the wall: u = w (the root), v > w' */
        m->impacts += 1;
        m->v_impact = y[1] - dw;
        m->t_impact = m->origin + tau;
        if (m->wall == WALL_COMPLIANT) {
            /* footnote 2: the linear wall passes the mass on with v -> r v (relative to the
             * wall). The Hertz laws enter continuously (Hunt-Crossley dissipates inside). */
            if (m->contact == CONTACT_LINEAR)
                y[1] = dw == 0.0 ? y[1] * m->r : dw + m->r * (y[1] - dw);
            y[0] = beside_wall(w, +1.0);
            m->mode = MODE_CONTACT;
        } else {
            rigid_impact(m, tau, y, w, dw);
        }
        return EVENT_JUMP;
    case MODE_CONTACT:
        y[0] = beside_wall(w, -1.0); /* leaving the compliant wall: no jump in v */
        m->mode = MODE_FREE;
        return EVENT_JUMP;
    case MODE_STICK:
        y[0] = beside_wall(w, -1.0);
        y[1] = dw;
        m->mode = MODE_FREE;
        return EVENT_JUMP;
    }
    return EVENT_NONE;
}

/* The inputs jumped between two steps (a new u_wall, F_ext or derivative). The rule, per wall:
 * - compliant: the mode follows the side of the wall the mass is now on; the state is kept (the
 *   mass is inside the wall as after a start inside it: no entry jump, no impact counted);
 * - rigid, mass beyond the new wall position: it is placed on the wall and, if it moves towards
 *   the wall, the impact rule applies to its velocity relative to the wall (an impact, counted,
 *   with v_impact and t_impact); if it already moves away, it is placed without a rebound;
 * - rigid, sticking: the mass stays with the wall if the wall moved into it (then the holding
 *   force is checked again), and is released into free flight if the wall moved away, keeping
 *   its velocity, the wall's velocity before the jump (velocity is continuous: the constraint
 *   vanished, no impulse acted).
 * Never a silent penetration of the rigid wall, never a crossing the solver cannot locate. */
int model_input_jump(ModelData *m, double tau, double y[2]) {
    if (m->wall == WALL_NONE) return 0;
    const double w = model_wall_position(m, tau), dw = model_wall_velocity(m);
    const double y0 = y[0], y1 = y[1];
    const int mode = m->mode;
    if (m->wall == WALL_COMPLIANT) {
        if (m->mode == MODE_FREE && y[0] > w) m->mode = MODE_CONTACT;
        else if (m->mode == MODE_CONTACT && y[0] < w) m->mode = MODE_FREE;
    } else if (m->mode == MODE_STICK) {
        /* a wall set to where it is up to the rounding of the master's own w0 + w' t (a few ulps)
         * has not gone away: the mass stays on it */
        if (y[0] >= w - wall_resolution(w)) {
            y[0] = w; /* pushed along (or not moved) */
            y[1] = dw;
            if (model_wall_force(m, tau) <= 0.0) {
                y[0] = beside_wall(w, -1.0);
                m->mode = MODE_FREE;
            }
        } else {
            /* The wall went away. Only the constraint is gone, no force acted: the velocity is
             * continuous, and the mass keeps the velocity it had riding the wall (y[1], the wall's
             * velocity before the jump), whatever the wall's new velocity. */
            m->mode = MODE_FREE; /* the wall went away: y[1] is kept */
        }
    } else if (y[0] > w || (y[0] == w && y[1] > dw)) {
        if (y[1] - dw > 0.0) model_event_update(m, tau, y, 0); /* an impact */
        else y[0] = beside_wall(w, -1.0); /* already moving away: placed, no rebound */
    }
    return m->mode != mode || y[0] != y0 || y[1] != y1;
}

void model_get_states(const ModelData *m, double x[MODEL_N_STATES]) {
    x[0] = m->u;
    x[1] = m->v;
}

void model_set_states(ModelData *m, const double x[MODEL_N_STATES]) {
    m->u = x[0];
    m->v = x[1];
}

double model_me_event_tolerance(const ModelData *m, double tau) {
    return MODEL_ME_EVENT_TOL * fmax(1.0, fabs(model_wall_position(m, tau)));
}

/* A sticking mass whose state the importer moved off the wall (beyond the tolerance): free if it
 * is outside the wall, refused inside it. */
static MeEventResult me_unstick(ModelData *m, double d) {
    if (d > 0.0) return ME_EVENT_INSIDE_RIGID;
    m->mode = MODE_FREE;
    return ME_EVENT_KEPT;
}

MeEventResult model_me_event_update(ModelData *m, double tau, double y[2]) {
    if (m->wall == WALL_NONE) return ME_EVENT_NONE;
    const double tol = model_me_event_tolerance(m, tau);
    const double d = y[0] - model_wall_position(m, tau), dv = y[1] - model_wall_velocity(m);
    if (m->mode == MODE_STICK) {
        if (fabs(d) > tol || fabs(dv) > tol) return me_unstick(m, d);
        if (!model_release_now(m, tau)) return ME_EVENT_NONE; /* still held */
        y[0] = model_wall_position(m, tau); /* the holding force has gone: released */
        y[1] = model_wall_velocity(m);
        return ME_EVENT_JUMP;
    }
    /* the importer stops on the far side of g0 = u - w = 0 (or on it) */
    const int crossed = m->mode == MODE_FREE ? (d > 0.0 || (d == 0.0 && dv > 0.0))
                                             : (d < 0.0 || (d == 0.0 && dv < 0.0));
    if (!crossed) return ME_EVENT_NONE;
    if (fabs(d) <= tol) { /* the crossing the importer located: the wall's jump */
        model_event_update(m, tau, y, 0);
        return ME_EVENT_JUMP;
    }
    if (m->mode == MODE_CONTACT) { /* far outside the compliant wall: in flight */
        m->mode = MODE_FREE;
        return ME_EVENT_KEPT;
    }
    if (m->wall == WALL_RIGID) return ME_EVENT_INSIDE_RIGID;
    m->mode = MODE_CONTACT; /* far inside the compliant wall: in contact, no entry jump */
    return ME_EVENT_KEPT;
}

/* --- what the FMI core asks of the model ---------------------------------------------------- */
/* The core (fmu_vars.c, fmu_snapshot.c, fmu_cs.c, fmu_core.c) knows variables, states and
 * snapshots; what they mean physically is decided here. */

const char *model_check_derived(const ModelData *m, char *buf, size_t n) {
    if (!(m->kappa <= 1e8)) {
        snprintf(buf, n, "kappa = sqrt(Gamma) Omega = %g would exceed 1e8", m->kappa);
        return buf;
    }
    const double amp = (1.0 + m->sigma) * m->F_g;
    if (!isfinite(m->phi) || !(fabs(amp) <= 1e15)) {
        snprintf(buf, n, "the forcing amplitude (1 + sigma) F_g = %g would exceed 1e15", amp);
        return buf;
    }
    return NULL;
}

void model_rebase_inputs(ModelData *m, double tau) {
    if (m->dF_ext != 0.0) m->F_ext = model_external_force(m, tau);
    if (m->du_wall != 0.0) m->u_wall = model_wall_position(m, tau);
    m->in_tau = tau;
}

int model_has_ramps(const ModelData *m) { return m->dF_ext != 0.0 || m->du_wall != 0.0; }

int model_begin_wall_ramp(ModelData *m, double tau) {
    if (m->du_wall != 0.0 || m->v_wall == 0.0) return 0; /* an input derivative, or no motion */
    model_rebase_inputs(m, tau);
    m->du_wall = m->v_wall;
    return 1;
}

int model_end_ramps(ModelData *m, double tau) {
    if (m->dF_ext == 0.0 && m->du_wall == 0.0) return 0;
    model_rebase_inputs(m, tau);
    m->dF_ext = m->du_wall = 0.0;
    return 1;
}

static int finite_within(double x, double bound) { return isfinite(x) && fabs(x) <= bound; }

const char *model_check_restored(const ModelData *m, int is_me, double max_state,
                                 double max_time) {
    if (m->mode < MODE_FREE || m->mode > MODE_STICK ||
        (m->mode == MODE_CONTACT && m->wall != WALL_COMPLIANT) ||
        (m->mode == MODE_STICK && m->wall != WALL_RIGID))
        return "contact mode inconsistent with the wall model";
    if (m->impacts < 0) return "negative event counter";
    if (!finite_within(m->u, max_state) || !finite_within(m->v, max_state))
        return "continuous state (u, v) not finite or beyond 1e15";
    for (int i = 0; i < 6; ++i)
        if (!isfinite(i < 4 ? m->sJ[i / 2][i % 2] : m->sS[i - 4]))
            return "sensitivities (J_uu ... S_v) not finite";
    if (!finite_within(m->dF_ext, MODEL_MAX_DF_EXT) ||
        !finite_within(m->du_wall, MODEL_MAX_DU_WALL) ||
        !finite_within(m->in_tau, 2 * max_time) || !isfinite(m->v_impact) ||
        !finite_within(m->t_impact, 2 * max_time))
        return "input derivatives or impact record not finite or out of range";
    /* only Co-Simulation takes input derivatives */
    if (model_has_ramps(m) && is_me) return "input derivatives in a Model Exchange state";
    return NULL;
}

double model_in_contact(const ModelData *m) { return m->mode != MODE_FREE; }

/* J = I, S = 0 (as set at initialisation) when they are not computed, so that every output stays
 * finite. */
double model_sensitivity(const ModelData *m, int i) {
    return i < 4 ? m->sJ[i / 2][i % 2] : m->sS[i - 4];
}

double model_derivative(const ModelData *m, double tau, int i) {
    const double y[2] = {m->u, m->v};
    double dy[2];
    model_derivatives(m, tau, y, dy);
    return dy[i];
}

double model_wall_indicator(const ModelData *m, double tau) {
    const double y[2] = {m->u, m->v};
    double g[MODEL_N_EVENTS];
    model_event_indicators(m, tau, y, g);
    return g[0];
}

double model_contact_output_now(const ModelData *m, double tau, int inputs_jumped) {
    if (inputs_jumped) {
        /* F_contact feeds through from u_wall (ModelStructure): with a new wall position not
         * yet stepped over, report the force of the state the wall-jump rule gives now. */
        ModelData t;
        memcpy(&t, m, sizeof t);
        double y[2] = {t.u, t.v};
        model_input_jump(&t, tau, y);
        t.u = y[0];
        t.v = y[1];
        return model_contact_output(&t, tau);
    }
    return model_contact_output(m, tau);
}

int model_outputs_finite(const ModelData *m, double tau, int inputs_jumped, double max_state) {
    return finite_within(m->u, max_state) && finite_within(m->v, max_state) &&
           isfinite(model_contact_output_now(m, tau, inputs_jumped)) && isfinite(m->v_impact);
}
