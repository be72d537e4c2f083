/*
 * The FMI core shared by the FMI 2.0 (fmi2_cs.c) and FMI 3.0 (fmi3.c) glue, Co-Simulation and
 * Model Exchange alike (the counterpart of the Reference FMUs' cosimulation.c): the instance and
 * its state machine, logging, argument checks, the variable table (get/set by value reference,
 * with each value's valid range), FMU-state snapshots (versioned, tagged with the interface,
 * checksummed and validated field by field), the Co-Simulation stepping loop and the Model
 * Exchange calls. The glue files only translate types and status codes.
 *
 * Adding a variable is one entry in fmu_src/variables.py, then `python
 * fmu_src/generate_variables.py` (it writes the VR enum, the rows of VARS[], the defaults, both
 * modelDescription files, the docs' tables and the twin's declarations), plus its field in
 * ModelData if it is stored there (or its getter in fmu_core.c). Snapshots: see the comment
 * above Snapshot in fmu_core.c.
 */
#ifndef IMPACT_FMU_CORE_H
#define IMPACT_FMU_CORE_H

#include <stddef.h>

#include "model.h"
#include "solver.h"

/* Status codes: the same numbers as fmi2Status and fmi3Status. */
typedef enum { CORE_OK = 0, CORE_WARNING = 1, CORE_DISCARD = 2, CORE_ERROR = 3 } CoreStatus;

/* Instance states (bit flags, so that a set of allowed states is one mask). */
enum {
    CS_INSTANTIATED = 1 << 0,
    CS_INIT = 1 << 1,
    CS_STEP = 1 << 2,
    CS_EVENT = 1 << 3,
    CS_CONT = 1 << 4,
    CS_TERMINATED = 1 << 5,
    CS_ERROR = 1 << 6,
    CS_INTERMEDIATE = 1 << 7, /* FMI 3.0 Co-Simulation: inside the intermediateUpdate callback */
    CS_FATAL = 1 << 8,        /* never entered: no call of this FMU answers Fatal */
};
#define CS_ANY 0x1ff
#define CS_RUN (CS_STEP | CS_EVENT | CS_CONT) /* initialised, not terminated */

/* Which interface an instance (and its snapshots) belongs to. */
typedef enum { IF_FMI2_CS = 1, IF_FMI2_ME = 2, IF_FMI3_CS = 3, IF_FMI3_ME = 4 } CoreInterface;

/* The glue's logger: status as above, message already formatted. */
typedef void (*CoreLogFn)(void *env, const char *instance_name, int status,
                          const char *category, const char *message);
typedef void *(*CoreCallocFn)(size_t n, size_t size);
typedef void (*CoreFreeFn)(void *p);

typedef struct CoreInstance {
    char *name;
    void *env;
    CoreLogFn log;
    CoreCallocFn calloc_fn;
    CoreFreeFn free_fn;
    int logging;
    CoreInterface iface;
    int is_me;
    int fmi3;
    int event_mode_used, early_return_allowed; /* FMI 3.0 Co-Simulation */
    int state;
    /* states in which a tunable parameter may be set (FMI 2.0 and 3.0 differ) */
    int tunable_states;
    double start_time;
    double me_time; /* Model Exchange: the time set by the importer */
    int inputs_changed; /* an input jumped since the last step: apply model_input_jump */
    ModelData m;
    Solver s;
} CoreInstance;

/* Bounds on times the FMU accepts: |t| <= CORE_MAX_TIME (beyond, one period is below the
 * resolution of a double's fractional part and steps would silently do nothing). */
#define CORE_MAX_TIME 1e9
/* Bound on continuous states (u, v) set by an importer or restored from a snapshot. */
#define CORE_MAX_STATE 1e15

/* -- life cycle -------------------------------------------------------------------------- */
CoreInstance *core_instantiate(const char *name, CoreInterface iface, void *env, CoreLogFn log,
                               CoreCallocFn calloc_fn, CoreFreeFn free_fn, int logging);
void core_free(CoreInstance *c);
/* Logs (errors always, others only with debug logging on). */
void core_log(CoreInstance *c, int status, const char *category, const char *fmt, ...);
/* Logs an error "fn: message" and returns CORE_ERROR. */
int core_fail(CoreInstance *c, const char *fn, const char *fmt, ...);
/* The state machine (fmu_core.c, STATE_TABLE): 1 if the FMI function named fn may be called in
 * the instance's state, else 0 (c NULL), or logs, moves the instance to its error state and
 * returns 0. Every entry point calls it first. */
int core_allowed(CoreInstance *c, const char *fn);
/* The states in which fn may be called by an instance of interface iface (event_mode: FMI 3.0
 * Co-Simulation instantiated with eventModeUsed); -1 for a function the table does not know. */
int core_allowed_states(CoreInterface iface, int event_mode, const char *fn);
/* The state an instance enters when a call returns Error (FMI 2.0: Error; FMI 3.0: Terminated). */
int core_error_state(const CoreInstance *c);

/* fmi2/fmi3SetDebugLogging: the categories must be the modelDescription's LogCategories. */
int core_set_logging(CoreInstance *c, const char *fn, int on, size_t n,
                     const char *const categories[]);

int core_setup(CoreInstance *c, const char *fn, int tol_defined, double tol, double start);
int core_enter_init(CoreInstance *c, const char *fn);
int core_exit_init(CoreInstance *c, const char *fn);
int core_terminate(CoreInstance *c, const char *fn);
int core_reset(CoreInstance *c, const char *fn);

/* -- variables --------------------------------------------------------------------------- */
typedef enum { VT_REAL = 0, VT_INTEGER = 1, VT_BOOLEAN = 2 } CoreVarType;
int core_get(CoreInstance *c, const char *fn, CoreVarType t, const unsigned vr[], size_t n,
             double out[]);
int core_set(CoreInstance *c, const char *fn, CoreVarType t, const unsigned vr[], size_t n,
             const double in[]);
/* FMI 2.0 input derivatives (order 1 used, higher orders ignored with a warning). */
int core_set_input_derivatives(CoreInstance *c, const char *fn, const unsigned vr[], size_t n,
                               const int order[], const double value[]);
const char *core_variable_name(unsigned vr);

/* -- FMU state ---------------------------------------------------------------------------- */
int core_get_state(CoreInstance *c, const char *fn, void **state);
int core_set_state(CoreInstance *c, const char *fn, const void *state);
int core_free_state(CoreInstance *c, const char *fn, void **state);
int core_serialized_size(CoreInstance *c, const char *fn, const void *state, size_t *size);
int core_serialize(CoreInstance *c, const char *fn, const void *state, unsigned char *bytes,
                   size_t size);
int core_deserialize(CoreInstance *c, const char *fn, const unsigned char *bytes, size_t size,
                     void **state);

/* -- Co-Simulation ---------------------------------------------------------------------------
 * One communication step from t to t + h. stop_at_event: return at the first wall event (the
 * jump left pending, *event_needed = 1). intermediate, if not NULL, is called at each wall event
 * (before its jump) and returns nonzero to request an early return there. */
typedef int (*CoreIntermediateFn)(CoreInstance *c, double t_event);
int core_do_step(CoreInstance *c, const char *fn, double t, double h, int stop_at_event,
                 CoreIntermediateFn intermediate, int *event_needed, int *early_return,
                 double *last_time);
double core_time(const CoreInstance *c);

/* -- Model Exchange (and FMI 3.0 CS event mode) ---------------------------------------- */
int core_enter_event_mode(CoreInstance *c, const char *fn);
/* The discrete-state update: ME applies the wall event the importer stopped at; CS applies the
 * jump of an early return. *values_changed: the continuous state changed. */
int core_update_discrete(CoreInstance *c, const char *fn, int *values_changed);
int core_enter_continuous_mode(CoreInstance *c, const char *fn);
int core_enter_step_mode(CoreInstance *c, const char *fn);
int core_set_time(CoreInstance *c, const char *fn, double t);
int core_set_states(CoreInstance *c, const char *fn, const double x[], size_t n);
int core_get_states(CoreInstance *c, const char *fn, double x[], size_t n);
int core_get_derivatives(CoreInstance *c, const char *fn, double dx[], size_t n);
int core_get_event_indicators(CoreInstance *c, const char *fn, double g[], size_t n);
int core_get_nominals(CoreInstance *c, const char *fn, double x[], size_t n);
int core_completed_step(CoreInstance *c, const char *fn, int *enter_event, int *terminate);

#endif
