/*
 * FMU state snapshots: core_get_state, core_set_state, core_free_state, core_serialized_size,
 * core_serialize, core_deserialize (fmu_core.h), called by the glue (fmi2.c, fmi3.c).
 *
 * The in-memory FMU state and its serialised form are the same bytes: a header (magic, format
 * version, interface tag, size), the instance's data, and a 64-bit FNV-1a checksum over all of
 * it. Restoring checks the header, the checksum and then every field (ranges as for set, the
 * FMI state word against the states this interface can be saved in, mode against wall model,
 * finite and bounded states and times); a bad one is refused with a message and the instance is
 * left exactly as it was. Extending it: add the field to Snapshot (before checksum), copy it in
 * snapshot_take/snapshot_restore, check it in snapshot_check, bump SNAPSHOT_VERSION. The model's
 * own fields are checked by the model (model_check_restored), the variables' ranges by the
 * variable table (fmu_vars.h), the clock here. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fmu_vars.h"

#define SNAPSHOT_MAGIC 0x494d504fu /* "IMPO" */
#define SNAPSHOT_VERSION 4u /* ModelData's layout: bumped whenever a field is added */

typedef struct {
    uint32_t magic, version, iface, size;
    int32_t state;
    int32_t inputs_changed;
    double start_time, me_time;
    ModelData m;
    double origin, tau;
    long events, guard_hits;
    int32_t pending;
    int32_t reserved;
    uint64_t checksum; /* over every byte before it */
} Snapshot;

static uint64_t fnv1a(const void *p, size_t n) {
    const unsigned char *b = (const unsigned char *)p;
    uint64_t h = 1469598103934665603ull;
    for (size_t i = 0; i < n; ++i) {
        h ^= b[i];
        h *= 1099511628211ull;
    }
    return h;
}

static uint64_t snapshot_sum(const Snapshot *s) { return fnv1a(s, offsetof(Snapshot, checksum)); }

static void snapshot_take(CoreInstance *c, Snapshot *s) {
    memset(s, 0, sizeof *s);
    s->magic = SNAPSHOT_MAGIC;
    s->version = SNAPSHOT_VERSION;
    s->iface = (uint32_t)c->iface;
    s->size = (uint32_t)sizeof *s;
    s->state = c->state;
    s->inputs_changed = c->inputs_changed;
    s->start_time = c->start_time;
    s->me_time = c->me_time;
    memcpy(&s->m, &c->m, sizeof s->m);
    s->origin = c->st.clk.origin;
    s->tau = c->st.clk.tau;
    s->events = c->st.clk.events;
    s->guard_hits = c->st.clk.guard_hits;
    s->pending = c->st.clk.pending;
    s->checksum = snapshot_sum(s);
    /* CVODE's step history is not part of the snapshot; restarting the live instance here too
     * makes "continue" and "restore, then continue" follow the very same computation. */
    c->st.clk.restart = 1;
}

static int finite_within(double x, double bound) { return isfinite(x) && fabs(x) <= bound; }

/* The header: this FMU's format, intact, of c's interface, taken in a state c can be in. */
static const char *check_header(const CoreInstance *c, const Snapshot *s, char *buf, size_t n) {
    if (s->magic != SNAPSHOT_MAGIC) return "not a state of this FMU (bad magic word)";
    if (s->version != SNAPSHOT_VERSION || s->size != sizeof *s) {
        snprintf(buf, n, "state format version %u, size %u: this FMU reads version %u, size %zu",
                 (unsigned)s->version, (unsigned)s->size, SNAPSHOT_VERSION, sizeof *s);
        return buf;
    }
    if (s->checksum != snapshot_sum(s)) return "checksum mismatch (the state is corrupted)";
    if (s->iface != (uint32_t)c->iface) {
        snprintf(buf, n, "a state of an %s instance cannot be set into an %s instance",
                 s->iface <= 4 ? core_interface_name((CoreInterface)s->iface) : "unknown",
                 core_interface_name(c->iface));
        return buf;
    }
    int savable = ST_INSTANTIATED | ST_INIT | ST_TERMINATED;
    if (!c->fmi3) savable |= ST_ERROR; /* fmi2GetFMUstate is allowed in Error */
    savable |= c->is_me ? (ST_EVENT | ST_CONT) : ST_STEP;
    if (!c->is_me && c->event_mode_used) savable |= ST_EVENT;
    const int st = s->state;
    if (!(st & savable) || (st & (st - 1))) {
        snprintf(buf, n, "FMI state word %d is not a state this instance can be restored to", st);
        return buf;
    }
    return NULL;
}

/* The model's data: every settable variable in its range, then the model's own checks. */
static const char *check_model(const CoreInstance *c, const Snapshot *s, char *buf, size_t n) {
    size_t n_vars;
    const VarDef *vars = vars_table(&n_vars);
    for (size_t i = 0; i < n_vars; ++i) {
        const VarDef *d = &vars[i];
        if (!vars_settable(d)) continue;
        const char *why = vars_check_value(d, vars_field_get(&s->m, d), buf, n);
        if (why) {
            char tmp[200];
            snprintf(tmp, sizeof tmp, "field %s %s", d->name, why);
            snprintf(buf, n, "%s", tmp);
            return buf;
        }
    }
    ModelData trial;
    memcpy(&trial, &s->m, sizeof trial);
    model_update_derived(&trial);
    if (model_check_derived(&trial, buf, n)) return buf;
    return model_check_restored(&s->m, c->is_me, CORE_MAX_STATE, CORE_MAX_TIME);
}

/* Ramped inputs: the values they give at the state's own time must lie in the inputs' ranges,
 * as a value set there would (each field within its bound still allows a slope of 1e6 from a
 * reference time 2e9 away). The inputs' getters read them at the clock's time. */
static const char *check_ramped_inputs(const CoreInstance *c, const Snapshot *s, char *buf,
                                       size_t n) {
    if (!model_has_ramps(&s->m)) return NULL;
    CoreInstance view;
    memcpy(&view, c, sizeof view);
    memcpy(&view.m, &s->m, sizeof view.m);
    view.st.clk.tau = s->tau;
    size_t n_vars;
    const VarDef *vars = vars_table(&n_vars);
    for (size_t i = 0; i < n_vars; ++i) {
        const VarDef *d = &vars[i];
        if (d->kind != K_INPUT) continue;
        const double x = d->get(&view);
        const char *bad = vars_check_value(d, x, buf, n);
        if (bad) {
            char tmp[200];
            snprintf(tmp, sizeof tmp, "ramped input %s = %g at the state's time %s", d->name, x,
                     bad);
            snprintf(buf, n, "%s", tmp);
            return buf;
        }
    }
    return NULL;
}

/* The clock's times and the instance's flags. */
static const char *check_clock(const CoreInstance *c, const Snapshot *s) {
    if (!finite_within(s->start_time, CORE_MAX_TIME) ||
        !finite_within(s->me_time, 2 * CORE_MAX_TIME))
        return "start or Model Exchange time not finite or beyond 1e9";
    if (!finite_within(s->origin, 2 * CORE_MAX_TIME) || s->origin != floor(s->origin) ||
        !(s->tau >= 0.0) || !finite_within(s->tau, 2 * CORE_MAX_TIME))
        return "solver time (origin, local time) not finite, out of range or not integral";
    /* the model's time origin follows the solver's while a Co-Simulation runs (model.h) */
    if (!c->is_me && (s->state & (ST_STEP | ST_EVENT | ST_TERMINATED)) && s->m.origin != s->origin)
        return "the model's and the solver's time origins differ";
    if (s->pending != 0 && (s->pending != 1 || c->is_me)) return "bad pending-event flag";
    if (s->inputs_changed != 0 && s->inputs_changed != 1) return "bad input flag";
    return NULL;
}

/* NULL if the snapshot may be restored into c, else why not (in buf). */
static const char *snapshot_check(const CoreInstance *c, const Snapshot *s, char *buf,
                                  size_t n) {
    const char *why = check_header(c, s, buf, n);
    if (!why) why = check_model(c, s, buf, n);
    if (!why && (s->events < 0 || s->guard_hits < 0)) why = "negative event counter";
    if (!why) why = check_ramped_inputs(c, s, buf, n);
    if (!why) why = check_clock(c, s);
    return why;
}

static void snapshot_restore(CoreInstance *c, const Snapshot *s) {
    c->state = s->state;
    c->inputs_changed = s->inputs_changed;
    c->start_time = s->start_time;
    c->me_time = s->me_time;
    memcpy(&c->m, &s->m, sizeof c->m);
    model_update_derived(&c->m); /* recomputed, never trusted */
    c->st.clk.origin = s->origin;
    c->st.clk.tau = s->tau;
    c->st.clk.events = s->events;
    c->st.clk.guard_hits = s->guard_hits;
    c->st.clk.pending = s->pending;
    c->st.clk.restart = 1;
    c->me_wall = model_wall_position(&c->m, core_local_tau(c));
}


int core_get_state(CoreInstance *c, const char *fn, void **state) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (!state) return core_fail(c, fn, "NULL argument");
    Snapshot *s = *state ? (Snapshot *)*state : core_alloc(c, sizeof(Snapshot));
    if (!s) return core_fail(c, fn, "out of memory");
    snapshot_take(c, s);
    *state = s;
    return CORE_OK;
}

int core_set_state(CoreInstance *c, const char *fn, const void *state) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (!state) return core_fail(c, fn, "NULL state");
    char buf[300];
    const char *why = snapshot_check(c, (const Snapshot *)state, buf, sizeof buf);
    if (why) return core_fail(c, fn, "state refused, instance unchanged: %s", why);
    snapshot_restore(c, (const Snapshot *)state);
    return core_select_stepper(c, fn); /* the state's own solver */
}

int core_free_state(CoreInstance *c, const char *fn, void **state) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (state && *state) {
        core_release(c, *state);
        *state = NULL;
    }
    return CORE_OK;
}

int core_serialized_size(CoreInstance *c, const char *fn, const void *state, size_t *size) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (!size || !state || ((const Snapshot *)state)->magic != SNAPSHOT_MAGIC)
        return core_fail(c, fn, "not a state of this FMU");
    *size = sizeof(Snapshot);
    return CORE_OK;
}

int core_serialize(CoreInstance *c, const char *fn, const void *state, unsigned char *bytes,
                   size_t size) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (!bytes || size < sizeof(Snapshot) || !state ||
        ((const Snapshot *)state)->magic != SNAPSHOT_MAGIC)
        return core_fail(c, fn, "bad state or buffer too small");
    memcpy(bytes, state, sizeof(Snapshot));
    return CORE_OK;
}

int core_deserialize(CoreInstance *c, const char *fn, const unsigned char *bytes, size_t size,
                     void **state) {
    if (!core_allowed(c, fn)) return CORE_ERROR;
    if (!bytes || !state || size != sizeof(Snapshot))
        return core_fail(c, fn, "%zu bytes are not a serialised state of this FMU (expected "
                         "%zu)", size, sizeof(Snapshot));
    Snapshot tmp;
    memcpy(&tmp, bytes, sizeof tmp);
    char buf[300];
    const char *why = snapshot_check(c, &tmp, buf, sizeof buf);
    if (why) return core_fail(c, fn, "not a valid serialised state of this instance: %s", why);
    Snapshot *s = *state ? (Snapshot *)*state : core_alloc(c, sizeof(Snapshot));
    if (!s) return core_fail(c, fn, "out of memory");
    memcpy(s, &tmp, sizeof tmp);
    *state = s;
    return CORE_OK;
}
