/*
 * Bare C driver of the closed-form solver (fmu_src/closed_form.c): the same code the FMU runs
 * with solver = 1, called directly, without FMI or Python. One advance_to of one period per
 * period through the stepper interface (fmu_src/stepper.h), as the FMU's doStep does, with the
 * sensitivities optional.
 *
 * Built by bench/sens_bench.py (and the tests):
 *   cc -O2 -I fmu_src bench/cf_driver.c fmu_src/closed_form.c fmu_src/stepper.c fmu_src/sens.c
 *      fmu_src/model.c -lm
 * With -DWITH_CVODE (and fmu_src/stepper_methods.c, fmu_src/solver_cvode.c and SUNDIALS linked) it
 * runs the stepper the FMU chooses for `solver`: CVODE with solver=0 given, else the closed form.
 * Usage:
 *   cf_driver T0 PERIODS REPEAT SENS OUT.bin [NAME=VALUE]...
 * NAME is nu, Omega, sigma, r, Gamma, wall, u0, v0. The timed loop is run REPEAT times from the
 * same start; each prints "run WALL CPU". OUT.bin receives, for the last run, PERIODS records
 * of 9 doubles: u, v, impacts, J_uu, J_uv, J_vu, J_vv, S_u, S_v after each period (the
 * derivatives of that period's end w.r.t. its start).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "closed_form.h"
#include "model.h"
#include "sens.h"
#include "stepper.h"

static double now(clockid_t clock) {
    struct timespec ts;
    clock_gettime(clock, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int set_param(ModelData *m, const char *arg) {
    char name[32];
    double x;
    if (sscanf(arg, "%31[^=]=%lf", name, &x) != 2) return -1;
    if (!strcmp(name, "nu")) m->nu = x;
    else if (!strcmp(name, "Omega")) m->Omega = x;
    else if (!strcmp(name, "sigma")) m->sigma = x;
    else if (!strcmp(name, "r")) m->r = x;
    else if (!strcmp(name, "Gamma")) m->Gamma = x;
    else if (!strcmp(name, "wall")) m->wall = (int)x;
    else if (!strcmp(name, "u0")) m->u0 = x;
    else if (!strcmp(name, "v0")) m->v0 = x;
    else if (!strcmp(name, "solver")) m->solver = (int)x;
    else if (!strcmp(name, "rtol")) m->rtol = x;
    else if (!strcmp(name, "atol")) m->atol = x;
    else return -1;
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 6) {
        fprintf(stderr, "usage: %s T0 PERIODS REPEAT SENS OUT.bin [NAME=VALUE]...\n", argv[0]);
        return 2;
    }
    const double t0 = atof(argv[1]);
    const long periods = atol(argv[2]);
    const int repeat = atoi(argv[3]);
    const int sens = atoi(argv[4]);
    const char *outpath = argv[5];
    ModelData m0;
    model_set_defaults(&m0);
    m0.solver = SOLVER_CLOSED_FORM;
    for (int k = 6; k < argc; ++k)
        if (set_param(&m0, argv[k]) != 0) {
            fprintf(stderr, "bad parameter %s\n", argv[k]);
            return 2;
        }
    m0.sensitivities = sens;
    model_update_derived(&m0);
    double *out = malloc(sizeof(double) * 9 * (size_t)(periods > 0 ? periods : 1));
    for (int run = 0; run < repeat; ++run) {
        static ModelData m; /* static: CVODE keeps a pointer to it */
        m = m0;
        Stepper st;
        memset(&st, 0, sizeof st);
#ifdef WITH_CVODE
        if (stepper_select(&st, &m) != 0) {
#else
        st.ops = &STEPPER_CLOSED_FORM;
        if (st.ops->create(&st, &m) != 0) {
#endif
            fprintf(stderr, "%s\n", st.clk.msg);
            return 1;
        }
        stepper_start(&st, t0);
        model_initialize_state(&m, st.clk.tau);
        const double w0 = now(CLOCK_MONOTONIC), c0 = now(CLOCK_PROCESS_CPUTIME_ID);
        for (long k = 0; k < periods; ++k) {
            if (sens) sens_reset(&m);
            if (stepper_advance_to(&st, &m, t0 + (double)(k + 1), 0) != 0) {
                fprintf(stderr, "period %ld: %s\n", k, st.clk.msg);
                free(out);
                return 1;
            }
            double *o = out + 9 * k;
            o[0] = m.u;
            o[1] = m.v;
            o[2] = m.impacts;
            o[3] = m.sJ[0][0];
            o[4] = m.sJ[0][1];
            o[5] = m.sJ[1][0];
            o[6] = m.sJ[1][1];
            o[7] = m.sS[0];
            o[8] = m.sS[1];
        }
        const double w1 = now(CLOCK_MONOTONIC), c1 = now(CLOCK_PROCESS_CPUTIME_ID);
        printf("run %.9f %.9f\n", w1 - w0, c1 - c0);
        stepper_free(&st);
    }
    FILE *f = fopen(outpath, "wb");
    if (!f || fwrite(out, sizeof(double) * 9, (size_t)periods, f) != (size_t)periods) {
        fprintf(stderr, "cannot write %s\n", outpath);
        return 1;
    }
    fclose(f);
    free(out);
    return 0;
}
