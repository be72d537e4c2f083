"""The FMI 2.0.4 and FMI 3.0 state machines, written from the standards' text.

This table is the conformance suite's reference. It is written from the standards, not from
fmu_src/fmu_states.c's STATE_TABLE, so that the two can be compared: tests/fmu/test_fmi_conformance.py
drives every (state, function) pair of the built FMUs and checks them against this module.

Sources, section by section:

* FMI 2.0.4, 2.1.3 (status codes): after ``fmi2Error`` the simulation cannot be continued; the
  instance can be restored with ``fmi2SetFMUstate``, or ``fmi2Reset``/``fmi2FreeInstance`` called.
  State "Error" below.
* FMI 2.0.4, 3.2.3 (Model Exchange state machine and its table of allowed calls) and 4.2.4
  (Co-Simulation state machine and table). The Co-Simulation states stepInProgress, stepFailed
  and stepCanceled are never entered here (doStep is synchronous, never returns Discard or
  Pending); stepComplete is "Step".
* FMI 3.0, 2.2.3 (status codes): after ``fmi3Error`` the instance is in Terminated (only
  ``fmi3Reset``, ``fmi3SetFMUState``, ``fmi3FreeInstance`` and the getters lead on).
* FMI 3.0, 3.2 (Model Exchange) and 4.2 (Co-Simulation, with ``eventModeUsed`` the Event Mode;
  Intermediate Update Mode inside ``intermediateUpdate``: only variables declared with
  ``intermediateUpdate="true"`` may be read or written there, and this FMU declares none, so no
  call is allowed in it).

Where a function's allowed states depend on what the FMU declares, the FMU's modelDescription
decides: no clocks (clock functions in Event Mode only, with zero clocks), no structural
parameters (configuration mode never entered), ``providesEvaluateDiscreteStates`` not declared
(``fmi3EvaluateDiscreteStates`` never allowed), no Scheduled Execution.
"""
from __future__ import annotations

# State names used by the suite. "Error" exists in FMI 2.0 only; "Update" is FMI 3.0's
# Intermediate Update Mode (Co-Simulation).
STATES_FMI2_CS = ("Instantiated", "Init", "Step", "Terminated", "Error")
STATES_FMI2_ME = ("Instantiated", "Init", "Event", "Continuous", "Terminated", "Error")
STATES_FMI3_CS = ("Instantiated", "Init", "Step", "Terminated", "Update")
STATES_FMI3_CS_EVENT = ("Instantiated", "Init", "Event", "Step", "Terminated", "Update")
STATES_FMI3_ME = ("Instantiated", "Init", "Event", "Continuous", "Terminated")

_ALL2 = {"Instantiated", "Init", "Step", "Event", "Continuous", "Terminated", "Error"}
_INITIALISED2 = {"Init", "Step", "Event", "Continuous", "Terminated", "Error"}


def _s(text: str) -> frozenset[str]:
    return frozenset(text.split())


# --- FMI 2.0.4 -----------------------------------------------------------------------------
# name: (Co-Simulation states, Model Exchange states)
FMI2: dict[str, tuple[frozenset[str], frozenset[str]]] = {}

# Common functions (3.2.3 / 4.2.4 tables, rows above the interface-specific ones).
for _fn in ("SetDebugLogging", "Reset", "FreeInstance", "GetFMUstate", "SetFMUstate",
            "FreeFMUstate", "SerializedFMUstateSize", "SerializeFMUstate",
            "DeSerializeFMUstate"):
    FMI2["fmi2" + _fn] = (_s("Instantiated Init Step Terminated Error"),
                          _s("Instantiated Init Event Continuous Terminated Error"))
FMI2["fmi2SetupExperiment"] = (_s("Instantiated"), _s("Instantiated"))
FMI2["fmi2EnterInitializationMode"] = (_s("Instantiated"), _s("Instantiated"))
FMI2["fmi2ExitInitializationMode"] = (_s("Init"), _s("Init"))
FMI2["fmi2Terminate"] = (_s("Step"), _s("Event Continuous"))
# getters: from Initialization Mode on, also in Terminated and Error ("for debugging")
for _fn in ("GetReal", "GetInteger", "GetBoolean", "GetString", "GetDirectionalDerivative"):
    FMI2["fmi2" + _fn] = (_s("Init Step Terminated Error"),
                          _s("Init Event Continuous Terminated Error"))
# setters: Real also in Continuous-Time Mode (continuous inputs only), the others not
FMI2["fmi2SetReal"] = (_s("Instantiated Init Step"), _s("Instantiated Init Event Continuous"))
for _fn in ("SetInteger", "SetBoolean", "SetString"):
    FMI2["fmi2" + _fn] = (_s("Instantiated Init Step"), _s("Instantiated Init Event"))
# Co-Simulation only (4.2.4)
FMI2["fmi2SetRealInputDerivatives"] = (_s("Instantiated Init Step"), frozenset())
FMI2["fmi2GetRealOutputDerivatives"] = (_s("Step Terminated Error"), frozenset())
FMI2["fmi2DoStep"] = (_s("Step"), frozenset())
FMI2["fmi2CancelStep"] = (frozenset(), frozenset())  # stepInProgress only: never entered
for _fn in ("GetStatus", "GetRealStatus", "GetIntegerStatus", "GetBooleanStatus",
            "GetStringStatus"):
    FMI2["fmi2" + _fn] = (_s("Step Terminated"), frozenset())
# Model Exchange only (3.2.3)
FMI2["fmi2EnterEventMode"] = (frozenset(), _s("Event Continuous"))
FMI2["fmi2NewDiscreteStates"] = (frozenset(), _s("Event"))
FMI2["fmi2EnterContinuousTimeMode"] = (frozenset(), _s("Event"))
FMI2["fmi2CompletedIntegratorStep"] = (frozenset(), _s("Continuous"))
FMI2["fmi2SetTime"] = (frozenset(), _s("Continuous"))
FMI2["fmi2SetContinuousStates"] = (frozenset(), _s("Continuous"))
# FMI 2.0.4, 3.2.3, the table of allowed calls per state (Model Exchange): fmi2GetDerivatives and
# fmi2GetNominalsOfContinuousStates have no mark in the Initialization Mode column (the derivatives
# are InitialUnknowns there, read with fmi2GetReal); fmusdk's masks agree.
FMI2["fmi2GetDerivatives"] = (frozenset(), _s("Event Continuous Terminated Error"))
FMI2["fmi2GetEventIndicators"] = (frozenset(), _s("Init Event Continuous Terminated Error"))
FMI2["fmi2GetContinuousStates"] = (frozenset(), _s("Init Event Continuous Terminated Error"))
FMI2["fmi2GetNominalsOfContinuousStates"] = (
    frozenset(), _s("Instantiated Event Continuous Terminated Error"))

# --- FMI 3.0 -------------------------------------------------------------------------------
# name: (Co-Simulation, Co-Simulation with eventModeUsed, Model Exchange)
FMI3: dict[str, tuple[frozenset[str], frozenset[str], frozenset[str]]] = {}
_ANY_CS = "Instantiated Init Step Terminated"
_ANY_CSE = "Instantiated Init Step Event Terminated"
_ANY_ME = "Instantiated Init Event Continuous Terminated"
for _fn in ("SetDebugLogging", "Reset", "FreeInstance", "GetFMUState", "SetFMUState",
            "FreeFMUState", "SerializedFMUStateSize", "SerializeFMUState",
            "DeserializeFMUState", "GetNumberOfVariableDependencies",
            "GetVariableDependencies"):
    FMI3["fmi3" + _fn] = (_s(_ANY_CS), _s(_ANY_CSE), _s(_ANY_ME))
FMI3["fmi3EnterInitializationMode"] = (_s("Instantiated"),) * 3
FMI3["fmi3ExitInitializationMode"] = (_s("Init"),) * 3
# FMI 3.0, 3.2 (Model Exchange state machine, the transitions into Event Mode) and 4.2.5
# (Co-Simulation Event Mode): fmi3EnterEventMode leads from Continuous-Time Mode (ME) or Step Mode
# (CS with eventModeUsed) into Event Mode; no transition starts in Event Mode itself (unlike FMI
# 2.0.4's table, which allows fmi2EnterEventMode in Event Mode). The Reference FMUs' mask agrees:
# MASK_fmi3EnterEventMode = (ContinuousTimeMode | StepMode).
FMI3["fmi3EnterEventMode"] = (frozenset(), _s("Step"), _s("Continuous"))
FMI3["fmi3Terminate"] = (_s("Step"), _s("Step Event"), _s("Event Continuous"))
TYPES3 = ("Float32", "Float64", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64",
          "UInt64", "Boolean", "String", "Binary")
for _t in TYPES3:
    FMI3["fmi3Get" + _t] = (_s("Init Step Terminated"), _s("Init Step Event Terminated"),
                            _s("Init Event Continuous Terminated"))
    # only floats are continuous: they alone may be set in Continuous-Time Mode
    me_set = "Instantiated Init Event" + (" Continuous" if _t.startswith("Float") else "")
    FMI3["fmi3Set" + _t] = (_s("Instantiated Init Step"), _s("Instantiated Init Step Event"),
                            _s(me_set))
for _fn in ("GetDirectionalDerivative", "GetAdjointDerivative"):
    FMI3["fmi3" + _fn] = (_s("Init Step Terminated"), _s("Init Step Event Terminated"),
                          _s("Init Event Continuous Terminated"))
FMI3["fmi3EnterConfigurationMode"] = (_s("Instantiated Step"), _s("Instantiated Step Event"),
                                      _s("Instantiated Event"))
FMI3["fmi3ExitConfigurationMode"] = (frozenset(),) * 3
for _fn in ("GetClock", "SetClock", "GetIntervalDecimal", "GetIntervalFraction",
            "GetShiftDecimal", "GetShiftFraction", "SetIntervalDecimal", "SetIntervalFraction",
            "SetShiftDecimal", "SetShiftFraction"):
    FMI3["fmi3" + _fn] = (frozenset(), _s("Event"), _s("Event"))
FMI3["fmi3EvaluateDiscreteStates"] = (frozenset(),) * 3
FMI3["fmi3UpdateDiscreteStates"] = (frozenset(), _s("Event"), _s("Event"))
FMI3["fmi3ActivateModelPartition"] = (frozenset(),) * 3
# Model Exchange only (3.2)
FMI3["fmi3EnterContinuousTimeMode"] = (frozenset(), frozenset(), _s("Event"))
FMI3["fmi3CompletedIntegratorStep"] = (frozenset(), frozenset(), _s("Continuous"))
FMI3["fmi3SetTime"] = (frozenset(), frozenset(), _s("Event Continuous"))
FMI3["fmi3SetContinuousStates"] = (frozenset(), frozenset(), _s("Continuous"))
for _fn in ("GetContinuousStateDerivatives", "GetEventIndicators", "GetContinuousStates",
            "GetNominalsOfContinuousStates"):
    FMI3["fmi3" + _fn] = (frozenset(), frozenset(), _s("Init Event Continuous Terminated"))
for _fn in ("GetNumberOfEventIndicators", "GetNumberOfContinuousStates"):
    FMI3["fmi3" + _fn] = (frozenset(), frozenset(), _s(_ANY_ME))
# Co-Simulation only (4.2)
FMI3["fmi3EnterStepMode"] = (frozenset(), _s("Event"), frozenset())
FMI3["fmi3GetOutputDerivatives"] = (_s("Step Terminated"), _s("Step Event Terminated"),
                                    frozenset())
FMI3["fmi3DoStep"] = (_s("Step"), _s("Step"), frozenset())


def allowed(interface: str, function: str) -> frozenset[str]:
    """The states in which `function` may be called.

    Parameters
    ----------
    interface : str
        One of "fmi2-cs", "fmi2-me", "fmi3-cs", "fmi3-cs-event", "fmi3-me".
    function : str
        The FMI function's name, e.g. "fmi2DoStep".

    Returns
    -------
    frozenset of str
        State names as in the STATES_* tuples ("Update" is in none: nothing is allowed there).
    """
    if interface.startswith("fmi2"):
        cs, me = FMI2[function]
        return me if interface == "fmi2-me" else cs
    cs, cse, me = FMI3[function]
    return {"fmi3-cs": cs, "fmi3-cs-event": cse, "fmi3-me": me}[interface]


def error_state(interface: str) -> str:
    """The state an instance is in after a call returned Error (FMI 2.0: Error; 3.0: Terminated)."""
    return "Error" if interface.startswith("fmi2") else "Terminated"


STATES = {"fmi2-cs": STATES_FMI2_CS, "fmi2-me": STATES_FMI2_ME, "fmi3-cs": STATES_FMI3_CS,
          "fmi3-cs-event": STATES_FMI3_CS_EVENT, "fmi3-me": STATES_FMI3_ME}
