"""Bounded work per doStep and tiny steps.

The work of one doStep is bounded by the parameters max_steps_per_time (CVODE steps) and
max_events_per_time (wall events), per unit of time advanced (at least one unit), and by a cap
of SOLVER_MAX_STEPS_PER_CALL = 2e6 CVODE steps per doStep (solver_cvode.h); the bounds are
computed in double (a step of 1e9 must not overflow an integer). Exceeding one is fmi2Error with a
message that names it. A positive step down to the smallest double succeeds.
"""
from __future__ import annotations

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave

from tests.support.fmu import FMU3_PATH, LoggedSlave, on_orbit

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)
UNDERDAMPED = dict(nu=0.196, Omega=7.368)


def failed_step(fmu: LoggedSlave, t: float, h: float) -> str:
    with pytest.raises(FMICallException) as e:
        fmu.slave.doStep(t, h)
    assert e.value.status == 3
    return fmu.errors()[-1]


@pytest.mark.parametrize("h", [1e-300, 5e-324, 1e-16])
@pytest.mark.parametrize("wall", ["none", "compliant", "rigid"])
def test_tiny_positive_steps_succeed_and_change_nothing_after(fmu, h, wall):
    """A tiny step is a step: the state there is CVODE's interpolant, and the run continues as
    if the point had not been there (the integration does not depend on the grid)."""
    start = dict(wall=wall, sigma=0.5, **on_orbit(0.5, 0.5), **FIG9)
    fmu.start(t0=0.5, **start)
    fmu.step_to(3.5)
    reference = fmu.state()
    fmu.start(t0=0.5, **start)
    x0 = fmu.state()
    # h itself, not (0.5 + h) - 0.5, which is 0 for h below half an ulp of 0.5 (a step of size
    # 0 is refused: both standards require h > 0)
    fmu.slave.doStep(0.5, h)
    fmu.t = 0.5 + h
    assert fmu.slave.getRealStatus(2) == 0.5 + h  # fmi2LastSuccessfulTime
    assert np.max(np.abs(fmu.state() - x0)) <= 100 * h  # |dv| ~ |acceleration| h
    fmu.step_to(3.5)
    np.testing.assert_array_equal(fmu.state(), reference)


def test_max_steps_per_time_is_a_settable_limit_named_in_the_error(fmu):
    fmu.start(t0=0.0, wall="none", max_steps_per_time=50.0)
    msg = failed_step(fmu, 0.0, 1.0)
    assert "max_steps_per_time = 50 per unit time" in msg, msg


def test_max_events_per_time_is_a_settable_limit_named_in_the_error(fmu):
    """Chatter on the rigid wall: dozens of impacts in the first period."""
    fmu.start(t0=0.0, wall="rigid", sigma=10.0, r=0.5, u0=-0.03, v0=0.0,
              max_events_per_time=5.0, **UNDERDAMPED)
    msg = failed_step(fmu, 0.0, 1.0)
    assert "more than 5 wall events" in msg and "max_events_per_time = 5" in msg, msg
    # the same run within the default limit
    fmu.start(t0=0.0, wall="rigid", sigma=10.0, r=0.5, u0=-0.03, v0=0.0, **UNDERDAMPED)
    fmu.step_to(1.0)
    assert fmu.impacts() > 5


def test_a_huge_step_stops_at_the_cap_not_an_overflow(fmu):
    """h = 1e9 (the largest the FMU accepts) without a wall would take 1e11 CVODE steps: the
    bound saturates at the per-doStep cap (computed in double), never at an overflowed integer,
    and the call returns within seconds."""
    fmu.start(t0=0.0, wall="none")
    msg = failed_step(fmu, 0.0, 1e9)
    assert "more than 2000000 CVODE steps in this doStep" in msg and "cap" in msg, msg


def test_the_event_bound_counts_the_whole_doStep_across_intermediate_updates():
    """FMI 3.0 with intermediate updates: the solver stops at every event to call back, and
    resumes towards the same end; the bound is on the whole doStep, not on each stretch."""
    md = read_model_description(str(FMU3_PATH))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    calls: list[float] = []

    def cb(env, t, set_req, get_ok, finished, can_return, early_req, early_time):  # noqa: ANN001
        calls.append(t)

    results = {}
    for limit in (5.0, 1e5):
        calls.clear()
        s = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(FMU3_PATH)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bound3")
        s.instantiate(eventModeUsed=False, earlyReturnAllowed=True, intermediateUpdate=cb)
        try:
            s.enterInitializationMode(startTime=0.0)
            reals = dict(sigma=10.0, r=0.5, u0=-0.03, v0=0.0, max_events_per_time=limit,
                         **UNDERDAMPED)
            s.setFloat64([vr[k] for k in reals], list(reals.values()))
            s.setInt32([vr["wall"]], [2])
            s.exitInitializationMode()
            try:
                s.doStep(0.0, 1.0)
                results[limit] = "ok"
            except FMICallException:
                results[limit] = "error"
        finally:
            s.freeInstance()
        results[limit, "calls"] = len(calls)
    assert results[5.0] == "error" and results[5.0, "calls"] <= 6
    assert results[1e5] == "ok" and results[1e5, "calls"] > 5
