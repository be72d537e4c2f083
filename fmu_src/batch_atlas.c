/*
 * The batch kernel over a parameter plane (the atlas): many pixels, each a parameter set, each
 * run from a few starts to its attractor with the closed form (closed_form.c), the FMU's own
 * sequence of calls as in batch.c (model_set_defaults, the parameters, model_update_derived and
 * its checks, stepper_start at t0 = theta, model_initialize_state, one advance per forcing period).
 *
 * Each start stops as soon as its stroboscopic orbit is periodic: after period k (k >= n_min) the
 * last M states equal the M before them (max norm, tolerance tol (1 + |u| + |v|), the same wall
 * entries in each period) for the smallest such M <= m_max. Then M more periods run with the
 * exact sensitivities (sens.c: variational equations and saltation matrices, m->sensitivities):
 * their product is the Jacobian of the M-period map at the orbit, and its largest multiplier in
 * modulus gives the orbit's Lyapunov exponent, ln|mu| / M per forcing period. A start not
 * periodic after n_max periods gets the largest Lyapunov exponent of the stroboscopic map over
 * its last n_lyap periods (a tangent vector through the same per-period Jacobians, renormalised
 * each period; the sensitivities ride along only then).
 *
 * The starts of a pixel run one after the other on one thread (pixels spread over the threads):
 * a start whose state lands within match_tol (relative, as tol) of a point of an orbit an earlier
 * start of the pixel reached, and follows that orbit point by point for two rounds (at least four
 * periods) with the same wall entries, is that orbit and stops there.
 *
 * A start still not periodic after n_max periods but whose last M states lie within
 * SETTLE_RESIDUAL of the M before them (a multiplier near -1 or +1 contracts slowly, as next to a
 * flip or a fold) is closed onto its period-M orbit by Newton with the exact Jacobian of the
 * M-period map (settle); only a start that Newton cannot close counts as aperiodic. Likewise a
 * start found periodic with period M but within SETTLE_RESIDUAL of period d | M (a period-d orbit
 * with a multiplier near -1 converges slowly, and its period-2d recurrence closes first) is
 * closed onto the period-d orbit when that one is stable.
 *
 * Outputs per start (pixel-major, k starts per pixel): status (ATLAS_*), period, wall entries per
 * orbit period, periods run, whether the orbit sticks (sticking at a sample, or chatter: at least
 * CHATTER_ENTRIES wall entries in one period), the exponent, and the orbit's M points in time
 * order (the last one last; NaN beyond M).
 *
 * Built into build/fmu/libimpact_batch.so with batch.c; loaded by harness/fmu/atlas_kernel.py.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "batch.h"
#include "closed_form.h"
#include "model.h"
#include "sens.h"
#include "stepper.h"

#ifdef _OPENMP
#include <omp.h>
#endif

#ifndef M_SQRT1_2
#define M_SQRT1_2 0.70710678118654752440
#endif

/* Per-start status (the `status` output). */
enum { ATLAS_PERIODIC = 0, ATLAS_APERIODIC = 1, ATLAS_INVALID = 2, ATLAS_FAILED = 3, ATLAS_ESCAPED = 4,
       ATLAS_MATCHED = 5 /* internal: landed on an earlier start's orbit (reported as PERIODIC) */ };

/* Wall entries in one period from which a start counts as chattering (harness
 * dynamics/attractors/identity.py, CHATTER_ENTRIES). */
#define CHATTER_ENTRIES 8
/* The looser tolerance (x tol) under which a detected period collapses onto a divisor. */
#define COLLAPSE_FACTOR 1e3
/* Largest period searched (the history kept is twice that). */
#define ATLAS_MAX_PERIOD 64
/* A start not periodic after n_max periods whose last M states are within this (relative) of
 * the M before them is closed onto its period-M orbit by Newton, in at most SETTLE_ITERATIONS. */
#define SETTLE_RESIDUAL 1e-3
#define SETTLE_ITERATIONS 6
/* Largest number of starts per pixel. */
#define ATLAS_MAX_STARTS 256

typedef struct {
    double theta, tol, match_tol;
    int n_min, n_max, m_max, n_lyap;
} AtlasRun;

typedef struct {
    int status, period, impacts, periods, sticks;
    double lyap;
} AtlasOutcome;

/* One period from the clock's time to theta + k; 0, or a status that ends the start. */
static int one_period(Stepper *st, ModelData *m, double theta, int k, double *t, char *err, int errlen) {
    const double target = theta + (double)k;
    const double t_end = *t + (target - *t); /* what the FMU's doStep(t, target - t) reaches */
    if (stepper_advance_to(st, m, t_end, 0) != 0) {
        snprintf(err, (size_t)errlen, "t = %.17g: %s", t_end, st->clk.msg);
        return ATLAS_FAILED;
    }
    *t = t_end;
    if (!(fabs(m->u) <= ESCAPE_BOUND && fabs(m->v) <= ESCAPE_BOUND)) return ATLAS_ESCAPED;
    return 0;
}

/* The smallest period M <= m_max with the last M states (ring buffer of h slots, newest at k)
 * equal to the M before them within the tolerance; 0 if none. */
static int recurrence(const double *hu, const double *hv, const int *he, int h, int k, int m_max, double tol) {
    for (int M = 1; M <= m_max; ++M) {
        int ok = 1;
        for (int j = 0; j < M && ok; ++j) {
            const int a = (k - j) % h, b = (k - j - M) % h;
            const double eps = tol * (1.0 + fabs(hu[b]) + fabs(hv[b]));
            ok = he[a] == he[b] && fabs(hu[a] - hu[b]) <= eps && fabs(hv[a] - hv[b]) <= eps;
        }
        if (ok) return M;
    }
    return 0;
}

/* The smallest divisor d of M whose shift maps the last M states onto themselves within the
 * looser tolerance `loose`: near a flip a period-1 orbit's states z_k - z_(k-2) shrink
 * faster than z_k - z_(k-1) (multiplier near -1), so the strict test may see period 2 first. */
static int collapse(const double *hu, const double *hv, const int *he, int h, int k, int M, double loose) {
    for (int d = 1; d < M; ++d) {
        if (M % d) continue;
        int ok = 1;
        for (int j = 0; j + d < M && ok; ++j) {
            const int a = (k - j) % h, b = (k - j - d) % h;
            const double eps = loose * (1.0 + fabs(hu[b]) + fabs(hv[b]));
            ok = he[a] == he[b] && fabs(hu[a] - hu[b]) <= eps && fabs(hv[a] - hv[b]) <= eps;
        }
        if (ok) return d;
    }
    return M;
}

/* J <- sJ J (2 x 2). */
static void chain(const double sJ[2][2], double J[2][2]) {
    for (int j = 0; j < 2; ++j) {
        const double x = J[0][j], y = J[1][j];
        J[0][j] = sJ[0][0] * x + sJ[0][1] * y;
        J[1][j] = sJ[1][0] * x + sJ[1][1] * y;
    }
}

/* ln of the largest |eigenvalue| of a 2 x 2 matrix (-745: a nilpotent one, e.g. through sticking). */
static double log_spectral_radius(const double J[2][2]) {
    const double tr = J[0][0] + J[1][1], det = J[0][0] * J[1][1] - J[0][1] * J[1][0];
    const double disc = 0.25 * tr * tr - det;
    const double rho = disc >= 0.0 ? fabs(0.5 * tr) + sqrt(disc) : sqrt(fabs(det));
    return rho > 0.0 ? log(rho) : -745.0;
}

/* A tangent vector carried through the per-period Jacobians: the sum of the logs of its growth. */
typedef struct {
    double w[2], sum;
    int n;
} Tangent;

static void tangent_step(Tangent *tg, const double sJ[2][2]) {
    const double x = sJ[0][0] * tg->w[0] + sJ[0][1] * tg->w[1], y = sJ[1][0] * tg->w[0] + sJ[1][1] * tg->w[1];
    const double norm = hypot(x, y);
    ++tg->n;
    if (!(norm > 0.0) || !isfinite(norm)) { /* collapsed through sticking, or overflowed */
        tg->sum += norm > 0.0 ? 745.0 : -745.0;
        tg->w[0] = tg->w[1] = M_SQRT1_2;
        return;
    }
    tg->sum += log(norm);
    tg->w[0] = x / norm, tg->w[1] = y / norm;
}

/* The exponent of a periodic start: M periods with sensitivities, the log spectral radius of
 * their product over M; the state advances; 0 or an ending status. */
static int orbit_exponent(Stepper *st, ModelData *m, const AtlasRun *r, int M, int *k, double *t, double *lyap,
                          char *err, int errlen) {
    m->sensitivities = 1;
    double J[2][2] = {{1.0, 0.0}, {0.0, 1.0}};
    for (int i = 0; i < M; ++i) {
        sens_reset(m);
        const int s = one_period(st, m, r->theta, ++*k, t, err, errlen);
        if (s) return s;
        chain(m->sJ, J);
    }
    *lyap = log_spectral_radius(J) / M;
    return 0;
}

/* The orbits the pixel's earlier starts reached: a later start that lands on one (within the
 * matching tolerance, with the same wall entries) and follows it for `confirm` periods in a row
 * is that orbit, and stops. */
typedef struct {
    int n, m_max;
    const int *start;      /* [n]: the start that reached it */
    const int *period;     /* [k]: per start of the pixel */
    const double *points;  /* [k][m_max][2] */
    const int *entries;    /* [k][m_max] */
    double tol;
} PixelOrbits;

static int near(const PixelOrbits *po, int a, int j, double u, double v, int e) {
    const int s = po->start[a];
    const double *p = po->points + 2 * ((size_t)s * po->m_max + j);
    const double eps = po->tol * (1.0 + fabs(p[0]) + fabs(p[1]));
    return po->entries[(size_t)s * po->m_max + j] == e && fabs(u - p[0]) <= eps && fabs(v - p[1]) <= eps;
}

/* Follows a start over the known orbits: returns the orbit once confirmed, else -1. */
typedef struct {
    int cand, j, run;
} Follow;

static int follow(const PixelOrbits *po, Follow *f, double u, double v, int e) {
    if (po->n == 0) return -1;
    if (f->cand >= 0) {
        const int M = po->period[po->start[f->cand]], j = (f->j + 1) % M;
        if (near(po, f->cand, j, u, v, e)) {
            f->j = j;
            if (++f->run >= (2 * M > 4 ? 2 * M : 4)) return f->cand;
            return -1;
        }
    }
    f->cand = -1;
    for (int a = 0; a < po->n && f->cand < 0; ++a)
        for (int j = 0; j < po->period[po->start[a]]; ++j)
            if (near(po, a, j, u, v, e)) {
                f->cand = a, f->j = j, f->run = 1;
                break;
            }
    return -1;
}

/* How far the last M states are from the M before them (relative, as the tolerance; infinite
 * when the wall entries differ). */
static double residual(const double *hu, const double *hv, const int *he, int h, int k, int M) {
    double worst = 0.0;
    for (int j = 0; j < M; ++j) {
        const int a = (k - j) % h, b = (k - j - M) % h;
        if (he[a] != he[b]) return INFINITY;
        const double d = fmax(fabs(hu[a] - hu[b]), fabs(hv[a] - hv[b])) / (1.0 + fabs(hu[b]) + fabs(hv[b]));
        worst = fmax(worst, d);
    }
    return worst;
}

/* The smallest d | M with the M points (time order) repeating after d within `loose` and the same
 * wall entries: Newton on the M-period map also closes an orbit of period d | M (traversed M / d
 * times). The last d points and entries are moved to the front (NaN, -1 after them). */
static int reduce_period(double *pts, int *ents, int M, double loose) {
    for (int d = 1; d < M; ++d) {
        if (M % d) continue;
        int ok = 1;
        for (int j = 0; j + d < M && ok; ++j) {
            const double eps = loose * (1.0 + fabs(pts[2 * j]) + fabs(pts[2 * j + 1]));
            ok = ents[j] == ents[j + d] && fabs(pts[2 * j] - pts[2 * (j + d)]) <= eps &&
                 fabs(pts[2 * j + 1] - pts[2 * (j + d) + 1]) <= eps;
        }
        if (!ok) continue;
        for (int j = 0; j < d; ++j) {
            pts[2 * j] = pts[2 * (M - d + j)], pts[2 * j + 1] = pts[2 * (M - d + j) + 1];
            ents[j] = ents[M - d + j];
        }
        for (int j = d; j < M; ++j) pts[2 * j] = pts[2 * j + 1] = NAN, ents[j] = -1;
        return d;
    }
    return M;
}

/* A start not settled in n_max periods but near a period-M orbit (a multiplier near -1 or +1
 * contracts slowly): Newton on the M-period map from its state (u, v) at t0 = theta + k0, each
 * iteration M periods with the exact sensitivities, until M periods close within the tolerance
 * with the wall entries of the first iteration, and the orbit is stable (exponent < 0). 1 with
 * the orbit (points, entries, impacts, exponent) in o, pts, ents; 0 otherwise. */
static int settle(const ModelData *m0, double u, double v, int k0, const AtlasRun *r, int M, double *pts, int *ents,
                  AtlasOutcome *o, char *err, int errlen) {
    int first[ATLAS_MAX_PERIOD];
    for (int it = 0; it < SETTLE_ITERATIONS; ++it) {
        Stepper st;
        ModelData m;
        batch_start_at(&st, &m, m0, u, v, r->theta + k0);
        m.sensitivities = 1;
        double J[2][2] = {{1.0, 0.0}, {0.0, 1.0}}, t = r->theta + k0;
        int ok = 1, before = 0, imp = 0, sticks = 0;
        for (int i = 0; i < M && ok; ++i) {
            sens_reset(&m);
            ok = one_period(&st, &m, r->theta, k0 + i + 1, &t, err, errlen) == 0;
            const int e = m.impacts - before;
            before = m.impacts;
            if (it == 0) first[i] = e;
            ok = ok && e == first[i];
            chain(m.sJ, J);
            pts[2 * i] = m.u, pts[2 * i + 1] = m.v, ents[i] = e;
            imp += e;
            sticks |= m.mode == MODE_STICK || e >= CHATTER_ENTRIES;
        }
        const double du = m.u - u, dv = m.v - v, eps = r->tol * (1.0 + fabs(u) + fabs(v));
        stepper_free(&st);
        if (!ok) return 0;
        o->periods += M;
        if (fabs(du) <= eps && fabs(dv) <= eps) { /* an attractor only if stable: not a saddle in chaos */
            const double lyap = log_spectral_radius(J) / M;
            if (!(lyap < 0.0)) return 0;
            const int d = reduce_period(pts, ents, M, COLLAPSE_FACTOR * r->tol);
            o->status = ATLAS_PERIODIC, o->period = d, o->impacts = imp / (M / d), o->sticks = sticks, o->lyap = lyap;
            return 1;
        }
        const double a = 1.0 - J[0][0], b = -J[0][1], c = -J[1][0], d = 1.0 - J[1][1], det = a * d - b * c;
        if (!(fabs(det) > 1e-14)) return 0;
        u += (d * du - b * dv) / det;
        v += (-c * du + a * dv) / det;
    }
    return 0;
}

/* One start of one pixel's model: run to its periodic orbit (or n_max periods), then its exponent;
 * a start that lands on an orbit of `po` returns as status ATLAS_MATCHED with .period = its index. */
static AtlasOutcome run_start(const ModelData *m0, double u0, double v0, const AtlasRun *r,
                              const PixelOrbits *po, double *pts, int *ents, char *err, int errlen) {
    AtlasOutcome o = {ATLAS_APERIODIC, 0, 0, 0, 0, NAN};
    for (int i = 0; i < r->m_max; ++i) pts[2 * i] = pts[2 * i + 1] = NAN, ents[i] = -1;
    if (m0->wall == WALL_RIGID && (u0 > m0->u_wall || (u0 == m0->u_wall && v0 > 0.0))) {
        o.status = ATLAS_INVALID; /* the FMU refuses a start inside a rigid wall */
        return o;
    }
    ModelData m;
    Stepper st;
    batch_start_at(&st, &m, m0, u0, v0, r->theta);
    const int h = 2 * r->m_max;
    double hu[2 * ATLAS_MAX_PERIOD], hv[2 * ATLAS_MAX_PERIOD];
    int he[2 * ATLAS_MAX_PERIOD], hs[2 * ATLAS_MAX_PERIOD];
    double t = r->theta;
    int before = 0, k = 0, M = 0, matched = -1;
    Follow f = {-1, 0, 0};
    Tangent tg = {{M_SQRT1_2, M_SQRT1_2}, 0.0, 0};
    const int lyap_from = r->n_max - r->n_lyap; /* the last n_lyap periods carry the tangent vector */
    while (k < r->n_max && !M && matched < 0) {
        m.sensitivities = k >= lyap_from;
        if (m.sensitivities) sens_reset(&m);
        const int s = one_period(&st, &m, r->theta, ++k, &t, err, errlen);
        if (s) {
            o.status = s;
            break;
        }
        if (m.sensitivities) tangent_step(&tg, m.sJ);
        const int slot = k % h;
        hu[slot] = m.u, hv[slot] = m.v, he[slot] = m.impacts - before;
        hs[slot] = m.mode == MODE_STICK || he[slot] >= CHATTER_ENTRIES;
        before = m.impacts;
        matched = follow(po, &f, m.u, m.v, he[slot]);
        if (matched < 0 && k >= r->n_min && k >= h) M = recurrence(hu, hv, he, h, k, r->m_max, r->tol);
    }
    if (matched >= 0) {
        o.status = ATLAS_MATCHED, o.period = matched, o.periods = k;
        stepper_free(&st);
        return o;
    }
    if (M > 1) M = collapse(hu, hv, he, h, k, M, COLLAPSE_FACTOR * r->tol);
    for (int d = 1; d < M && M > 1; ++d) /* a period-d orbit still settling, seen as period M */
        if (M % d == 0 && residual(hu, hv, he, h, k, d) <= SETTLE_RESIDUAL &&
            settle(m0, hu[k % h], hv[k % h], k, r, d, pts, ents, &o, err, errlen)) {
            o.periods += k;
            stepper_free(&st);
            return o;
        }
    if (!M && o.status == ATLAS_APERIODIC && k >= h) { /* not settled: near an orbit, Newton closes it */
        for (int c = 1; c <= r->m_max; ++c)
            if (residual(hu, hv, he, h, k, c) <= SETTLE_RESIDUAL &&
                settle(m0, hu[k % h], hv[k % h], k, r, c, pts, ents, &o, err, errlen)) {
                o.periods += k;
                stepper_free(&st);
                return o;
            }
        for (int i = 0; i < r->m_max; ++i) pts[2 * i] = pts[2 * i + 1] = NAN, ents[i] = -1;
    }
    if (o.status == ATLAS_APERIODIC) {
        for (int j = 0; j < (M ? M : 1); ++j) { /* the orbit's points, oldest first */
            const int slot = (k - (M ? M : 1) + 1 + j) % h;
            pts[2 * j] = hu[slot], pts[2 * j + 1] = hv[slot], ents[j] = he[slot];
            if (M) o.impacts += he[slot], o.sticks |= hs[slot]; /* an aperiodic start: neither */
        }
        o.period = M;
        const int s = M ? orbit_exponent(&st, &m, r, M, &k, &t, &o.lyap, err, errlen) : 0;
        if (!M) o.lyap = tg.n > 0 ? tg.sum / tg.n : NAN;
        o.status = s ? s : (M ? ATLAS_PERIODIC : ATLAS_APERIODIC);
    }
    o.periods = k;
    stepper_free(&st);
    return o;
}

BATCH_EXPORT int impact_atlas_max_period(void) { return ATLAS_MAX_PERIOD; }

/*
 * Runs n_pix pixels x k starts. The model of pixel p: the n_params base values, then the n_vary
 * values pix_values[p][0..n_vary) (e.g. sigma and the second parameter), checked as the FMU
 * checks them. Starts (u0, v0)[p * k + i] at t = theta. Outputs per start as in the file
 * comment; pix_ok[p] = 0 where the pixel's parameters are refused (its starts: ATLAS_FAILED).
 * Returns 0, or -1 with err naming the first refusal or failure (n_params base values refused:
 * nothing run).
 */
BATCH_EXPORT int impact_atlas_run(int n_params, const char *const *names, const double *values, int n_vary,
                                  const char *const *vary_names, long n_pix, const double *pix_values, int k,
                                  const double *u0, const double *v0, double theta, int n_min, int n_max,
                                  int m_max, double tol, double match_tol, int n_lyap, int threads, int *pix_ok, int *status,
                                  int *period, int *impacts, int *periods, unsigned char *sticks, double *lyap,
                                  double *points, char *err, int errlen) {
    err[0] = '\0';
    ModelData base;
    if (batch_build_model(&base, n_params, names, values, err, errlen) != 0) return -1;
    if (m_max < 1 || m_max > ATLAS_MAX_PERIOD) {
        snprintf(err, (size_t)errlen, "the largest period must be in 1..%d, got %d", ATLAS_MAX_PERIOD, m_max);
        return -1;
    }
    if (k < 1 || k > ATLAS_MAX_STARTS) {
        snprintf(err, (size_t)errlen, "the starts per pixel must be in 1..%d, got %d", ATLAS_MAX_STARTS, k);
        return -1;
    }
    const AtlasRun r = {theta, tol, match_tol, n_min, n_max, m_max, n_lyap};
    ModelData *models = malloc((size_t)(n_pix > 0 ? n_pix : 1) * sizeof *models);
    if (!models) {
        snprintf(err, (size_t)errlen, "out of memory for %ld pixels", n_pix);
        return -1;
    }
    int failed = 0;
    for (long p = 0; p < n_pix; ++p) {
        char msg[400];
        models[p] = base;
        pix_ok[p] = batch_finish_model(&models[p], n_vary, vary_names, pix_values + (size_t)p * n_vary, msg,
                                       (int)sizeof msg) == 0;
        if (!pix_ok[p] && !failed) {
            snprintf(err, (size_t)errlen, "pixel %ld: %s", p, msg);
            failed = 1;
        }
    }
    int *ents = malloc((size_t)(n_pix > 0 ? n_pix : 1) * (size_t)k * (size_t)m_max * sizeof *ents);
    if (!ents) {
        free(models);
        snprintf(err, (size_t)errlen, "out of memory for %ld pixels", n_pix);
        return -1;
    }
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads > 0 ? threads : 1)
#else
    (void)threads;
#endif
    for (long p = 0; p < n_pix; ++p) {
        const size_t i0 = (size_t)p * (size_t)k;
        int found[ATLAS_MAX_STARTS];
        PixelOrbits po = {0, m_max, found, period + i0, points + i0 * 2 * (size_t)m_max,
                          ents + i0 * (size_t)m_max, r.match_tol};
        AtlasRun rp = r; /* after an aperiodic start of the pixel: the shorter run (file comment) */
        for (int i = 0; i < k; ++i) {
            char msg[600];
            msg[0] = '\0';
            const size_t at = i0 + (size_t)i;
            AtlasOutcome o = {ATLAS_FAILED, 0, 0, 0, 0, NAN};
            double *pts = points + at * 2 * (size_t)m_max;
            int *e = ents + at * (size_t)m_max;
            if (pix_ok[p]) o = run_start(&models[p], u0[at], v0[at], &rp, &po, pts, e, msg, (int)sizeof msg);
            else for (int j = 0; j < 2 * m_max; ++j) pts[j] = NAN;
            if (o.status == ATLAS_MATCHED) { /* the earlier start's orbit, as that start reported it */
                const size_t src = i0 + (size_t)found[o.period];
                memcpy(pts, points + src * 2 * (size_t)m_max, 2 * (size_t)m_max * sizeof *pts);
                o.status = status[src], o.period = period[src], o.impacts = impacts[src];
                o.sticks = sticks[src], o.lyap = lyap[src];
            } else if (o.status == ATLAS_PERIODIC && po.n < ATLAS_MAX_STARTS) {
                found[po.n++] = i;
            }
            if (o.status == ATLAS_APERIODIC && rp.n_max == r.n_max) {
                rp.n_max = r.n_max / 2 > 2 * m_max ? r.n_max / 2 : 2 * m_max + 1;
                rp.n_lyap = r.n_lyap < rp.n_max / 2 ? r.n_lyap : rp.n_max / 2;
            }
            status[at] = o.status, period[at] = o.period, impacts[at] = o.impacts, periods[at] = o.periods;
            sticks[at] = (unsigned char)o.sticks, lyap[at] = o.lyap;
            if (o.status == ATLAS_FAILED && pix_ok[p]) {
#ifdef _OPENMP
#pragma omp critical
#endif
                {
                    if (!failed) snprintf(err, (size_t)errlen, "start (%.17g, %.17g) of pixel %ld: %s", u0[at], v0[at], p, msg);
                    failed = 1;
                }
            }
        }
    }
    free(ents);
    free(models);
    return failed ? -1 : 0;
}
