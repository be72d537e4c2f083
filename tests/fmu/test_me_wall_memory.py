"""Model Exchange's memory of the wall: the position of the rigid wall at the last event.

A state far inside the rigid wall at an event is one of two things: the wall jumped into the mass
since the last event (the importer moved u_wall): the input-jump rule places it on the wall; or
the importer handed over a state no contact mode holds (it did not locate the crossing): refused
with a message.  Which one depends on where the wall was at the last event, so that memory must
follow every event: the importer moves the wall, an event passes (the wall's new position is the
last event's), then a state 0.1 inside it is refused; without that event between, the same
state is the wall's jump (placed on the wall, an impact counted).
"""
from __future__ import annotations

import ctypes

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model
from fmpy.fmi3 import FMU3Model

from tests.support.fmu import FMU3_PATH, FMU_PATH

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112, sigma=0.2)


class MeInstance:
    """An initialised ME instance, rigid wall at 0, mass at rest at u0 = -0.5, in
    Continuous-Time Mode at t = 0."""

    def __init__(self, fmi3: bool) -> None:
        self.fmi3 = fmi3
        path = FMU3_PATH if fmi3 else FMU_PATH
        md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        cls = FMU3Model if fmi3 else FMU2Model
        self.fmu = cls(guid=md.guid, unzipDirectory=extract(str(path)),
                       modelIdentifier=md.modelExchange.modelIdentifier, instanceName="me-wall")
        self.fmu.instantiate()
        if not fmi3:
            self.fmu.setupExperiment(startTime=0.0)
        self.set(**FIG9, u0=-0.5, v0=0.0)
        (self.fmu.setInt32 if fmi3 else self.fmu.setInteger)([self.vr["wall"]], [2])
        if fmi3:
            self.fmu.enterInitializationMode(startTime=0.0)
        else:
            self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self.event()
        self.fmu.enterContinuousTimeMode()

    def set(self, **values: float) -> None:
        (self.fmu.setFloat64 if self.fmi3 else self.fmu.setReal)(
            [self.vr[k] for k in values], [float(x) for x in values.values()])

    def get(self, name: str) -> float:
        return (self.fmu.getFloat64 if self.fmi3 else self.fmu.getReal)([self.vr[name]])[0]

    def event(self) -> None:
        """An event iteration (Event Mode must have been entered, or be the initial one)."""
        while True:
            out = self.fmu.updateDiscreteStates() if self.fmi3 else self.fmu.newDiscreteStates()
            if not out[0]:
                return

    def continuous(self, t: float, u: float, v: float) -> None:
        self.fmu.setTime(t)
        self.fmu.setContinuousStates((ctypes.c_double * 2)(u, v), 2)

    def states(self) -> tuple[float, float]:
        x = (ctypes.c_double * 2)()
        self.fmu.getContinuousStates(x, 2)
        return x[0], x[1]


@pytest.mark.parametrize("fmi3", [False, True], ids=["fmi2", "fmi3"])
def test_a_state_inside_the_wall_moved_before_the_last_event_is_refused(fmi3):
    x = MeInstance(fmi3)
    try:
        # the importer moves the wall to -0.3 in Continuous-Time Mode (a continuous input), the
        # mass stays below it; an event then passes with nothing crossed
        x.continuous(0.1, -0.5, 0.0)
        x.set(u_wall=-0.3)
        x.fmu.enterEventMode()
        x.event()
        assert x.states() == (-0.5, 0.0)
        x.fmu.enterContinuousTimeMode()
        # a state 0.1 inside the wall that has not moved since that event: no mode holds it
        x.continuous(0.2, -0.2, 0.5)
        x.fmu.enterEventMode()
        with pytest.raises(Exception):
            x.event()
    finally:
        x.fmu.freeInstance()


@pytest.mark.parametrize("fmi3", [False, True], ids=["fmi2", "fmi3"])
def test_a_state_inside_the_wall_moved_since_the_last_event_is_the_walls_jump(fmi3):
    x = MeInstance(fmi3)
    try:
        x.continuous(0.1, -0.5, 0.0)
        x.set(u_wall=-0.3)
        x.continuous(0.2, -0.2, 0.5)  # the wall moved into the mass since the start's event
        x.fmu.enterEventMode()
        x.event()
        u, v = x.states()
        assert u == pytest.approx(-0.3, abs=1e-15)  # placed on the wall
        assert v == pytest.approx(-0.5 * 0.9)  # the impact law: v -> -r v (r = 0.9, wall at rest)
        assert x.get("v_impact") == 0.5
        x.fmu.enterContinuousTimeMode()
    finally:
        x.fmu.freeInstance()
