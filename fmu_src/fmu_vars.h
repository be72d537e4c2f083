/*
 * The FMU's variables (fmu_vars.c): the value references, the variable table's row type, and what
 * the snapshot unit (fmu_snapshot.c) needs of the table. The FMI calls on variables (core_get,
 * core_set, core_set_input_derivatives, core_variable_name) are declared in fmu_core.h.
 */
#ifndef IMPACT_FMU_VARS_H
#define IMPACT_FMU_VARS_H

#include <stddef.h>

#include "fmu_core.h"

/* The value references (enum ValueReference, VR_*), generated from fmu_src/variables.py. */
#include "variables.h"

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
