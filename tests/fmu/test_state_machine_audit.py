"""The cases of an independent audit of every (state, function) pair, as conformance tests.

Each case names the standard's text that decides it (tests/support/fmi_standard.py holds the same
sections); the full pair-by-pair comparison with that table is tests/fmu/test_fmi_conformance.py
and tests/twin/test_fmi_conformance.py.
"""
from __future__ import annotations

import ctypes

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave, fmi2LastSuccessfulTime

from tests.support import fmi_standard as std
from tests.support.derivatives import Instance
from tests.support.fmu import FMU_PATH, ROOT

TWIN = ROOT / "build" / "fmu" / "ImpactOscillatorPy.fmu"


def test_fmi3_model_exchange_enters_event_mode_only_from_continuous_time_mode():
    """FMI 3.0, 3.2: fmi3EnterEventMode leads from Continuous-Time Mode into Event Mode; in Event
    Mode it is refused (it was accepted before)."""
    assert std.allowed("fmi3-me", "fmi3EnterEventMode") == {"Continuous"}
    x = Instance("fmi3-me", u0=-0.5)
    x.enter_event_mode()  # from Continuous-Time Mode: allowed
    with pytest.raises(FMICallException):
        x.enter_event_mode()  # in Event Mode: refused
    x.fmu.freeInstance()


def test_fmi2_model_exchange_still_enters_event_mode_from_event_mode():
    """FMI 2.0.4, 3.2.3's table marks fmi2EnterEventMode in Event Mode too (fmusdk's mask
    modelEventMode | modelContinuousTimeMode): the two versions differ here."""
    assert std.allowed("fmi2-me", "fmi2EnterEventMode") == {"Event", "Continuous"}
    x = Instance("fmi2-me", u0=-0.5)
    x.enter_event_mode()
    x.enter_event_mode()
    x.close()


@pytest.mark.parametrize("path", [FMU_PATH, TWIN], ids=["c-fmu", "twin"])
def test_last_successful_time_after_a_step_and_after_terminate(path):
    """FMI 2.0.4, 4.2.3 (fmi2GetRealStatus with fmi2LastSuccessfulTime) in stepComplete and
    Terminated (the table of 4.2.4): the end of the last completed step, on both FMUs."""
    assert std.allowed("fmi2-cs", "fmi2GetRealStatus") == {"Step", "Terminated"}
    md = read_model_description(str(path))
    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="audit")
    s.instantiate()
    s.setupExperiment(startTime=0.25)
    s.enterInitializationMode()
    s.exitInitializationMode()
    assert s.getRealStatus(fmi2LastSuccessfulTime) == 0.25
    s.doStep(0.25, 0.5)
    s.doStep(0.75, 0.125)
    assert s.getRealStatus(fmi2LastSuccessfulTime) == 0.875
    s.terminate()
    assert s.getRealStatus(fmi2LastSuccessfulTime) == 0.875
    s.freeInstance()


@pytest.mark.parametrize("fn", ["fmi2GetDerivatives", "fmi2GetNominalsOfContinuousStates"])
def test_initialization_mode_refuses_the_derivative_and_nominal_calls_but_not_get_real(fn):
    """FMI 2.0.4, 3.2.3's table: neither call is marked in the Initialization Mode column; the
    derivatives are InitialUnknowns there and fmi2GetReal answers them."""
    assert "Init" not in std.allowed("fmi2-me", fn)
    from fmpy.fmi2 import FMU2Model

    md = read_model_description(str(FMU_PATH))
    m = FMU2Model(guid=md.guid, unzipDirectory=extract(str(FMU_PATH)),
                  modelIdentifier=md.modelExchange.modelIdentifier, instanceName="audit")
    m.instantiate()
    m.setupExperiment(startTime=0.0)
    m.setReal([6, 7], [-0.4, 0.5])  # u0, v0
    m.enterInitializationMode()
    # the initial unknowns answer the start values set (not the defaults u = -1, v = 0)
    assert m.getReal([13, 14, 19]) == [-0.4, 0.5, 0.5]  # u, v, der(u) = v0
    x = (ctypes.c_double * 2)()
    with pytest.raises(FMICallException):
        getattr(m, fn.replace("fmi2G", "g"))(x, 2)
    m.freeInstance()
