/*
 * The batch kernel: the closed-form stepper (closed_form.c) run for many starts at once, for basin
 * scans. Not a second implementation of the physics: each start is the FMU's own sequence of
 * calls -- model_set_defaults, the parameters, model_update_derived and its checks, stepper_start
 * at t0 = theta, model_initialize_state, then one advance_to per forcing period to the same
 * t_end the FMU computes from the harness's doStep (t + (target - t)) -- so its stroboscopic
 * points are the FMU's closed-form mode's, bit for bit.
 *
 * Early stopping (recurrence on the stroboscopic section). The caller passes the attractors
 * found so far: per attractor its period p, its p stroboscopic points in orbit order, the
 * wall entries of the period that ends on each point and how many periods in a row confirm it.
 * After every period the state is compared with them in the max norm; a start whose state
 * lands within `tol` (the tolerance the attractors are told apart with) of point j of an
 * attractor, and then on point j+1, j+2, ... (cyclically) with the right wall entries each
 * period, for that attractor's `confirm` periods in a row, is labelled with it and stops. Any other start runs the whole transient and its
 * samples come back to the caller, which classifies them (and so finds new attractors).
 *
 * Early stopping on recurrence (recur_tol > 0, for starts run without known attractors): after
 * every period from n_samples on, a start whose last n_samples states repeat with a shift
 * M <= max_period -- the caller's periodicity test (harness classify_orbit: max norm, threshold
 * recur_tol (1 + the largest peak-to-peak range of u and v over them), the same wall entries) --
 * stops, and those states come back as its samples. The caller passes recur_tol well below its
 * own tolerance: the samples then pass its test too, converged far enough that a smaller period
 * still settling (a multiplier near -1 seen as period 2M first) passes it as well.
 *
 * Early stopping when aperiodic (aperiodic_tol > 0): a start whose samples so far already rule
 * out every shift M <= max_period of the caller's periodicity test -- for each M a pair of
 * samples M apart with other wall entries, or farther apart than aperiodic_tol (1 + the largest
 * range of the samples so far) -- and that no known attractor can recognise any more before its
 * last period (its run, or a fresh one, would end beyond it) stops with status BATCH_APERIODIC,
 * its samples so far filled in. The caller (harness/runs/basins/kernel_scan.py) passes its
 * periodicity tolerance times 1 + ten times the spread of its starts: the rest of the samples could
 * then pass its test only by widening their range by more than ten times that spread, far beyond
 * every orbit the starts were drawn around, so the start ends not periodic as when run in full, but
 * for sticking, chatter or a failure in the periods it does not run (its samples so far say
 * whether it stuck or chattered). A chaotic start stops at the first sample after max_period of
 * them (the 13th of 24) instead of the last.
 *
 * Starts are independent: OpenMP spreads them over `threads` threads (dynamic schedule: early
 * stops make their costs uneven); ctypes releases the GIL while it runs.
 *
 * Built by fmu_src/CMakeLists.txt into build/fmu/libimpact_batch.so; loaded by
 * harness/fmu/batch_kernel.py.
 */
#include <math.h>
#include <stdio.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "batch.h"
#include "closed_form.h"
#include "model.h"
#include "stepper.h"

#ifdef _OPENMP
#include <omp.h>
#endif

/* Per-start status (the `status` output). */
enum { BATCH_RAN = 0, BATCH_MATCHED = 1, BATCH_INVALID = 2, BATCH_FAILED = 3, BATCH_ESCAPED = 4,
       BATCH_APERIODIC = 5 };

/* The settable values ModelData stores, by name: generated from fmu_src/variables.py, so a
 * parameter added there is known here without an edit. */
typedef struct {
    const char *name;
    size_t offset; /* in ModelData */
    int integer;   /* stored as int (Integer, Boolean), else double */
} ParamField;
static const ParamField PARAMS[] = {
#include "model_params.inc"
};

/* The method's own settings: this kernel is the closed form from the given start, whatever they say. */
static const char *const IGNORED[] = {"solver", "rtol", "atol", "sensitivities", "u0", "v0"};

int batch_set_param(ModelData *m, const char *name, double x) {
    for (size_t i = 0; i < sizeof IGNORED / sizeof IGNORED[0]; ++i)
        if (!strcmp(name, IGNORED[i])) return 0;
    for (size_t i = 0; i < sizeof PARAMS / sizeof PARAMS[0]; ++i) {
        if (strcmp(name, PARAMS[i].name)) continue;
        char *field = (char *)m + PARAMS[i].offset;
        if (PARAMS[i].integer) *(int *)field = (int)x;
        else *(double *)field = x;
        return 0;
    }
    return -1;
}

int batch_build_model(ModelData *m, int n_params, const char *const *names, const double *values,
                      char *err, int errlen) {
    model_set_defaults(m);
    return batch_finish_model(m, n_params, names, values, err, errlen);
}

int batch_finish_model(ModelData *m, int n_params, const char *const *names, const double *values,
                       char *err, int errlen) {
    for (int i = 0; i < n_params; ++i)
        if (batch_set_param(m, names[i], values[i]) != 0) {
            snprintf(err, (size_t)errlen, "the batch kernel does not know the parameter %s", names[i]);
            return -1;
        }
    m->solver = SOLVER_CLOSED_FORM;
    m->sensitivities = 0;
    model_update_derived(m);
    char buf[300];
    const char *why = model_check_consistency(m, buf, sizeof buf);
    if (!why) why = model_check_derived(m, buf, sizeof buf);
    if (!why) why = closed_form_unsupported(m);
    if (why) {
        snprintf(err, (size_t)errlen, "%s", why);
        return -1;
    }
    return 0;
}

/* The attractors known to the early stop. */
typedef struct {
    int n, width;          /* attractors; points per attractor in the arrays (largest period) */
    const int *period;     /* [n] */
    const double *points;  /* [n][width][2] */
    const int *entries;    /* [n][width]: wall entries of the period that ends on the point */
    double tol;
    const int *confirm;    /* [n]: consecutive periods on the orbit that recognise a start */
    int min_confirm;       /* the smallest of them (at least 1) */
} Known;

/* The point j of an attractor whose state z is within tol of it (with the same wall entries),
 * searching every attractor; returns the attractor (and *j) or -1. */
static int find_point(const Known *k, double u, double v, int entries, int *j) {
    for (int a = 0; a < k->n; ++a)
        for (int i = 0; i < k->period[a]; ++i) {
            const double *p = k->points + 2 * ((size_t)a * k->width + i);
            if (fabs(u - p[0]) <= k->tol && fabs(v - p[1]) <= k->tol &&
                k->entries[(size_t)a * k->width + i] == entries) {
                *j = i;
                return a;
            }
        }
    return -1;
}

/* Whether the state continues the recurrence on attractor a from point j (to j + 1). */
static int next_point(const Known *k, int a, int j, double u, double v, int entries) {
    const int i = (j + 1) % k->period[a];
    const double *p = k->points + 2 * ((size_t)a * k->width + i);
    return fabs(u - p[0]) <= k->tol && fabs(v - p[1]) <= k->tol &&
           k->entries[(size_t)a * k->width + i] == entries;
}

typedef struct {
    int label, periods, status;
} Outcome;

/* The recurrence stop (file comment): its tolerance (0: off), largest shift, and the ring of the
 * last n states (slot k % n holds period k's). */
typedef struct {
    double tol;
    int max_period, n;
    double *u, *v;
    int *imp;
    unsigned char *stuck;
} Recur;

void batch_start_at(Stepper *st, ModelData *m, const ModelData *m0, double u, double v, double t) {
    *m = *m0;
    m->u0 = u;
    m->v0 = v;
    memset(st, 0, sizeof *st);
    st->ops = &STEPPER_CLOSED_FORM;
    st->ops->create(st, m);
    stepper_start(st, t);
    m->origin = st->clk.origin;
    m->in_tau = st->clk.tau;
    model_initialize_state(m, st->clk.tau);
}

/* The aperiodic stop (file comment): its tolerance (0: off), the shifts tried, which of them the
 * samples so far already rule out, how many, and the samples' ranges so far. */
typedef struct {
    double tol;
    int max_period, n_out;
    unsigned char *out; /* [max_period + 1]: shift M ruled out */
    double ulo, uhi, vlo, vhi;
} Aperiodic;

/* With sample s (0-based) just written: whether every shift M <= max_period is ruled out, by a
 * pair of samples M apart whose wall entries differ or whose difference exceeds the tolerance
 * times (1 + the samples' largest range so far). */
static int aperiodic(Aperiodic *ap, const double *us, const double *vs, const int *imp, int s) {
    ap->ulo = fmin(ap->ulo, us[s]), ap->uhi = fmax(ap->uhi, us[s]);
    ap->vlo = fmin(ap->vlo, vs[s]), ap->vhi = fmax(ap->vhi, vs[s]);
    const double thr = ap->tol * (1.0 + fmax(ap->uhi - ap->ulo, ap->vhi - ap->vlo));
    for (int M = 1; M <= ap->max_period && M <= s; ++M)
        if (!ap->out[M] && (imp[s] != imp[s - M] || fabs(us[s] - us[s - M]) > thr || fabs(vs[s] - vs[s - M]) > thr)) {
            ap->out[M] = 1;
            ++ap->n_out;
        }
    return ap->n_out >= ap->max_period;
}

/* Whether a known attractor may still recognise the start by the end of its run (period `total`),
 * at period k with the run `run` on attractor `cand` (-1: none). */
static int may_confirm(const Known *k, int cand, int run, int at, int total) {
    if (k->n == 0) return 0;
    if (cand >= 0 && at + (k->confirm[cand] < 1 ? 1 : k->confirm[cand]) - run <= total) return 1;
    return at + k->min_confirm <= total;
}

/* Whether the last r->n states, the newest at period k, repeat with some shift M <= max_period. */
static int recurs(const Recur *r, int k) {
    const int n = r->n;
    double ulo = INFINITY, uhi = -INFINITY, vlo = INFINITY, vhi = -INFINITY;
    for (int i = 0; i < n; ++i) {
        ulo = fmin(ulo, r->u[i]), uhi = fmax(uhi, r->u[i]);
        vlo = fmin(vlo, r->v[i]), vhi = fmax(vhi, r->v[i]);
    }
    const double thr = r->tol * (1.0 + fmax(uhi - ulo, vhi - vlo));
    for (int M = 1; M <= r->max_period; ++M) {
        int ok = 1;
        for (int j = 0; j + M < n && ok; ++j) { /* newest pairs first: a start far from it fails at once */
            const int a = (k - j) % n, b = (k - j - M) % n;
            ok = fabs(r->u[a] - r->u[b]) <= thr && fabs(r->v[a] - r->v[b]) <= thr && r->imp[a] == r->imp[b];
        }
        if (ok) return 1;
    }
    return 0;
}

/* One start: the FMU's initialisation and doStep sequence (file comment), with the early stop. */
static Outcome run_start(const ModelData *m0, double u0, double v0, double theta, int n_transient,
                         int n_samples, const Known *known, Recur *rec, Aperiodic *ap, double *us, double *vs,
                         int *imp, unsigned char *stuck, char *err, int errlen) {
    Outcome o = {-1, 0, BATCH_RAN};
    if (m0->wall == WALL_RIGID && (u0 > m0->u_wall || (u0 == m0->u_wall && v0 > 0.0))) {
        o.status = BATCH_INVALID; /* the FMU refuses a start inside a rigid wall */
        return o;
    }
    ModelData m;
    Stepper st;
    batch_start_at(&st, &m, m0, u0, v0, theta);
    double t = theta;
    int before = 0, cand = -1, cj = 0, run = 0;
    const int total = n_transient + n_samples;
    for (int k = 1; k <= total; ++k) {
        const double target = theta + (double)k;
        const double t_end = t + (target - t); /* what the FMU's doStep(t, target - t) reaches */
        if (stepper_advance_to(&st, &m, t_end, 0) != 0) {
            o.status = BATCH_FAILED;
            snprintf(err, (size_t)errlen, "start (%.17g, %.17g), t = %.17g: %s", u0, v0, t_end, st.clk.msg);
            break;
        }
        t = t_end;
        o.periods = k;
        if (!(fabs(m.u) <= ESCAPE_BOUND && fabs(m.v) <= ESCAPE_BOUND)) {
            o.status = BATCH_ESCAPED;
            break;
        }
        const int entries = m.impacts - before;
        before = m.impacts;
        if (k > n_transient) {
            const int s = k - n_transient - 1;
            us[s] = m.u;
            vs[s] = m.v;
            imp[s] = entries;
            stuck[s] = m.mode == MODE_STICK;
        }
        if (rec->tol > 0.0) {
            const int slot = k % rec->n;
            rec->u[slot] = m.u, rec->v[slot] = m.v, rec->imp[slot] = entries;
            rec->stuck[slot] = m.mode == MODE_STICK;
            if (k >= rec->n && k < total && recurs(rec, k)) { /* its last n_samples states, oldest first */
                for (int s = 0; s < n_samples; ++s) {
                    const int slot_s = (k - n_samples + 1 + s) % rec->n;
                    us[s] = rec->u[slot_s], vs[s] = rec->v[slot_s];
                    imp[s] = rec->imp[slot_s], stuck[s] = rec->stuck[slot_s];
                }
                break;
            }
        }
        if (known->n > 0) {
            if (cand >= 0 && next_point(known, cand, cj, m.u, m.v, entries)) {
                cj = (cj + 1) % known->period[cand];
                ++run;
            } else {
                cand = find_point(known, m.u, m.v, entries, &cj);
                run = cand >= 0;
            }
            if (cand >= 0 && run >= (known->confirm[cand] < 1 ? 1 : known->confirm[cand])) {
                o.label = cand;
                o.status = BATCH_MATCHED;
                break;
            }
        }
        if (ap->tol > 0.0 && k > n_transient && k < total && aperiodic(ap, us, vs, imp, k - n_transient - 1) &&
            !may_confirm(known, cand, run, k, total)) {
            o.status = BATCH_APERIODIC;
            break;
        }
    }
    stepper_free(&st);
    return o;
}

/* Library version: the loader refuses a stale build. */
BATCH_EXPORT int impact_batch_version(void) { return BATCH_VERSION; }

BATCH_EXPORT int impact_batch_threads(void) {
#ifdef _OPENMP
    return omp_get_max_threads();
#else
    return 1;
#endif
}

/*
 * Runs n starts (u0[i], v0[i]) at t = theta for n_transient + n_samples periods each, or until
 * recognised as one of the n_known attractors (file comment; n_known = 0: no early stop;
 * confirm[a] < 1 counts as 1), or until their last n_samples states repeat (recur_tol > 0, shifts
 * up to max_period, at most n_samples - 1; file comment), or until their samples rule out a
 * period (aperiodic_tol > 0, the same shifts; file comment).
 * Outputs per start: label (the attractor, or -1), periods run, status (BATCH_*), and the
 * samples of the last n_samples periods (u, v, wall entries, sticking at the sample), left as
 * they were for periods not reached. Returns 0, or -1 with err set: the parameters are refused
 * (nothing run), or some start failed (its status says which; err names the first).
 */
BATCH_EXPORT int impact_batch_run(int n_params, const char *const *names, const double *values,
                                  long n, const double *u0, const double *v0, double theta,
                                  int n_transient, int n_samples, int n_known, int width,
                                  const int *known_period, const double *known_points,
                                  const int *known_entries, double tol, const int *confirm,
                                  double recur_tol, int max_period, double aperiodic_tol, int threads, int *label,
                                  int *periods, int *status, double *u_out, double *v_out,
                                  int *imp_out, unsigned char *stuck_out, char *err, int errlen) {
    ModelData m0;
    err[0] = '\0';
    if (batch_build_model(&m0, n_params, names, values, err, errlen) != 0) return -1;
    Known known = {n_known, width, known_period, known_points, known_entries, tol, confirm, 0};
    for (int a = 0; a < n_known; ++a) {
        const int c = confirm[a] < 1 ? 1 : confirm[a];
        if (a == 0 || c < known.min_confirm) known.min_confirm = c;
    }
    if (max_period > n_samples - 1) max_period = n_samples - 1;
    if (max_period < 1 || n_samples < 2) recur_tol = 0.0, aperiodic_tol = 0.0;
    int failed = 0;
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 8) num_threads(threads > 0 ? threads : 1)
#else
    (void)threads;
#endif
    for (long i = 0; i < n; ++i) {
        char msg[600];
        msg[0] = '\0';
        const size_t off = (size_t)i * (size_t)n_samples;
        Recur rec = {0.0, max_period, n_samples, NULL, NULL, NULL, NULL};
        void *ring = recur_tol > 0.0 ? malloc((size_t)n_samples * (2 * sizeof(double) + sizeof(int) + 1)) : NULL;
        if (ring) {
            rec.tol = recur_tol;
            rec.u = ring;
            rec.v = rec.u + n_samples;
            rec.imp = (int *)(rec.v + n_samples);
            rec.stuck = (unsigned char *)(rec.imp + n_samples);
        }
        Aperiodic ap = {0.0, max_period, 0, NULL, INFINITY, -INFINITY, INFINITY, -INFINITY};
        if (aperiodic_tol > 0.0 && (ap.out = calloc((size_t)max_period + 1, 1)) != NULL) ap.tol = aperiodic_tol;
        const Outcome o = run_start(&m0, u0[i], v0[i], theta, n_transient, n_samples, &known, &rec, &ap,
                                    u_out + off, v_out + off, imp_out + off, stuck_out + off, msg,
                                    (int)sizeof msg);
        free(ring);
        free(ap.out);
        label[i] = o.label;
        periods[i] = o.periods;
        status[i] = o.status;
        if (o.status == BATCH_FAILED) {
#ifdef _OPENMP
#pragma omp critical
#endif
            {
                if (!failed) snprintf(err, (size_t)errlen, "%s", msg);
                failed = 1;
            }
        }
    }
    return failed ? -1 : 0;
}
