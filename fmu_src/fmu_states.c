/*
 * The FMI state machine (fmu_states.h): the table of allowed states and the states' names.
 * Linked into the C FMU (fmu_core.c's core_allowed) and into the twin's C front
 * (pytwin/twin_export.c); scripts/state_table_doc.py renders docs/fmi-state-machine.md from the
 * table below.
 */
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "fmu_states.h"

/* The standards' state machines as data: for each FMI function, the states in which it may be
 * called, per interface. Taken from FMI 2.0.4 sections 3.2.3 (Model Exchange) and 4.2.4
 * (Co-Simulation) and FMI 3.0 sections 3.2 (Model Exchange) and 4.2 (Co-Simulation, with and
 * without eventModeUsed, Intermediate Update Mode), narrowed where this FMU declares less
 * (no clocks, no structural parameters, no providesEvaluateDiscreteStates, no variable with
 * intermediateUpdate = true). docs/fmi-state-machine.md is rendered from this table
 * (scripts/state_table_doc.py; tests/fmu/test_fmi_state_doc.py keeps them equal), and
 * tests/fmu/test_fmi_conformance.py checks every (state, function) pair against a table written
 * independently from the standards' text (tests/support/fmi_standard.py).
 *
 * States: I Instantiated, N Initialization Mode, S Step Mode (FMI 2.0: stepComplete), E Event
 * Mode, C Continuous-Time Mode, T Terminated, X Error (FMI 2.0; FMI 3.0 enters Terminated on
 * fmi3Error), U Intermediate Update Mode (no call allowed: nothing is declared for it).
 * Columns: Co-Simulation, Model Exchange, FMI 3.0 Co-Simulation with eventModeUsed.
 * Keep one row per line: the documentation is parsed from it. */
typedef struct {
    const char *fn;
    int cs, me, cs_event;
} StateRow;

#define I ST_INSTANTIATED
#define N ST_INIT
#define S ST_STEP
#define E ST_EVENT
#define C ST_CONT
#define T ST_TERMINATED
#define X ST_ERROR
/* STATE_TABLE_BEGIN */
static const StateRow STATE_TABLE[] = {
    {"fmi2SetDebugLogging", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2SetupExperiment", I, I, 0},
    {"fmi2EnterInitializationMode", I, I, 0},
    {"fmi2ExitInitializationMode", N, N, 0},
    {"fmi2Terminate", S, E|C, 0},
    {"fmi2Reset", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2FreeInstance", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2GetReal", N|S|T|X, N|E|C|T|X, 0},
    {"fmi2GetInteger", N|S|T|X, N|E|C|T|X, 0},
    {"fmi2GetBoolean", N|S|T|X, N|E|C|T|X, 0},
    {"fmi2GetString", N|S|T|X, N|E|C|T|X, 0},
    {"fmi2SetReal", I|N|S, I|N|E|C, 0},
    {"fmi2SetInteger", I|N|S, I|N|E, 0},
    {"fmi2SetBoolean", I|N|S, I|N|E, 0},
    {"fmi2SetString", I|N|S, I|N|E, 0},
    {"fmi2GetFMUstate", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2SetFMUstate", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2FreeFMUstate", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2SerializedFMUstateSize", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2SerializeFMUstate", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2DeSerializeFMUstate", I|N|S|T|X, I|N|E|C|T|X, 0},
    {"fmi2GetDirectionalDerivative", N|S|T|X, N|E|C|T|X, 0},
    {"fmi2SetRealInputDerivatives", I|N|S, 0, 0},
    {"fmi2GetRealOutputDerivatives", S|T|X, 0, 0},
    {"fmi2DoStep", S, 0, 0},
    {"fmi2CancelStep", 0, 0, 0},
    {"fmi2GetStatus", S|T, 0, 0},
    {"fmi2GetRealStatus", S|T, 0, 0},
    {"fmi2GetIntegerStatus", S|T, 0, 0},
    {"fmi2GetBooleanStatus", S|T, 0, 0},
    {"fmi2GetStringStatus", S|T, 0, 0},
    {"fmi2EnterEventMode", 0, E|C, 0},
    {"fmi2NewDiscreteStates", 0, E, 0},
    {"fmi2EnterContinuousTimeMode", 0, E, 0},
    {"fmi2CompletedIntegratorStep", 0, C, 0},
    {"fmi2SetTime", 0, C, 0},
    {"fmi2SetContinuousStates", 0, C, 0},
    {"fmi2GetDerivatives", 0, E|C|T|X, 0},
    {"fmi2GetEventIndicators", 0, N|E|C|T|X, 0},
    {"fmi2GetContinuousStates", 0, N|E|C|T|X, 0},
    {"fmi2GetNominalsOfContinuousStates", 0, I|E|C|T|X, 0},
    {"fmi3SetDebugLogging", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3EnterInitializationMode", I, I, I},
    {"fmi3ExitInitializationMode", N, N, N},
    {"fmi3EnterEventMode", 0, C, S},
    {"fmi3Terminate", S, E|C, S|E},
    {"fmi3Reset", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3FreeInstance", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3GetFloat32", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetFloat64", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetInt8", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetUInt8", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetInt16", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetUInt16", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetInt32", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetUInt32", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetInt64", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetUInt64", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetBoolean", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetString", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetBinary", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3SetFloat32", I|N|S, I|N|E|C, I|N|S|E},
    {"fmi3SetFloat64", I|N|S, I|N|E|C, I|N|S|E},
    {"fmi3SetInt8", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetUInt8", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetInt16", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetUInt16", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetInt32", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetUInt32", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetInt64", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetUInt64", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetBoolean", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetString", I|N|S, I|N|E, I|N|S|E},
    {"fmi3SetBinary", I|N|S, I|N|E, I|N|S|E},
    {"fmi3GetClock", 0, E, E},
    {"fmi3SetClock", 0, E, E},
    {"fmi3GetIntervalDecimal", 0, E, E},
    {"fmi3GetIntervalFraction", 0, E, E},
    {"fmi3GetShiftDecimal", 0, E, E},
    {"fmi3GetShiftFraction", 0, E, E},
    {"fmi3SetIntervalDecimal", 0, E, E},
    {"fmi3SetIntervalFraction", 0, E, E},
    {"fmi3SetShiftDecimal", 0, E, E},
    {"fmi3SetShiftFraction", 0, E, E},
    {"fmi3GetNumberOfVariableDependencies", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3GetVariableDependencies", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3GetFMUState", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3SetFMUState", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3FreeFMUState", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3SerializedFMUStateSize", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3SerializeFMUState", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3DeserializeFMUState", I|N|S|T, I|N|E|C|T, I|N|S|E|T},
    {"fmi3GetDirectionalDerivative", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3GetAdjointDerivative", N|S|T, N|E|C|T, N|S|E|T},
    {"fmi3EnterConfigurationMode", I|S, I|E, I|S|E},
    {"fmi3ExitConfigurationMode", 0, 0, 0},
    {"fmi3EvaluateDiscreteStates", 0, 0, 0},
    {"fmi3UpdateDiscreteStates", 0, E, E},
    {"fmi3EnterContinuousTimeMode", 0, E, 0},
    {"fmi3CompletedIntegratorStep", 0, C, 0},
    {"fmi3SetTime", 0, E|C, 0},
    {"fmi3SetContinuousStates", 0, C, 0},
    {"fmi3GetContinuousStateDerivatives", 0, N|E|C|T, 0},
    {"fmi3GetEventIndicators", 0, N|E|C|T, 0},
    {"fmi3GetContinuousStates", 0, N|E|C|T, 0},
    {"fmi3GetNominalsOfContinuousStates", 0, N|E|C|T, 0},
    {"fmi3GetNumberOfEventIndicators", 0, I|N|E|C|T, 0},
    {"fmi3GetNumberOfContinuousStates", 0, I|N|E|C|T, 0},
    {"fmi3EnterStepMode", 0, 0, E},
    {"fmi3GetOutputDerivatives", S|T, 0, S|E|T},
    {"fmi3DoStep", S, 0, S},
    {"fmi3ActivateModelPartition", 0, 0, 0},
};
/* STATE_TABLE_END */
#undef I
#undef N
#undef S
#undef E
#undef C
#undef T
#undef X

int core_allowed_states(CoreInterface iface, int event_mode, const char *fn) {
    if (!fn) return -1;
    for (size_t i = 0; i < sizeof STATE_TABLE / sizeof STATE_TABLE[0]; ++i) {
        const StateRow *r = &STATE_TABLE[i];
        if (strcmp(r->fn, fn) != 0) continue;
        if (iface == IF_FMI2_ME || iface == IF_FMI3_ME) return r->me;
        return iface == IF_FMI3_CS && event_mode ? r->cs_event : r->cs;
    }
    return -1;
}

const char *core_state_name(int state) {
    switch (state) {
    case ST_INSTANTIATED: return "Instantiated";
    case ST_INIT: return "Initialization Mode";
    case ST_STEP: return "Step Mode";
    case ST_EVENT: return "Event Mode";
    case ST_CONT: return "Continuous-Time Mode";
    case ST_TERMINATED: return "Terminated";
    case ST_ERROR: return "Error";
    case ST_INTERMEDIATE: return "Intermediate Update Mode";
    default: return "an unknown state";
    }
}

const char *core_interface_name(CoreInterface iface) {
    static const char *const NAMES[] = {"?", "FMI 2.0 Co-Simulation", "FMI 2.0 Model Exchange",
                                        "FMI 3.0 Co-Simulation", "FMI 3.0 Model Exchange"};
    return (int)iface >= 1 && (int)iface <= 4 ? NAMES[iface] : NAMES[0];
}

int core_state_allows(CoreInterface iface, int event_mode, int state, const char *fn, char *buf,
                      size_t n) {
    const int states = core_allowed_states(iface, event_mode, fn);
    if (states < 0) {
        snprintf(buf, n, "not in the FMU's state table (an FMU bug)");
        return 0;
    }
    if (state & states) return 1;
    snprintf(buf, n, "not allowed in %s (%s%s; docs/fmi-state-machine.md)", core_state_name(state),
             core_interface_name(iface),
             iface == IF_FMI3_CS ? (event_mode ? " with eventModeUsed" : " without eventModeUsed")
                                 : "");
    return 0;
}
