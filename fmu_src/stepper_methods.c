/*
 * The integration methods by the value of the model's parameter `solver` (model.h, SolverKind),
 * and stepper_select (stepper.h), which the FMI core calls at instantiation, at the end of
 * initialisation and when it restores a snapshot. A new method: its StepperOps in its own file,
 * one row here, its value in SolverKind and in the variable `solver`'s range; the core is
 * unchanged. Kept apart from stepper.c so that a program that needs one method only links that
 * one (bench/cf_driver.c).
 */
#include <stdio.h>

#include "closed_form.h"
#include "solver_cvode.h"
#include "stepper.h"

/* The methods, by the value of the parameter `solver` (model.h, SolverKind). */
static const StepperOps *const METHODS[] = {
    [SOLVER_CVODE] = &STEPPER_CVODE,
    [SOLVER_CLOSED_FORM] = &STEPPER_CLOSED_FORM,
};
#define N_METHODS (sizeof METHODS / sizeof METHODS[0])

int stepper_select(Stepper *st, ModelData *m) {
    const StepperOps *ops = m->solver >= 0 && (size_t)m->solver < N_METHODS ? METHODS[m->solver]
                                                                              : NULL;
    if (!ops) {
        snprintf(st->clk.msg, sizeof st->clk.msg, "no integration method solver = %d", m->solver);
        return -1;
    }
    if (st->ops == ops) return 0;
    stepper_free(st);
    st->ops = ops;
    if (ops->create(st, m) != 0) {
        stepper_free(st);
        return -1;
    }
    return 0;
}

