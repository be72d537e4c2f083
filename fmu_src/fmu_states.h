/*
 * The FMI state machine of FMI 2.0 and 3.0, Co-Simulation and Model Exchange, as data: the
 * instance states, the interfaces, and for every FMI function the states in which it may be
 * called (STATE_TABLE in fmu_states.c). One table for every binary that speaks FMI here: the C
 * FMU's core (fmu_core.c, core_allowed, checked first by every entry point) and the twin's C front
 * (pytwin/twin_export.c, built by pytwin/build.py with this unit). No instance type, no logging:
 * the callers word their own refusals from core_state_name.
 */
#ifndef IMPACT_FMU_STATES_H
#define IMPACT_FMU_STATES_H

#include <stddef.h>

/* Instance states (bit flags, so that a set of allowed states is one mask). */
enum {
    ST_INSTANTIATED = 1 << 0,
    ST_INIT = 1 << 1,
    ST_STEP = 1 << 2,
    ST_EVENT = 1 << 3,
    ST_CONT = 1 << 4,
    ST_TERMINATED = 1 << 5,
    ST_ERROR = 1 << 6,
    ST_INTERMEDIATE = 1 << 7, /* FMI 3.0 Co-Simulation: inside the intermediateUpdate callback */
    ST_FATAL = 1 << 8,        /* never entered: no call of this FMU answers Fatal */
};
#define ST_ANY 0x1ff
#define ST_RUN (ST_STEP | ST_EVENT | ST_CONT) /* initialised, not terminated */

/* Which interface an instance (and its snapshots) belongs to. */
typedef enum { IF_FMI2_CS = 1, IF_FMI2_ME = 2, IF_FMI3_CS = 3, IF_FMI3_ME = 4 } CoreInterface;

/* The states in which fn may be called by an instance of interface iface (event_mode: FMI 3.0
 * Co-Simulation instantiated with eventModeUsed); -1 for a function the table does not know. */
int core_allowed_states(CoreInterface iface, int event_mode, const char *fn);
/* "Step Mode", ... for one state bit ("an unknown state" for anything else). */
const char *core_state_name(int state);
/* "FMI 2.0 Co-Simulation", ... ("?" for anything else). */
const char *core_interface_name(CoreInterface iface);
/* 1 if fn may be called in `state`; else 0 and buf holds why ("not allowed in Step Mode (...)",
 * or, for a function the table lacks, "not in the FMU's state table (an FMU bug)"). */
int core_state_allows(CoreInterface iface, int event_mode, int state, const char *fn, char *buf,
                      size_t n);

#endif
