/*
 * The FMU's variables (fmu_vars.c): the value references, the variable table's row type, and what
 * the snapshot unit (fmu_snapshot.c) needs of the table. The FMI calls on variables (core_get,
 * core_set, core_set_input_derivatives, core_variable_name) are declared in fmu_core.h.
 */
#ifndef IMPACT_FMU_VARS_H
#define IMPACT_FMU_VARS_H

#include <stddef.h>

#include "fmu_core.h"

/* Value references: the names in modelDescription.xml are the interface, these numbers its
 * implementation. Keep both in step. */
typedef enum {
    VR_NU = 0,
    VR_OMEGA = 1,
    VR_SIGMA = 2,
    VR_R = 3,
    VR_GAMMA = 4,
    VR_WALL = 5,
    VR_U0 = 6,
    VR_V0 = 7,
    VR_RTOL = 8,
    VR_ATOL = 9,
    VR_F_G = 10,
    VR_PHI = 11,
    VR_KAPPA = 12,
    VR_U = 13,
    VR_V = 14,
    VR_IMPACTS = 15,
    VR_IN_CONTACT = 16,
    /* added after the FMI 2.0 CS interface was fixed: contact laws, Model Exchange */
    VR_CONTACT = 17,       /* Integer: 0 linear, 1 Hertz, 2 Hunt-Crossley */
    VR_HC_ALPHA = 18,      /* Hunt-Crossley damping factor */
    VR_DER_U = 19,         /* der(u) (Model Exchange) */
    VR_DER_V = 20,         /* der(v) (Model Exchange) */
    VR_WALL_INDICATOR = 21, /* the event indicator g0 (FMI 3.0 Model Exchange) */
    VR_TIME = 22,          /* FMI 3.0 independent variable (handled by the FMI glue) */
    /* ports (issue 14) and limits (issue 13) */
    VR_F_EXT = 23,         /* input: external force added to the right-hand side */
    VR_U_WALL = 24,        /* input: wall position (contact when u > u_wall) */
    VR_F_CONTACT = 25,     /* output: the wall's force on the mass, repulsive positive */
    VR_V_IMPACT = 26,      /* output: relative velocity at the last wall entry, before the jump */
    VR_T_IMPACT = 27,      /* output: time of the last wall entry */
    VR_MAX_EVENTS = 28,    /* parameter: wall events allowed per unit of time */
    VR_MAX_STEPS = 29,     /* parameter: CVODE steps allowed per unit of time */
    /* issue 11: sensitivities and the closed-form solver (23..29: ports and limits, fmu_core) */
    VR_SENSITIVITIES = 30, /* Boolean parameter */
    VR_SOLVER = 31,        /* Integer parameter: 0 CVODE, 1 closed form */
    VR_J_UU = 32,          /* outputs: d(u, v)(end of doStep)/d(u, v)(its start) */
    VR_J_UV = 33,
    VR_J_VU = 34,
    VR_J_VV = 35,
    VR_S_U = 36,           /* outputs: d(u, v)(end of doStep)/d sigma */
    VR_S_V = 37,
    VR_COUNT
} ValueReference;

typedef enum {
    K_FIXED = 'f',      /* parameter, settable before initialisation ends */
    K_TUNABLE = 't',    /* parameter, also settable after (c->tunable_states) */
    K_INPUT = 'i',      /* input, settable in every state but Terminated/Error */
    K_CALCULATED = 'c', /* calculated parameter */
    K_OUTPUT = 'o',
    K_LOCAL = 'l',
    K_INDEPENDENT = 'x', /* FMI 3.0 time */
} Kind;

typedef struct {
    unsigned vr;
    const char *name;
    CoreVarType type;
    Kind kind;
    size_t off;      /* offset of its double (Real) or int (Integer/Boolean) in ModelData */
    double lo, hi;   /* valid range of a settable value (also checked on snapshots) */
    int lo_open;     /* lo excluded */
    double (*get)(const CoreInstance *c); /* computed values (off == NO_FIELD) */
    int fmi3_only;
} VarDef;

/* The table's rows, in order (n of them). */
const VarDef *vars_table(size_t *n);
/* The row of vr for instance c (NULL: none, or FMI 3.0 only and c is FMI 2.0). */
const VarDef *vars_find(const CoreInstance *c, unsigned vr);
/* Parameters and inputs. */
int vars_settable(const VarDef *d);
/* Why x is not a valid value of d (NULL if it is); buf receives the message. */
const char *vars_check_value(const VarDef *d, double x, char *buf, size_t n);
/* d's value stored in m (d->off != NO_FIELD). */
double vars_field_get(const ModelData *m, const VarDef *d);

#endif
