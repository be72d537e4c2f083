/*
 * What the batch kernel's units share (batch.c: basin scans; batch_atlas.c: parameter planes):
 * the model of a run built from parameter names and values, checked as the FMU checks it at the
 * end of initialisation, and the escape bound. Not part of the FMU.
 */
#ifndef IMPACT_BATCH_H
#define IMPACT_BATCH_H

#include "model.h"
#include "stepper.h"

#define BATCH_EXPORT __attribute__((visibility("default")))

/* The library's version: harness/fmu/batch_kernel.py refuses another (a stale build). */
#define BATCH_VERSION 5

/* Above this |u| or |v| a start has escaped (the FMU's own bound is 1e15, CORE_MAX_STATE). */
static const double ESCAPE_BOUND = 1e12;

/* Sets one settable value of ModelData by its FMU name (the method's own settings -- solver,
 * tolerances, sensitivities, start values -- are ignored); -1 for an unknown name. */
int batch_set_param(ModelData *m, const char *name, double x);

/* model_set_defaults, then batch_finish_model. */
int batch_build_model(ModelData *m, int n_params, const char *const *names, const double *values,
                      char *err, int errlen);

/* Sets the values on m, the closed form as its solver, the derived values, and the FMU's checks;
 * 0, or -1 with err naming what is refused. */
int batch_finish_model(ModelData *m, int n_params, const char *const *names, const double *values,
                       char *err, int errlen);

/* A start (u, v) at time t as the FMU makes one: m from m0 with those start values, a fresh
 * closed-form stepper started at t, and the model's state (contact mode) initialised there. */
void batch_start_at(Stepper *st, ModelData *m, const ModelData *m0, double u, double v, double t);

#endif
