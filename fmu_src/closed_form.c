/*
 * The closed-form solver: exact propagation on each side of the wall, certified crossing search.
 *
 * Solution of one mode. With the stiffness k2 of the mode (Omega^2 free, Omega^2 + kappa^2 in
 * the compliant wall) the ODE is u'' + nu u' + k2 u = (1 + sigma) F_g cos(2 pi tau + phi) + c(tau)
 * with c linear in tau (the spring's offset, and the ports when they are inputs). Its particular
 * solution q = amp (gr cos th - gi sin th) + p0 + p1 (tau - tref), th = 2 pi tau, and the
 * homogeneous part w = y - q obeys w' = M w, M = [[0, 1], [-k2, -nu]], so
 *     y(tau_a + s) - y_a = (P(s) - I) w_a + (q(tau_a + s) - q(tau_a)),
 * both brackets evaluated with small relative error for small s (a series for P - I, half-angle
 * differences for q), so that contacts and chatter 1e-9 apart keep their digits.
 *
 * Certified search. The energy E = sqrt(k2 w^2 + w'^2) of the homogeneous part never grows
 * (dE^2/dt = -2 nu w'^2), so over the whole segment |w^(k)| <= m_k with m_0 = E/sqrt(k2),
 * m_1 = E, m_(k+2) = nu m_(k+1) + k2 m_k, and |u^(k)| <= M_k = m_k + (2 pi)^k amp |g| (+|p1|
 * for k = 1). With g = +-(u - wall) the side indicator (> 0: crossed), an interval [L, R] is
 *   - excluded if the Taylor bound from both ends, max(g_L + |g'_L| h/2, g_R + |g'_R| h/2)
 *     + M_2 h^2/8, is negative: no contact inside;
 *   - else, if g' keeps one sign on it (g'_L + g'_R > M_2 h in that sign, since
 *     g' >= (g'_L + g'_R - M_2 h)/2 there), g is monotone: a crossing is a sign change of g
 *     (its only one), located as below;
 *   - else, if u'' = a keeps one sign on it (a_L + a_R > M_3 h in that sign), g' is monotone:
 *     g has at most one turning point, located by a root of g', and on the (at most two)
 *     monotone pieces a crossing is a sign change of g, located by a safeguarded Newton
 *     iteration;
 *   - else it is halved.
 * A contact however shallow lies around a turning point where a != 0, so it is decided by the
 * value of g at that turning point, never by samples that happen to miss it. Only a turning
 * point with a = 0 exactly on the wall (the release from sticking) needs more: there a < 0
 * is certified for a time -j/M_4 by the jerk j, and the search starts after it.
 */
#define _GNU_SOURCE /* sincos */
#include "closed_form.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "sens.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#define TWO_PI (2.0 * M_PI)

/* Same bound on the work of one step as the CVODE driver: an error, never a hang. */
static const double MAX_EVENTS_PER_UNIT_TIME = 1e5;
/* P - I by its series below this rate * s (terms <= 0.05^k/k!: 13 reach 1e-24 relative). */
static const double SERIES_RATE_T = 0.05;

/* Constants of one linear mode (see the file comment). */
typedef struct {
    double nu, k2, b, d, w, rate, omega;
    double amp, gr, gi, fr, fi, Qa;
    double c0, c1, p0, p1, tref; /* c(tau) = c0 + c1 (tau - tref); q's polynomial part */
    double wall0, wall1;         /* wall position wall0 + wall1 (tau - tref) */
} Mode;

/* One segment: the mode's solution anchored at (tau_a, u_a, v_a), with its derivative bounds. */
typedef struct {
    const Mode *md;
    double tau_a, u_a, v_a, ca, sa, th_a, wu, wv;
    double M[5];
} Seg;

/* The state at tau_a + s, with what the sensitivities need (P - I and the phase increments). */
typedef struct {
    double s, u, v, a, j;
    double E[2][2], dcos, dsin;
} Pt;

/* The ports, as linear functions of local time: force F0 + F1 (tau - tref), wall position
 * W0 + W1 (tau - tref). */
static void inputs(const ModelData *m, double *F0, double *F1, double *W0, double *W1,
                   double *tref) {
    *F0 = m->F_ext;
    *F1 = m->dF_ext;
    *W0 = m->u_wall;
    *W1 = m->du_wall;
    *tref = m->in_tau;
}

static void mode_init(Mode *md, const ModelData *m, int contact) {
    double F0, F1, W0, W1, tref;
    inputs(m, &F0, &F1, &W0, &W1, &tref);
    const double kap2 = contact ? m->kappa2 : 0.0;
    md->nu = m->nu;
    md->k2 = m->Omega2 + kap2;
    md->omega = sqrt(md->k2);
    md->b = 0.5 * m->nu;
    md->d = md->b * md->b - md->k2;
    md->w = sqrt(fabs(md->d));
    md->rate = md->d >= 0.0 ? md->b + md->w : md->omega; /* spectral radius of M */
    md->amp = 1.0 + m->sigma;
    /* F_g e^{i phi} = (Omega^2 - 4 pi^2) + 2 pi nu i; g = that / (k2 - 4 pi^2 + 2 pi nu i) */
    const double zr = m->Omega2 - 4.0 * M_PI * M_PI, zi = TWO_PI * m->nu;
    const double yr = md->k2 - 4.0 * M_PI * M_PI, yi = zi;
    const double den = yr * yr + yi * yi;
    md->gr = (zr * yr + zi * yi) / den;
    md->gi = (zi * yr - zr * yi) / den;
    md->fr = zr;
    md->fi = zi;
    md->Qa = fabs(md->amp) * hypot(md->gr, md->gi);
    md->tref = tref;
    md->c0 = -m->Omega2 + F0 + kap2 * W0;
    md->c1 = F1 + kap2 * W1;
    md->p1 = md->c1 / md->k2;
    md->p0 = (md->c0 - md->nu * md->p1) / md->k2;
    md->wall0 = W0;
    md->wall1 = W1;
}

/* e^{-b s} C(s) and e^{-b s} S(s): C = cosh(sqrt(d) s), S = sinh(sqrt(d) s)/sqrt(d) (cos/sin for
 * d < 0), a series where |d| s^2 is small (critical damping), combined exponentials far out. */
static void damped_cs(const Mode *md, double s, double *eC, double *eS) {
    const double z = md->d * s * s;
    if (fabs(z) <= 1e-6) {
        const double E = exp(-md->b * s);
        *eC = E * (1.0 + z * (1.0 / 2 + z * (1.0 / 24 + z / 720)));
        *eS = E * s * (1.0 + z * (1.0 / 6 + z * (1.0 / 120 + z / 5040)));
    } else if (md->d > 0.0) {
        const double qs = md->w * s;
        if (fabs(qs) > 30.0) {
            const double ep = exp((md->w - md->b) * s), em = exp(-(md->w + md->b) * s);
            *eC = 0.5 * (ep + em);
            *eS = 0.5 * (ep - em) / md->w;
        } else {
            const double E = exp(-md->b * s);
            *eC = E * cosh(qs);
            *eS = E * sinh(qs) / md->w;
        }
    } else {
        double sn, cs;
        sincos(md->w * s, &sn, &cs);
        const double E = exp(-md->b * s);
        *eC = E * cs;
        *eS = E * sn / md->w;
    }
}

/* P(s) - I with small relative error also for small s. */
static void prop_minus_identity(const Mode *md, double s, double E[2][2]) {
    if (md->rate * fabs(s) <= SERIES_RATE_T) {
        /* sum_k M^k s^k/k! with M^k = a_k M + b_k I, M^2 = -nu M - k2 I */
        double A = 0.0, B = 0.0, ak = 1.0, bk = 0.0, fac = s;
        for (int k = 1; k < 14; ++k) {
            A += ak * fac;
            B += bk * fac;
            const double an = -md->nu * ak + bk;
            bk = -md->k2 * ak;
            ak = an;
            fac *= s / (k + 1);
            if (fabs(fac) * (fabs(ak) + fabs(bk)) <= 1e-18 * (fabs(A) + fabs(B))) break;
        }
        E[0][0] = B;
        E[0][1] = A;
        E[1][0] = -md->k2 * A;
        E[1][1] = B - md->nu * A;
        return;
    }
    double eC, eS;
    damped_cs(md, s, &eC, &eS);
    E[0][0] = eC + md->b * eS - 1.0;
    E[0][1] = eS;
    E[1][0] = -md->k2 * eS;
    E[1][1] = eC - md->b * eS - 1.0;
}

static void seg_init(Seg *sg, const Mode *md, double tau_a, double u_a, double v_a) {
    sg->md = md;
    sg->tau_a = tau_a;
    sg->u_a = u_a;
    sg->v_a = v_a;
    sg->th_a = TWO_PI * tau_a;
    sincos(sg->th_a, &sg->sa, &sg->ca);
    const double qu = md->amp * (md->gr * sg->ca - md->gi * sg->sa) + md->p0 +
                      md->p1 * (tau_a - md->tref);
    const double qv = md->amp * TWO_PI * (-md->gr * sg->sa - md->gi * sg->ca) + md->p1;
    sg->wu = u_a - qu;
    sg->wv = v_a - qv;
    /* derivative bounds over the segment (file comment); 1e-12 relative covers rounding */
    const double E = sqrt(md->k2 * sg->wu * sg->wu + sg->wv * sg->wv);
    double mk[5];
    mk[0] = E / md->omega;
    mk[1] = E;
    for (int k = 2; k < 5; ++k) mk[k] = md->nu * mk[k - 1] + md->k2 * mk[k - 2];
    double wk = 1.0;
    for (int k = 0; k < 5; ++k, wk *= TWO_PI)
        sg->M[k] = (mk[k] + wk * md->Qa + (k == 1 ? fabs(md->p1) : 0.0)) * (1.0 + 1e-12) + 1e-300;
}

static void seg_eval(const Seg *sg, double s, Pt *p) {
    const Mode *md = sg->md;
    prop_minus_identity(md, s, p->E);
    /* the phase at mid-step by the angle-sum formula from the anchor's sin and cos (seg_init):
     * one sincos per evaluation instead of two, as accurate (absolute error ~ 1 ulp of 1) */
    double sh, ch;
    sincos(M_PI * s, &sh, &ch);
    const double smid = sg->sa * ch + sg->ca * sh, cmid = sg->ca * ch - sg->sa * sh;
    p->dcos = -2.0 * sh * smid;
    p->dsin = 2.0 * sh * cmid;
    const double dqu = md->amp * (md->gr * p->dcos - md->gi * p->dsin) + md->p1 * s;
    const double dqv = md->amp * TWO_PI * (-md->gr * p->dsin - md->gi * p->dcos);
    p->s = s;
    p->u = sg->u_a + (p->E[0][0] * sg->wu + p->E[0][1] * sg->wv + dqu);
    p->v = sg->v_a + (p->E[1][0] * sg->wu + p->E[1][1] * sg->wv + dqv);
    const double ct = sg->ca + p->dcos, st = sg->sa + p->dsin;
    const double c = md->c0 + md->c1 * (sg->tau_a + s - md->tref);
    p->a = md->amp * (md->fr * ct - md->fi * st) + c - md->nu * p->v - md->k2 * p->u;
    p->j = md->amp * TWO_PI * (-md->fr * st - md->fi * ct) + md->c1 - md->nu * p->a - md->k2 * p->v;
}

/* Side indicator (> 0: on the far side) and its derivative. */
static double side(const Seg *sg, double sgn, const Pt *p) {
    const Mode *md = sg->md;
    return sgn * (p->u - (md->wall0 + md->wall1 * (sg->tau_a + p->s - md->tref)));
}
static double side_rate(const Seg *sg, double sgn, const Pt *p) {
    return sgn * (p->v - sg->md->wall1);
}

/* Root of f = side (which = 0) or side_rate (which = 1) on [lo, hi], where f is monotone with
 * f(lo) <= 0 < f(hi) (which = 0) or a sign change (which = 1): Newton's iteration on the exact
 * solution, kept inside the bracket (bisection when it leaves it), until the step or the
 * bracket is below rounding in s. A Newton step below rounding ends it at once: taken, it
 * rounds onto the end of the bracket Newton came from, which counted as leaving the bracket
 * and restarted a bisection of the whole bracket (30 more evaluations at a contact exit on
 * Figure 7's orbits, converging to the same root). */
static void bracket_root(const Seg *sg, double sgn, int which, Pt lo, Pt hi, Pt *out) {
    double flo = which ? side_rate(sg, sgn, &lo) : side(sg, sgn, &lo);
    const double up = flo <= 0.0 ? 1.0 : -1.0; /* orient so that f(lo) <= 0 */
    Pt x = (fabs(flo) < fabs(which ? side_rate(sg, sgn, &hi) : side(sg, sgn, &hi))) ? lo : hi;
    for (int it = 0; it < 100; ++it) {
        const double f = up * (which ? side_rate(sg, sgn, &x) : side(sg, sgn, &x));
        const double df = up * sgn * (which ? x.a : x.v - sg->md->wall1);
        if (f == 0.0) break;
        if (f < 0.0) lo = x;
        else hi = x;
        const double tol = 2.0 * DBL_EPSILON * fabs(x.s) + 1e-300;
        if (hi.s - lo.s <= 2.0 * DBL_EPSILON * fabs(hi.s) + 1e-300) break;
        if (fabs(f) <= tol * fabs(df)) break; /* Newton's step below rounding: x is the root */
        double xn = x.s - f / df;
        if (!(xn > lo.s && xn < hi.s) || !isfinite(xn)) xn = 0.5 * (lo.s + hi.s);
        const double step = fabs(xn - x.s);
        seg_eval(sg, xn, &x);
        if (step <= tol) break;
    }
    *out = x;
}

/* The first crossing to the far side (g > 0) in (0, s_end]: returns 1 with *hit the crossing
 * state, or 0 with *hit the state at s_end. `released`: the segment starts at the release from
 * sticking. */
static int first_crossing(const Seg *sg, double sgn, double s_end, int released, Pt *hit) {
    const Mode *md = sg->md;
    Pt L, R, T;
    seg_eval(sg, 0.0, &L);
    if (released && L.j * sgn < 0.0) {
        /* a <= a_0 + j x + M_4 x^2/2 < 0 on (2 a_0/|j|, -j/M_4]: certified away from the wall */
        const double x = fmin(s_end, fabs(L.j) / sg->M[4]);
        seg_eval(sg, x, &L);
        if (x >= s_end) {
            *hit = L;
            return 0;
        }
    }
    const double h0 = fmin(0.25, 1.0 / fmax(TWO_PI, md->omega));
    double h = h0;
    /* right ends of the last undecided steps: after a halving the search often comes back to
     * one of them (same s, same state), which is then not evaluated again */
    enum { KEPT = 4 };
    Pt kept[KEPT];
    int n_kept = 0, slot = 0;
    while (L.s < s_end) {
        const double sR = fmin(L.s + h, s_end);
        const double hh = sR - L.s;
        int k = 0;
        while (k < n_kept && kept[k].s != sR) ++k;
        if (k < n_kept) R = kept[k];
        else seg_eval(sg, sR, &R);
        const double gL = side(sg, sgn, &L), gR = side(sg, sgn, &R);
        const double dL = side_rate(sg, sgn, &L), dR = side_rate(sg, sgn, &R);
        const double ub = fmax(gL + fabs(dL) * 0.5 * hh, gR + fabs(dR) * 0.5 * hh) +
                          sg->M[2] * hh * hh * 0.125;
        const double aL = sgn * L.a, aR = sgn * R.a;
        const int monotone_rate = (aL > 0.0 && aR > 0.0 && aL + aR > sg->M[3] * hh) ||
                                  (aL < 0.0 && aR < 0.0 && -(aL + aR) > sg->M[3] * hh);
        /* g' >= (g'_L + g'_R - M_2 h)/2 on [L, R] (file comment): g itself monotone */
        const int monotone_side = (dL > 0.0 && dR > 0.0 && dL + dR > sg->M[2] * hh) ||
                                  (dL < 0.0 && dR < 0.0 && -(dL + dR) > sg->M[2] * hh);
        const int tiny = hh <= 4.0 * DBL_EPSILON * (1.0 + fabs(sg->tau_a + L.s));
        if (ub < 0.0) {
            /* no contact inside */
        } else if (monotone_side) {
            if (gL <= 0.0 && gR > 0.0) { /* the only sign change */
                bracket_root(sg, sgn, 0, L, R, hit);
                return 1;
            }
        } else if (monotone_rate || tiny) {
            if (dL * dR < 0.0 && monotone_rate) { /* one turning point: split there */
                bracket_root(sg, sgn, 1, L, R, &T);
                const double gT = side(sg, sgn, &T);
                if (gL <= 0.0 && gT > 0.0) {
                    bracket_root(sg, sgn, 0, L, T, hit);
                    return 1;
                }
                if (gT <= 0.0 && gR > 0.0) {
                    bracket_root(sg, sgn, 0, T, R, hit);
                    return 1;
                }
            } else if (gL <= 0.0 && gR > 0.0) {
                bracket_root(sg, sgn, 0, L, R, hit);
                return 1;
            }
        } else {
            h = 0.5 * hh; /* not decided: halve */
            kept[slot] = R; /* the oldest goes */
            slot = (slot + 1) % KEPT;
            n_kept += n_kept < KEPT;
            continue;
        }
        L = R;
        h = fmin(2.0 * h, h0);
    }
    *hit = L; /* at s_end: the caller's end state, not evaluated again */
    return 0;
}

const char *closed_form_unsupported(const ModelData *m) {
    if (m->wall == WALL_COMPLIANT && m->contact != CONTACT_LINEAR)
        return "solver = 1 (closed form) needs the linear contact law (contact = 0): the Hertz "
               "and Hunt-Crossley laws are nonlinear, use solver = 0 (CVODE)";
    return NULL;
}

/* Release time of a mass sticking on the rigid wall: the first tau in [tau0, tau_end] at which
 * the net force into the wall, f(tau) = A cos(2 pi tau + phi) + beta tau + const (beta from the
 * input ramps), is no longer positive; tau_end if it stays positive. Between the zeros of
 * f' (sin(2 pi tau + phi) = beta / (2 pi A), known in closed form) f is monotone, so the first
 * piece whose end has f <= 0 holds the root, found by bisection. */
static double release_time(const ModelData *m, double tau0, double tau_end) {
    if (model_wall_force(m, tau0) <= 0.0) return tau0;
    const double A = fabs((1.0 + m->sigma) * m->F_g);
    /* the forcing has period 1: the difference over one period is the ramp's slope */
    const double beta = model_wall_force(m, tau0 + 1.0) - model_wall_force(m, tau0);
    const double s = A > 0.0 ? beta / (TWO_PI * A) : (beta > 0.0 ? 2.0 : -2.0);
    double crit[2] = {0.0, 0.0}; /* phases of the turning points, in [0, 2 pi) */
    int nc = 0;
    if (fabs(s) <= 1.0) {
        crit[0] = asin(s);
        crit[1] = M_PI - crit[0];
        if (crit[0] < 0.0) crit[0] += TWO_PI;
        nc = 2;
    }
    double a = tau0;
    while (a < tau_end) {
        /* the next turning point after a (or one period on, if f is monotone) */
        double b = a + 1.0;
        const double psi = fmod(TWO_PI * a + m->phi, TWO_PI);
        for (int k = 0; k < nc; ++k) {
            double d = fmod(crit[k] - psi, TWO_PI);
            if (d <= 0.0) d += TWO_PI;
            b = fmin(b, a + d / TWO_PI);
        }
        b = fmin(b, tau_end);
        /* a on a turning point up to rounding: d is a few ulps and a + d / 2 pi == a; step past
         * it, or the loop never moves (fuzzer find F13) */
        if (!(b > a)) b = fmin(nextafter(a, HUGE_VAL), tau_end);
        if (model_wall_force(m, b) <= 0.0) {
            double lo = a, hi = b; /* f(lo) > 0 >= f(hi), f monotone */
            for (int it = 0; it < 200 && hi - lo > 2.0 * DBL_EPSILON * fabs(hi); ++it) {
                const double mid = 0.5 * (lo + hi);
                if (model_wall_force(m, mid) > 0.0) lo = mid;
                else hi = mid;
            }
            return hi;
        }
        if (b >= tau_end) break;
        a = b;
    }
    return tau_end;
}

/* A mass sticking on the wall at tau: at the wall, moving with it. */
static void stuck_state(ModelData *m, double tau) {
    double F0, F1, W0, W1, tref;
    inputs(m, &F0, &F1, &W0, &W1, &tref);
    m->u = W0 + W1 * (tau - tref);
    m->v = W1;
}

/* A mass sticking on the wall from the clock's time on: held there to tau_end (returns 0, the
 * clock at tau_end), or released where the wall stops pushing: 1 with the release pending
 * (stop_at_event), else 2 with it applied. */
static int stick_until_release(StepClock *s, ModelData *m, double tau_end, int stop_at_event) {
    const double tr = release_time(m, s->tau, tau_end);
    if (tr >= tau_end && model_wall_force(m, tau_end) > 0.0) {
        s->tau = tau_end;
        stuck_state(m, tau_end); /* carried along by the wall */
        return 0;
    }
    s->tau = tr;
    if (stop_at_event) {
        s->pending = 1;
        return 1;
    }
    double y[2] = {m->u, m->v};
    sens_event_update(m, tr, y);
    m->u = y[0];
    m->v = y[1];
    s->events++;
    return 2;
}

/* The wall events one advance over `span` (local time) may take: an error, never a hang. */
static long event_bound(const ModelData *m, double span) {
    const double units = fmax(1.0, ceil(span));
    const double per_time = m->max_events_per_time > 0.0 ? m->max_events_per_time
                                                         : MAX_EVENTS_PER_UNIT_TIME;
    return (long)(per_time * units);
}

/* J <- P J; S <- P S + (q_sigma(tau) - q_sigma(tau_a)) - (P - I) q_sigma(tau_a): the sensitivities
 * over the smooth stretch from the segment's anchor to p. */
static void propagate_sensitivities(ModelData *m, const Mode *md, const Seg *sg, const Pt *p) {
    const double P[2][2] = {{p->E[0][0] + 1.0, p->E[0][1]}, {p->E[1][0], p->E[1][1] + 1.0}};
    const double qu = md->gr * sg->ca - md->gi * sg->sa;
    const double qv = TWO_PI * (-md->gr * sg->sa - md->gi * sg->ca);
    const double ds[2] = {
        md->gr * p->dcos - md->gi * p->dsin - (p->E[0][0] * qu + p->E[0][1] * qv),
        TWO_PI * (-md->gr * p->dsin - md->gi * p->dcos) - (p->E[1][0] * qu + p->E[1][1] * qv)};
    sens_propagate(m, P, ds);
}

static int cf_advance_to(Stepper *st, ModelData *m, double t_end, int stop_at_event) {
    StepClock *s = &st->clk;
    s->msg[0] = '\0';
    const char *why = closed_form_unsupported(m);
    if (why) {
        snprintf(s->msg, sizeof s->msg, "%s", why);
        return -1;
    }
    clock_apply_pending(s, m);
    clock_reorigin(s, m);
    double tau_end = t_end - s->origin;
    if (tau_end < s->tau) {
        snprintf(s->msg, sizeof s->msg, "cannot integrate backwards to t = %.17g", t_end);
        return -1;
    }
    const long max_events = event_bound(m, tau_end - s->tau);
    long events = 0;
    Mode modes[2];
    mode_init(&modes[0], m, 0);
    mode_init(&modes[1], m, 1);
    int released = 0;
    if (model_release_now(m, s->tau)) {
        s->events++;
        released = 1;
    }
    while (s->tau < tau_end) {
        if (m->mode == MODE_STICK) {
            const int rc = stick_until_release(s, m, tau_end, stop_at_event);
            if (rc == 0) break;
            if (rc == 1) return 1;
            released = 1;
            continue;
        }
        const Mode *md = &modes[m->mode == MODE_CONTACT];
        Seg sg;
        seg_init(&sg, md, s->tau, m->u, m->v);
        const double s_end = tau_end - s->tau;
        Pt p;
        int hit = 0;
        if (m->wall != WALL_NONE)
            hit = first_crossing(&sg, m->mode == MODE_CONTACT ? -1.0 : 1.0, s_end, released, &p);
        else
            seg_eval(&sg, s_end, &p);
        released = 0;
        if (m->sensitivities) propagate_sensitivities(m, md, &sg, &p);
        m->u = p.u;
        m->v = p.v;
        if (!hit) {
            s->tau = tau_end;
            break;
        }
        s->tau = sg.tau_a + p.s;
        if (stop_at_event) {
            s->pending = 1;
            return 1;
        }
        double y[2] = {p.u, p.v};
        sens_event_update(m, s->tau, y);
        m->u = y[0];
        m->v = y[1];
        s->events++;
        if (++events > max_events) {
            snprintf(s->msg, sizeof s->msg,
                     "more than %ld wall events before t = %.17g (chatter that does not end?)",
                     max_events, s->origin + s->tau);
            return -1;
        }
        const double k = floor(s->tau);
        if (k > 0.0) {
            clock_reorigin(s, m);
            tau_end -= k;
            mode_init(&modes[0], m, 0); /* tref moves with the origin (the ports) */
            mode_init(&modes[1], m, 1);
        }
    }
    return 0;
}

/* The closed form keeps nothing between calls: its memory is empty. */
static int cf_create(Stepper *st, ModelData *m) {
    (void)m;
    st->impl = NULL;
    return 0;
}

static void cf_free(Stepper *st) { st->impl = NULL; }

static void cf_start(Stepper *st, double t) { clock_start(&st->clk, t); }

static int cf_apply_pending(Stepper *st, ModelData *m) { return clock_apply_pending(&st->clk, m); }

const StepperOps STEPPER_CLOSED_FORM = {
    "closed form", cf_create, cf_free, cf_start, cf_advance_to, cf_apply_pending,
};
