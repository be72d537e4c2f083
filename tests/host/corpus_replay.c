/*
 * The fuzzer's corpus (tests/fuzz_corpus/) replayed through a C importer, for the binaries of
 * every platform (tests/platforms/test_corpus.py; natively, under wine, under qemu-user). A port
 * of tests/fuzz/executor.py's actions and oracle: no Fatal, no non-finite value with status OK,
 * refused sets and state restores change nothing, a serialised state restores the same values,
 * Model Exchange and Co-Simulation calls refused on the other interface, "must_pass" actions
 * pass, "expect_error" sequences see a refusal, and after every sequence reset + initialisation
 * + one step work. tests/platforms/test_corpus.py writes the corpus as text (doubles as hex bits):
 *
 *   corpus_replay FMI2_BINARY FMI3_BINARY GUID < corpus.txt
 *
 * input:  "V2 nr vr.. ni vr.. nb vr.. timevr nx nind" and the same "V3 ..." (the variables of
 *         each model description), then per sequence "SEQ name interface expect_error", action
 *         lines "A repeat must_pass op args..." and "END".
 * output: per sequence "SEQ name", per action "A index op refusals-so-far", then "PASS" or
 *         "VIOLATION kind message".
 */
#include <inttypes.h>
#include <math.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
#define LOAD(path) ((void *)LoadLibraryA(path))
#define SYM(lib, name) ((void *)GetProcAddress((HMODULE)(lib), name))
#else
#include <dlfcn.h>
#define LOAD(path) dlopen(path, RTLD_NOW | RTLD_LOCAL)
#define SYM(lib, name) dlsym(lib, name)
#endif

#include "fmi2Functions.h"
#include "fmi3Functions.h"

#define MAXV 64
#define FATAL 4
typedef struct { int nr, ni, nb, timevr, nx, nind; unsigned r[MAXV], i[MAXV], b[MAXV]; } Vars;
typedef struct { int ok, n; double v[3 * MAXV]; } Snap;

static void *libs[2];
static Vars vars[2];
static const char *token;
static int v3, me, errors;           /* this sequence: FMI 3.0?, Model Exchange?, refusals so far */
static void *inst;
static void *slots[3];
static Snap slot_values[3];
static unsigned char *foreign_blob;
static size_t foreign_len;
static double me_time, start_time;
static jmp_buf violation;
static char message[512];

static double hexd(const char *s) { uint64_t b = strtoull(s, NULL, 16); double x; memcpy(&x, &b, 8); return x; }
static void *sym(int ver3, const char *name) {
    void *f = SYM(libs[ver3], name);
    if (!f) { fprintf(stderr, "missing %s\n", name); exit(3); }
    return f;
}
#define F2(name) ((name##TYPE *)sym(0, #name))
#define F3(name) ((name##TYPE *)sym(1, #name))

static void fail(const char *kind, const char *what) {
    snprintf(message, sizeof message, "%s %s", kind, what);
    longjmp(violation, 1);
}
static int check(const char *fn, int st) {
    if (st >= FATAL || st < 0) fail("fatal", fn);
    if (st >= 2) errors++;
    return st;
}
static void logger2(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c, fmi2String m, ...) {
    (void)e; (void)n; (void)s; (void)c; (void)m;
}
static void logger3(fmi3InstanceEnvironment e, fmi3Status s, fmi3String c, fmi3String m) {
    (void)e; (void)s; (void)c; (void)m;
}
static const fmi2CallbackFunctions cb2 = {logger2, calloc, free, NULL, NULL};

/* ---- the binding: one call per FMI function the actions use -------------------------------- */
static void *instantiate(int ver3, int as_me) {
    if (!ver3) return F2(fmi2Instantiate)("fuzz", as_me ? fmi2ModelExchange : fmi2CoSimulation, token, "file:///tmp", &cb2, 0, 1);
    if (as_me) return F3(fmi3InstantiateModelExchange)("fuzz", token, "/tmp", 0, 1, NULL, logger3);
    return F3(fmi3InstantiateCoSimulation)("fuzz", token, "/tmp", 0, 1, 0, 0, NULL, 0, NULL, logger3, NULL);
}
static void free_instance(void *c) { if (v3) F3(fmi3FreeInstance)(c); else F2(fmi2FreeInstance)(c); }
static int setup(void *c, double start, int tol_def, double tol) {
    return v3 ? 0 : F2(fmi2SetupExperiment)(c, tol_def, tol, start, 0, 0.0);
}
static int enter_init(void *c, double start, int tol_def, double tol) {
    return v3 ? F3(fmi3EnterInitializationMode)(c, tol_def, tol, start, 0, 0.0) : F2(fmi2EnterInitializationMode)(c);
}
static int exit_init(void *c) { return v3 ? F3(fmi3ExitInitializationMode)(c) : F2(fmi2ExitInitializationMode)(c); }
static int reset(void *c) { return v3 ? F3(fmi3Reset)(c) : F2(fmi2Reset)(c); }
static int get_reals(const unsigned *vr, int n, double *x) {
    return v3 ? F3(fmi3GetFloat64)(inst, vr, n, x, n) : F2(fmi2GetReal)(inst, vr, n, x);
}
static int get_ints(const unsigned *vr, int n, int *x) {
    return v3 ? F3(fmi3GetInt32)(inst, vr, n, x, n) : F2(fmi2GetInteger)(inst, vr, n, x);
}
static int get_bools(const unsigned *vr, int n, double *out) {
    int st, k;
    if (v3) { fmi3Boolean b[MAXV]; st = F3(fmi3GetBoolean)(inst, vr, n, b, n); for (k = 0; k < n; k++) out[k] = b[k]; }
    else { fmi2Boolean b[MAXV]; st = F2(fmi2GetBoolean)(inst, vr, n, b); for (k = 0; k < n; k++) out[k] = b[k]; }
    return st;
}
static int get_state(void *c, void **p) { return v3 ? F3(fmi3GetFMUState)(c, p) : F2(fmi2GetFMUstate)(c, p); }
static int set_state(void *p) { return v3 ? F3(fmi3SetFMUState)(inst, p) : F2(fmi2SetFMUstate)(inst, p); }
static int free_state(void *c, void **p) { return v3 ? F3(fmi3FreeFMUState)(c, p) : F2(fmi2FreeFMUstate)(c, p); }
static int serialize(void *c, void *p, unsigned char **data, size_t *n) {
    int st = v3 ? F3(fmi3SerializedFMUStateSize)(c, p, n) : F2(fmi2SerializedFMUstateSize)(c, p, n);
    if (st > 1) return st;
    *data = malloc(*n ? *n : 1);
    return v3 ? F3(fmi3SerializeFMUState)(c, p, *data, *n) : F2(fmi2SerializeFMUstate)(c, p, (fmi2Byte *)*data, *n);
}
static int deserialize(const unsigned char *d, size_t n, void **p) {
    return v3 ? F3(fmi3DeserializeFMUState)(inst, d, n, p) : F2(fmi2DeSerializeFMUstate)(inst, (const fmi2Byte *)d, n, p);
}
static int do_step(void *c, double t, double h) {
    fmi3Boolean a, b, e; fmi3Float64 last;
    return v3 ? F3(fmi3DoStep)(c, t, h, 1, &a, &b, &e, &last) : F2(fmi2DoStep)(c, t, h, 1);
}
static int set_time(void *c, double t) { return v3 ? F3(fmi3SetTime)(c, t) : F2(fmi2SetTime)(c, t); }
static int set_x(const double *x, int n) {
    return v3 ? F3(fmi3SetContinuousStates)(inst, x, n) : F2(fmi2SetContinuousStates)(inst, x, n);
}
static int me_get(char what, double *out, int n) {
    if (what == 'd') return v3 ? F3(fmi3GetContinuousStateDerivatives)(inst, out, n) : F2(fmi2GetDerivatives)(inst, out, n);
    if (what == 'x') return v3 ? F3(fmi3GetContinuousStates)(inst, out, n) : F2(fmi2GetContinuousStates)(inst, out, n);
    return v3 ? F3(fmi3GetEventIndicators)(inst, out, n) : F2(fmi2GetEventIndicators)(inst, out, n);
}
static int completed(void) {
    fmi2Boolean a2, b2; fmi3Boolean a3, b3;
    return v3 ? F3(fmi3CompletedIntegratorStep)(inst, 1, &a3, &b3) : F2(fmi2CompletedIntegratorStep)(inst, 1, &a2, &b2);
}
static int enter_event(void) { return v3 ? F3(fmi3EnterEventMode)(inst) : F2(fmi2EnterEventMode)(inst); }
static int update(void) {
    if (v3) { fmi3Boolean a, b, c, d, e; fmi3Float64 t; return F3(fmi3UpdateDiscreteStates)(inst, &a, &b, &c, &d, &e, &t); }
    fmi2EventInfo info; return F2(fmi2NewDiscreteStates)(inst, &info);
}
static int enter_cont(void) { return v3 ? F3(fmi3EnterContinuousTimeMode)(inst) : F2(fmi2EnterContinuousTimeMode)(inst); }

/* ---- the oracle's pieces -------------------------------------------------------------------- */
static Snap snapshot(void) {
    Snap s = {0, 0, {0}};
    Vars *V = &vars[v3];
    int iv[MAXV];
    if (V->nr && check("get real", get_reals(V->r, V->nr, s.v)) > 1) return s;
    for (int k = 0; k < V->nr; k++)
        if (!isfinite(s.v[k])) fail("nonfinite", "get real OK with a non-finite value");
    if (V->ni) { if (check("get int", get_ints(V->i, V->ni, iv)) > 1) return s; for (int k = 0; k < V->ni; k++) s.v[V->nr + k] = iv[k]; }
    if (V->nb && check("get bool", get_bools(V->b, V->nb, s.v + V->nr + V->ni)) > 1) return s;
    s.ok = 1;
    s.n = V->nr + V->ni + V->nb;
    return s;
}
static Snap snapshot_quiet(void) {
    jmp_buf saved; Snap s = {0, 0, {0}};
    memcpy(saved, violation, sizeof saved);
    if (!setjmp(violation)) s = snapshot();
    memcpy(violation, saved, sizeof saved);
    return s;
}
static int same(const Snap *a, const Snap *b) {
    if (a->n != b->n) return 0;
    for (int k = 0; k < a->n; k++)
        if (!(a->v[k] == b->v[k] || (isnan(a->v[k]) && isnan(b->v[k])))) return 0;
    return 1;
}
static double now(void) {
    double t = 0;
    if (me) return me_time;
    if (vars[v3].timevr >= 0) {
        unsigned vr = (unsigned)vars[v3].timevr;
        return check("get time", get_reals(&vr, 1, &t)) <= 1 ? t : 0.0;
    }
    return check("last time", F2(fmi2GetRealStatus)(inst, fmi2LastSuccessfulTime, &t)) <= 1 ? t : 0.0;
}
static int me_only(const char *fn, int st) {
    if (check(fn, st) <= 1 && !me) fail("cs-me-call", fn);
    return st;
}
static int me_vec(char what, double *out) {
    int n = what == 'i' ? vars[v3].nind : vars[v3].nx;
    int st = me_only("me_get", me_get(what, out, n));
    for (int k = 0; st <= 1 && k < n; k++)
        if (!isfinite(out[k])) fail("nonfinite", "me_get OK with a non-finite value");
    return st;
}
static void integrate(double h, int n) {
    double g[8], g2[8], x[8], dx[8];
    int nx = vars[v3].nx, ni = vars[v3].nind;
    if (!me || me_vec('i', g) > 1) return;
    for (int s = 0; s < n; s++) {
        if (me_vec('x', x) > 1 || me_vec('d', dx) > 1) return;
        double t = me_time + h;
        if (me_only("set_time", set_time(inst, t)) > 1) return;
        me_time = t;
        for (int k = 0; k < nx; k++) x[k] += h * dx[k];
        if (me_only("set_x", set_x(x, nx)) > 1) return;
        me_only("completed", completed());
        if (me_vec('i', g2) > 1) return;
        int crossed = 0;
        for (int k = 0; k < ni; k++) crossed |= (g[k] > 0) != (g2[k] > 0);
        if (crossed) {
            check("enter_event", enter_event());
            check("update", update());
            check("enter_cont", enter_cont());
            me_vec('i', g2);
        }
        memcpy(g, g2, sizeof g);
    }
    snapshot();
}
static int restore(void *p) {
    Snap before = snapshot_quiet();
    int st = check("set_state", set_state(p));
    if (st <= 1) snapshot();
    else if (before.ok) {
        Snap after = snapshot_quiet();
        if (after.ok && !same(&before, &after)) fail("not-atomic", "a refused state restore changed the variables");
    }
    return st;
}
/* tests/fuzz/executor.py corrupt(): the same damage, byte for byte */
static size_t corrupt(unsigned char *b, size_t n, const char *how, double pos, int bit, long offset) {
    if (!n || !strcmp(how, "none")) return n;
    size_t i = offset >= 0 ? (size_t)offset : (size_t)(pos * n);
    if (i > n - 1) i = n - 1;
    size_t i8 = i - i % 8;
    if (i8 > (n >= 8 ? n - 8 : 0)) i8 = n >= 8 ? n - 8 : 0;
    if (!strcmp(how, "bitflip")) b[i] ^= (unsigned char)(1u << bit);
    else if (!strcmp(how, "nan") || !strcmp(how, "inf")) {
        double x = !strcmp(how, "nan") ? NAN : -INFINITY;
        memcpy(b + i8, &x, n - i8 < 8 ? n - i8 : 8);
    } else if (!strcmp(how, "zero_word")) {
        size_t i4 = i - i % 4;
        memset(b + i4, 0, n - i4 < 4 ? n - i4 : 4);
    } else { fprintf(stderr, "corruption %s not ported\n", how); exit(2); }
    return n;
}
static void make_foreign(double h) {
    void *other = instantiate(v3, !me);
    void *p = NULL;
    free(foreign_blob); foreign_blob = NULL; foreign_len = 0;
    if (!other) return;
    check("foreign setup", setup(other, 0, 0, 0));
    check("foreign enter_init", enter_init(other, 0, 0, 0));
    check("foreign exit_init", exit_init(other));
    if (!me && h) set_time(other, h); else if (h) do_step(other, 0.0, h);
    if (get_state(other, &p) == 0 && serialize(other, p, &foreign_blob, &foreign_len) != 0) foreign_len = 0;
    free_state(other, &p);
    free_instance(other);
}

/* ---- one action line ---------------------------------------------------------------------- */
static void act(char *op, char **a) {
    if (!strcmp(op, "setup")) { start_time = hexd(a[0]); check("setup", setup(inst, start_time, strcmp(a[1], "-") != 0, strcmp(a[1], "-") ? hexd(a[1]) : 0)); }
    else if (!strcmp(op, "enter_init")) { me_time = start_time = hexd(a[0]); check("enter_init", enter_init(inst, start_time, strcmp(a[1], "-") != 0, strcmp(a[1], "-") ? hexd(a[1]) : 0)); }
    else if (!strcmp(op, "exit_init")) { if (check("exit_init", exit_init(inst)) <= 1) { me_time = start_time; snapshot(); } }
    else if (!strcmp(op, "reset")) check("reset", reset(inst));
    else if (!strcmp(op, "get_all")) snapshot();
    else if (!strcmp(op, "set")) {
        unsigned vr = (unsigned)atoi(a[1]);
        double before = 0, after = 0; int ib = 0, ia = 0, had;
        if (a[0][0] == 'r') {
            had = check("get", get_reals(&vr, 1, &before)) <= 1;
            double x = hexd(a[2]);
            int st = check("set", v3 ? F3(fmi3SetFloat64)(inst, &vr, 1, &x, 1) : F2(fmi2SetReal)(inst, &vr, 1, &x));
            if (st <= 1) snapshot();
            else if (had && check("get", get_reals(&vr, 1, &after)) <= 1 && !(before == after || (isnan(before) && isnan(after))))
                fail("not-atomic", "a refused set changed the value");
        } else {
            had = check("get", get_ints(&vr, 1, &ib)) <= 1;
            int x = atoi(a[2]);
            int st = check("set", v3 ? F3(fmi3SetInt32)(inst, &vr, 1, &x, 1) : F2(fmi2SetInteger)(inst, &vr, 1, &x));
            if (st <= 1) snapshot();
            else if (had && check("get", get_ints(&vr, 1, &ia)) <= 1 && ia != ib) fail("not-atomic", "a refused set changed the value");
        }
    } else if (!strcmp(op, "step")) {
        double t = hexd(a[1]), h = hexd(a[2]);
        if (!strcmp(a[0], "now")) t = now();
        if (check("doStep", do_step(inst, t, h)) <= 1) { if (me) fail("me-dostep", "a Model Exchange instance accepted doStep"); snapshot(); }
    } else if (!strcmp(op, "get_state")) {
        int s = atoi(a[0]); Snap before = snapshot_quiet(); void *p = slots[s];
        if (check("get_state", get_state(inst, &p)) <= 1) { slots[s] = p; slot_values[s] = before; }
    } else if (!strcmp(op, "set_state")) restore(slots[atoi(a[0])]);
    else if (!strcmp(op, "roundtrip")) {
        int s = atoi(a[0]); unsigned char *d = NULL; size_t n = 0; void *p = NULL;
        if (!slots[s]) return;
        if (check("serialize", serialize(inst, slots[s], &d, &n)) > 1) { free(d); return; }
        int st = check("deserialize", deserialize(d, n, &p));
        free(d);
        if (st > 1) fail("roundtrip", "own serialised state refused");
        if (restore(p) <= 1 && slot_values[s].ok) {
            Snap got = snapshot();
            if (got.ok && !same(&slot_values[s], &got)) fail("roundtrip", "restored values differ");
        }
        check("free_state", free_state(inst, &p));
    } else if (!strcmp(op, "deser")) {
        int s = atoi(a[0]); unsigned char *d = NULL; size_t n = 0;
        if (!strcmp(a[1], "foreign")) {
            if (!foreign_len) return;
            d = malloc(foreign_len); memcpy(d, foreign_blob, foreign_len); n = foreign_len;
        } else {
            void *src = slots[atoi(a[1] + 4)];
            if (!src) return;
            if (check("serialize", serialize(inst, src, &d, &n)) > 1) { free(d); return; }
        }
        if (!n) { free(d); return; }
        n = corrupt(d, n, a[2], hexd(a[3]), atoi(a[4]), atol(a[5]));
        void *p = slots[s];
        int st = check("deserialize", deserialize(d, n, &p));
        free(d);
        if (st <= 1) { slots[s] = p; slot_values[s].ok = 0; if (atoi(a[6])) restore(p); }
    } else if (!strcmp(op, "update")) { if (check("update", update()) <= 1) snapshot(); }
    else if (!strcmp(op, "enter_cont")) me_only("enter_cont", enter_cont());
    else if (!strcmp(op, "set_x")) { double x[8]; int n = atoi(a[0]); for (int k = 0; k < n; k++) x[k] = hexd(a[1 + k]); me_only("set_x", set_x(x, n)); }
    else if (!strcmp(op, "me_get")) { double out[8]; me_vec(a[0][0], out); }
    else if (!strcmp(op, "integrate")) integrate(hexd(a[0]), atoi(a[1]));
    else if (!strcmp(op, "foreign")) make_foreign(hexd(a[0]));
    else { fprintf(stderr, "unknown action %s\n", op); exit(2); }
}

static void probe(void) {
    const char *fn = "reset";
    if (check(fn, reset(inst)) > 1 || check(fn = "setup", setup(inst, 0, 0, 0)) > 1 ||
        check(fn = "enter_init", enter_init(inst, 0, 0, 0)) > 1 || check(fn = "exit_init", exit_init(inst)) > 1)
        fail("bricked", fn);
    me_time = 0;
    if (me) integrate(1e-3, 3);
    else if (check("doStep", do_step(inst, 0.0, 0.1)) > 1) fail("bricked", "doStep after reset failed");
    if (!snapshot().ok) fail("bricked", "values not readable after reset and initialisation");
}

static void read_vars(Vars *V) {
    int k;
    if (scanf(" %d", &V->nr) != 1) exit(2);
    for (k = 0; k < V->nr; k++) if (scanf(" %u", &V->r[k]) != 1) exit(2);
    if (scanf(" %d", &V->ni) != 1) exit(2);
    for (k = 0; k < V->ni; k++) if (scanf(" %u", &V->i[k]) != 1) exit(2);
    if (scanf(" %d", &V->nb) != 1) exit(2);
    for (k = 0; k < V->nb; k++) if (scanf(" %u", &V->b[k]) != 1) exit(2);
    if (scanf(" %d %d %d", &V->timevr, &V->nx, &V->nind) != 3) exit(2);
}

int main(int argc, char **argv) {
    static char line[8192], name[256], itf[32];
    int expect_error;
    if (argc != 4) { fprintf(stderr, "usage: corpus_replay FMI2_BINARY FMI3_BINARY GUID < corpus.txt\n"); return 2; }
    for (int k = 0; k < 2; k++)
        if (!(libs[k] = LOAD(argv[1 + k]))) { fprintf(stderr, "cannot load %s\n", argv[1 + k]); return 3; }
    token = argv[3];
    if (scanf(" V2") != 0) return 2;
    read_vars(&vars[0]);
    if (scanf(" V3") != 0) return 2;
    read_vars(&vars[1]);
    while (scanf(" SEQ %255s %31s %d", name, itf, &expect_error) == 3) {
        volatile int index = 0, failed = 0;
        v3 = itf[3] == '3';
        me = !strcmp(itf + 4, "me");
        errors = 0;
        memset(slots, 0, sizeof slots);
        printf("SEQ %s\n", name);
        inst = instantiate(v3, me);
        if (!inst) { printf("VIOLATION instantiate valid instantiation refused\n"); failed = 1; }
        if (!failed && setjmp(violation)) { printf("VIOLATION %s\n", message); failed = 1; }
        while (fgets(line, sizeof line, stdin)) {
            char *tok[16], *op;
            int n = 0, repeat, must_pass;
            if (!strncmp(line, "END", 3)) break;
            if (line[0] != 'A' || failed) continue;
            for (char *p = strtok(line + 1, " \n"); p && n < 16; p = strtok(NULL, " \n")) tok[n++] = p;
            repeat = atoi(tok[0]); must_pass = atoi(tok[1]); op = tok[2];
            int before = errors;
            for (int r = 0; r < repeat; r++) act(op, tok + 3);
            if (must_pass && errors > before) fail("refused-valid", op);
            printf("A %d %s %d\n", index++, op, errors);
        }
        if (!failed) {
            if (setjmp(violation)) {
                printf("VIOLATION %s\n", message);
            } else {
                snapshot_quiet();
                if (expect_error && !errors) fail("accepted-extreme", "every call of the sequence returned OK");
                probe();
                printf("PASS\n");
            }
        }
        for (int k = 0; k < 3; k++) if (slots[k] && inst) free_state(inst, &slots[k]);
        if (inst) free_instance(inst);
        inst = NULL;
    }
    fflush(stdout);
    return 0;
}
