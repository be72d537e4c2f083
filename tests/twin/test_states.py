"""The pythonfmu twin's FMI 2.0 Co-Simulation state machine.

FMI 2.0.4, section 4.2.4 (the table of allowed calls per state) and 2.1.3 (after fmi2Error the
simulation cannot go on; fmi2Reset, fmi2SetFMUstate or fmi2FreeInstance lead on).  Each case
drives the twin into a state, makes one call the table forbids there or one an importer gets
wrong (unknown value reference, a fixed parameter or an output set after initialisation), and
checks the twin's answer: fmi2Error (never fmi2Fatal), the reason through the importer's logger
although the importer switched logging off, the instance in Error afterwards (fmi2DoStep is
refused there too, without a crash), and fmi2Reset brings it back to a run equal to a fresh one.
The complete (state, function) table is the conformance suite's (tests/support/fmi_standard.py).
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from tests.support.fmu import ROOT, LoggedSlave

TWIN_FMU = ROOT / "build" / "fmu" / "ImpactOscillatorPy.fmu"
FMI2_ERROR = 3
VR = {"nu": 0, "sigma": 2, "r": 3, "wall": 5, "u": 13, "impacts": 15}
FIG9 = {"nu": 0.1, "Omega": 4.0, "sigma": 0.5, "r": 0.8, "Gamma": 100.0, "wall": 1}


@pytest.fixture(scope="module")
def twin_fmu() -> Path:
    assert TWIN_FMU.exists(), f"{TWIN_FMU} missing: build it with scripts/setup.sh"
    return TWIN_FMU


def into(s: LoggedSlave, state: str) -> None:
    """Drive a fresh instance into ``state`` (names of tests/support/fmi_standard.py)."""
    f = s.slave
    if state == "Instantiated":
        return
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    s.set(**FIG9)
    if state == "Init":
        return
    f.exitInitializationMode()
    f.doStep(currentCommunicationPoint=0.0, communicationStepSize=1.0)
    if state == "Terminated":
        f.terminate()
    elif state == "Error":  # h <= 0 is an importer's error (FMI 2.0.4, 4.2.2)
        with pytest.raises(FMICallException):
            f.doStep(currentCommunicationPoint=1.0, communicationStepSize=-1.0)


Call = Callable[[LoggedSlave], object]
ILLEGAL: dict[str, dict[str, Call]] = {
    "Instantiated": {
        "ExitInitializationMode": lambda s: s.slave.exitInitializationMode(),
        "DoStep": lambda s: s.slave.doStep(0.0, 1.0),
        "Terminate": lambda s: s.slave.terminate(),
        "GetReal": lambda s: s.slave.getReal([VR["u"]]),
        "SetReal output u": lambda s: s.slave.setReal([VR["u"]], [0.0]),
        "SetReal unknown vr": lambda s: s.slave.setReal([99], [0.0]),
        "SetInteger on a Real vr": lambda s: s.slave.setInteger([VR["nu"]], [1]),
    },
    "Init": {
        "SetupExperiment": lambda s: s.slave.setupExperiment(startTime=0.0),
        "EnterInitializationMode": lambda s: s.slave.enterInitializationMode(),
        "DoStep": lambda s: s.slave.doStep(0.0, 1.0),
        "Terminate": lambda s: s.slave.terminate(),
        "GetReal unknown vr": lambda s: s.slave.getReal([17]),
    },
    "Step": {
        "SetupExperiment": lambda s: s.slave.setupExperiment(startTime=0.0),
        "EnterInitializationMode": lambda s: s.slave.enterInitializationMode(),
        "ExitInitializationMode": lambda s: s.slave.exitInitializationMode(),
        "SetReal fixed r": lambda s: s.slave.setReal([VR["r"]], [0.5]),
        "SetInteger fixed wall": lambda s: s.slave.setInteger([VR["wall"]], [2]),
        "SetReal output u": lambda s: s.slave.setReal([VR["u"]], [0.0]),
        "GetInteger unknown vr": lambda s: s.slave.getInteger([1000]),
        "DoStep h = 0": lambda s: s.slave.doStep(1.0, 0.0),
    },
    "Terminated": {
        "DoStep": lambda s: s.slave.doStep(1.0, 1.0),
        "SetReal sigma": lambda s: s.slave.setReal([VR["sigma"]], [0.3]),
        "Terminate": lambda s: s.slave.terminate(),
        "SetupExperiment": lambda s: s.slave.setupExperiment(startTime=0.0),
    },
    "Error": {
        "DoStep": lambda s: s.slave.doStep(1.0, 1.0),
        "Terminate": lambda s: s.slave.terminate(),
        "SetReal sigma": lambda s: s.slave.setReal([VR["sigma"]], [0.3]),
        "EnterInitializationMode": lambda s: s.slave.enterInitializationMode(),
    },
}
CASES = [(state, name) for state, calls in ILLEGAL.items() for name in calls]


def run_after_reset(s: LoggedSlave) -> np.ndarray:
    """fmi2Reset, then two periods of Figure 9's compliant case: the state reached."""
    s.slave.reset()
    into(s, "Step")
    s.slave.doStep(currentCommunicationPoint=1.0, communicationStepSize=1.0)
    return s.state()


@pytest.fixture(scope="module")
def fresh_run(twin_fmu: Path) -> np.ndarray:
    s = LoggedSlave(path=twin_fmu, name="fresh")
    try:
        return run_after_reset(s)
    finally:
        s.close()


@pytest.mark.parametrize("state, call", CASES, ids=[f"{a}-{b}" for a, b in CASES])
def test_illegal_call_is_an_error_through_the_logger(twin_fmu: Path, fresh_run: np.ndarray,
                                                     state: str, call: str) -> None:
    s = LoggedSlave(path=twin_fmu, name="states", logging=False)
    try:
        into(s, state)
        before = len(s.errors())
        with pytest.raises(FMICallException) as refused:
            ILLEGAL[state][call](s)
        assert refused.value.status == FMI2_ERROR  # never fmi2Fatal for an importer's mistake
        new = s.errors()[before:]
        assert new, "no message through the logger (logging is off: errors must still come)"
        assert all(st == FMI2_ERROR for st, _, m in s.messages if m in new)
        # Error state: the simulation cannot go on (FMI 2.0.4, 2.1.3), and nothing crashes
        with pytest.raises(FMICallException) as again:
            s.slave.doStep(currentCommunicationPoint=1.0, communicationStepSize=1.0)
        assert again.value.status == FMI2_ERROR
        assert "not allowed in Error" in s.errors()[-1]
        np.testing.assert_array_equal(run_after_reset(s), fresh_run)
    finally:
        s.close()


@pytest.mark.parametrize("bad", [{"r": 1.5}, {"nu": float("nan")}, {"Omega": -1.0}])
def test_rejected_parameter_is_an_error_not_fatal(twin_fmu: Path, fresh_run: np.ndarray,
                                                  bad: dict) -> None:
    """A value the model rejects (the Python side raises; pythonfmu would answer fmi2Fatal) is
    fmi2Error with the model's reason through the logger, then the Error state."""
    s = LoggedSlave(path=twin_fmu, name="values", logging=False)
    try:
        s.slave.setupExperiment(startTime=0.0)
        s.slave.enterInitializationMode()
        with pytest.raises(FMICallException) as refused:
            s.set(**bad)
        assert refused.value.status == FMI2_ERROR
        assert any(next(iter(bad)) in m for m in s.errors()), s.messages
        for step in range(3):  # after the error, calls are refused, never a crash
            with pytest.raises(FMICallException):
                s.slave.exitInitializationMode()
            with pytest.raises(FMICallException):
                s.slave.doStep(currentCommunicationPoint=float(step), communicationStepSize=1.0)
        np.testing.assert_array_equal(run_after_reset(s), fresh_run)
    finally:
        s.close()


def test_state_snapshot_restores_the_machine_state(twin_fmu: Path) -> None:
    """fmi2SetFMUstate in Error (allowed there) brings back the state the snapshot was taken in,
    also through serialisation: Step Mode, and the run continues as it did from the snapshot
    before the error (a snapshot restarts CVODE, so that run is the reference)."""
    s = LoggedSlave(path=twin_fmu, name="snap", logging=False)
    try:
        into(s, "Step")
        snap = s.slave.getFMUstate()
        data = s.slave.serializeFMUstate(snap)
        s.slave.doStep(currentCommunicationPoint=1.0, communicationStepSize=1.0)
        reference = s.state()
        for restore in ("snapshot", "serialised"):
            with pytest.raises(FMICallException):
                s.slave.setReal([VR["r"]], [0.5])
            with pytest.raises(FMICallException):
                s.slave.doStep(currentCommunicationPoint=2.0, communicationStepSize=1.0)
            state = snap if restore == "snapshot" else s.slave.deSerializeFMUstate(data)
            s.slave.setFMUstate(state)
            s.slave.doStep(currentCommunicationPoint=1.0, communicationStepSize=1.0)
            np.testing.assert_array_equal(s.state(), reference)
            s.slave.freeFMUstate(state)
    finally:
        s.close()
