/*
 * The FMI core shared by the FMI 2.0 (fmi2.c) and FMI 3.0 (fmi3.c) glue, Co-Simulation and
 * Model Exchange alike (the counterpart of the Reference FMUs' cosimulation.c). One instance type
 * and one API, implemented by one unit per concern:
 *   fmu_states.c    the state machine (STATE_TABLE; shared with the twin's C front)
 *   fmu_core.c      the instance's life cycle, logging, core_allowed
 *   fmu_vars.c      the variable table (get/set by value reference, each value's valid range)
 *   fmu_snapshot.c  FMU-state snapshots (versioned, tagged with the interface, checksummed and
 *                   validated field by field)
 *   fmu_cs.c        the Co-Simulation stepping loop
 *   fmu_me.c        the Model Exchange calls and the event mode of FMI 3.0 Co-Simulation
 *   fmu_derivatives.c  directional and adjoint derivatives (the model's exact partials)
 * The physics is the model's (model.h: its checks, derived quantities and outputs are calls
 * into model.c) and the integration the stepper's (stepper.h). The glue files only translate
 * types and status codes.
 *
 * Adding a variable is one entry in fmu_src/variables.py, then `python
 * fmu_src/generate_variables.py` (it writes the VR enum, the rows of VARS[], the defaults, both
 * modelDescription files, the docs' tables and the twin's declarations), plus its field in
 * ModelData if it is stored there (or its getter in fmu_vars.c). Snapshots: see the comment
 * above Snapshot in fmu_snapshot.c.
 */
#ifndef IMPACT_FMU_CORE_H
#define IMPACT_FMU_CORE_H

#include <stddef.h>

#include "fmu_states.h"
#include "model.h"
#include "stepper.h"

/* Status codes: the same numbers as fmi2Status and fmi3Status. */
typedef enum { CORE_OK = 0, CORE_WARNING = 1, CORE_DISCARD = 2, CORE_ERROR = 3 } CoreStatus;

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
    /* Model Exchange: the wall's position at the last event (or the start, or a restored state):
     * a mass far beyond a rigid wall that has moved since is the wall's jump (the input-jump
     * rule), one beyond a wall that has not moved is an importer's state no mode holds. */
    double me_wall;
    int inputs_changed; /* an input jumped since the last step: apply model_input_jump */
    ModelData m;
    Stepper st; /* the integration method chosen by m.solver, and its clock */
} CoreInstance;

/* Bounds on times the FMU accepts: |t| <= CORE_MAX_TIME (beyond, one period is below the
 * resolution of a double's fractional part and steps would silently do nothing). */
#define CORE_MAX_TIME 1e9
/* Bound on continuous states (u, v) set by an importer or restored from a snapshot. */
#define CORE_MAX_STATE 1e15

/* -- life cycle (fmu_core.c) ----------------------------------------------------------- */
CoreInstance *core_instantiate(const char *name, CoreInterface iface, void *env, CoreLogFn log,
                               CoreCallocFn calloc_fn, CoreFreeFn free_fn, int logging);
void core_free(CoreInstance *c);
/* Logs (errors always, others only with debug logging on). */
void core_log(CoreInstance *c, int status, const char *category, const char *fmt, ...);
/* Logs an error "fn: message" and returns CORE_ERROR. */
int core_fail(CoreInstance *c, const char *fn, const char *fmt, ...);
/* The state machine (fmu_states.c, STATE_TABLE): 1 if the FMI function named fn may be called in
 * the instance's state, else 0 (c NULL), or logs, moves the instance to its error state and
 * returns 0. Every entry point calls it first. */
int core_allowed(CoreInstance *c, const char *fn);
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

/* -- variables (fmu_vars.c) ------------------------------------------------------------ */
typedef enum { VT_REAL = 0, VT_INTEGER = 1, VT_BOOLEAN = 2 } CoreVarType;
int core_get(CoreInstance *c, const char *fn, CoreVarType t, const unsigned vr[], size_t n,
             double out[]);
int core_set(CoreInstance *c, const char *fn, CoreVarType t, const unsigned vr[], size_t n,
             const double in[]);
/* FMI 2.0 input derivatives (order 1 used, higher orders ignored with a warning). */
int core_set_input_derivatives(CoreInstance *c, const char *fn, const unsigned vr[], size_t n,
                               const int order[], const double value[]);
const char *core_variable_name(unsigned vr);

/* -- FMU state (fmu_snapshot.c) -------------------------------------------------------- */
int core_get_state(CoreInstance *c, const char *fn, void **state);
int core_set_state(CoreInstance *c, const char *fn, const void *state);
int core_free_state(CoreInstance *c, const char *fn, void **state);
int core_serialized_size(CoreInstance *c, const char *fn, const void *state, size_t *size);
int core_serialize(CoreInstance *c, const char *fn, const void *state, unsigned char *bytes,
                   size_t size);
int core_deserialize(CoreInstance *c, const char *fn, const unsigned char *bytes, size_t size,
                     void **state);

/* -- Co-Simulation (fmu_cs.c) ---------------------------------------------------------------
 * One communication step from t to t + h. stop_at_event: return at the first wall event (the
 * jump left pending, *event_needed = 1). intermediate, if not NULL, is called at each wall event
 * (before its jump) and returns nonzero to request an early return there. */
typedef int (*CoreIntermediateFn)(CoreInstance *c, double t_event);
int core_do_step(CoreInstance *c, const char *fn, double t, double h, int stop_at_event,
                 CoreIntermediateFn intermediate, int *event_needed, int *early_return,
                 double *last_time);
double core_time(const CoreInstance *c);

/* -- Model Exchange and FMI 3.0 CS event mode (fmu_me.c) ------------------------------ */
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

/* -- exact partial derivatives (fmu_derivatives.c) -----------------------------------------
 * Knowns: the states u, v and the inputs F_ext, u_wall; unknowns: der(u), der(v), the outputs,
 * (FMI 3.0) the event indicator. Directional: out[i] = sum_j d unknown_i / d known_j seed[j]
 * (seed over the knowns); adjoint: out[j] = sum_i seed[i] d unknown_i / d known_j (seed over
 * the unknowns). */
int core_directional_derivative(CoreInstance *c, const char *fn, const unsigned unknowns[],
                                size_t nu, const unsigned knowns[], size_t nk,
                                const double seed[], double out[]);
int core_adjoint_derivative(CoreInstance *c, const char *fn, const unsigned unknowns[],
                            size_t nu, const unsigned knowns[], size_t nk, const double seed[],
                            double out[]);

/* -- shared by the core's units (fmu_core.c) ---------------------------------------------- */
/* What the getters read: c itself, or in Initialization Mode a copy in *buf holding the state the
 * start values give (model_initialize_state at the start time), so that the initial unknowns
 * (u, v, der(u), der(v), F_contact, in_contact, the indicator) answer the start values set so far
 * rather than the defaults; exiting Initialization Mode computes the same state. */
const CoreInstance *core_view(const CoreInstance *c, CoreInstance *buf);
/* The model's local time now: the stepper's (Co-Simulation) or the importer's (Model Exchange). */
double core_local_tau(const CoreInstance *c);
/* The importer's allocator (or calloc/free). */
void *core_alloc(CoreInstance *c, size_t n);
void core_release(CoreInstance *c, void *p);
/* The stepper for the instance's m.solver (fmu_core.c): CORE_OK, or the error of fn. */
int core_select_stepper(CoreInstance *c, const char *fn);

#endif
