"""Nothing non-finite with OK: every value that enters the FMU is checked where it
enters (setters, start values, Model Exchange states and time, inputs, the start time), derived
quantities that could overflow are checked too (kappa, the forcing amplitude), and a step that
returns OK has finite outputs. The inputs once reported as leaking non-finite values are here one by one, and
the corners of the valid ranges run to a finite state or fail with a message, never OK with inf.
"""
from __future__ import annotations

import ctypes
import itertools

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model
from fmpy.fmi3 import FMU3Slave

from harness.fmu.fmi2_logging import Fmi2Callbacks
from tests.support.fmu import FMU3_PATH, FMU_PATH, LoggedSlave, expect_error, refused_and_restored

OUTPUTS_REAL = ("u", "v", "F_contact", "v_impact", "t_impact", "F_g", "phi", "kappa")


def _init(fmu, t0=0.0):
    fmu.slave.reset()
    fmu.slave.setupExperiment(startTime=t0)
    fmu.slave.enterInitializationMode()


@pytest.mark.parametrize("name,value", [
    ("Omega", 1.8e308), ("sigma", 1e308), ("sigma", 1e295), ("u0", -1e296), ("nu", 1e7),
    ("Omega", 1e-7), ("Gamma", 1e17), ("rtol", 1e-18), ("atol", 1.0), ("alpha_hc", 1e7),
    ("v0", float("-inf")), ("max_steps_per_time", 0.5), ("max_events_per_time", float("nan")),
])
def test_out_of_range_values_are_refused_where_they_enter(fmu, name, value):
    _init(fmu)
    before = fmu.get(name)
    refused_and_restored(fmu, lambda: fmu.set(**{name: value}))
    assert name in fmu.errors()[-1] and "rejected" in fmu.errors()[-1]
    assert fmu.get(name) == before
    fmu.slave.exitInitializationMode()
    fmu.t = 0.0
    fmu.step_to(1.0)
    assert all(np.isfinite(fmu.get(n)) for n in OUTPUTS_REAL)


def test_derived_quantities_that_would_overflow_are_refused(fmu):
    """Each value in range, together out of it: kappa = sqrt(Gamma) Omega > 1e8."""
    _init(fmu)
    fmu.set(Gamma=1e16, Omega=1e4)
    expect_error(fmu.slave.exitInitializationMode)
    assert "kappa" in fmu.errors()[-1]


def test_absurd_times_are_refused(fmu):
    fmu.slave.reset()
    refused_and_restored(fmu, lambda: fmu.slave.setupExperiment(startTime=1e300))
    assert "startTime" in fmu.errors()[-1]
    fmu.start()
    refused_and_restored(fmu, fmu.slave.doStep, 0.0, 1e14)
    assert "time range" in fmu.errors()[-1]
    fmu.step_to(1.0)  # restored to before the refused step, the instance goes on


def _me_instance(msgs):
    md = read_model_description(str(FMU_PATH))
    me = FMU2Model(guid=md.guid, unzipDirectory=extract(str(FMU_PATH)),
                   modelIdentifier=md.modelExchange.modelIdentifier, instanceName="me")
    # not a ctypes logger of its own: fmpy's proxy would keep it past this instance
    # (harness/fmu/fmi2_logging.py)
    cb = Fmi2Callbacks(lambda _name, _status, _category, text: msgs.append(text))
    me.instantiate(callbacks=cb.functions)
    me._keep = cb
    return me


def _arr(*x):
    return (ctypes.c_double * len(x))(*x)


def test_model_exchange_states_and_time_are_checked():
    msgs: list[str] = []
    me = _me_instance(msgs)
    try:
        me.setupExperiment(startTime=0.0)
        me.enterInitializationMode()
        me.exitInitializationMode()
        me.enterContinuousTimeMode()
        me.setContinuousStates(_arr(0.001, -0.5), 2)
        saved = me.getFMUstate()
        with pytest.raises(FMICallException):
            me.setContinuousStates(_arr(0.001, 1e308), 2)
        assert "1e+15" in msgs[-1]
        x = _arr(0.0, 0.0)
        me.getContinuousStates(x, 2)  # allowed in the Error state (FMI 2.0.4 3.2.3)
        assert list(x) == [0.001, -0.5]  # kept
        me.setFMUstate(saved)  # the documented way out of Error (FMI 2.0.4 2.1.3)
        with pytest.raises(FMICallException):
            me.setTime(1e300)
        me.setFMUstate(saved)
        me.freeFMUstate(saved)
        # the largest valid states give finite derivatives
        me.setContinuousStates(_arr(1e15, -1e15), 2)
        dx = _arr(0.0, 0.0)
        me.getDerivatives(dx, 2)
        assert np.all(np.isfinite(dx))
    finally:
        me.terminate()
        me.freeInstance()


def test_fmi3_refuses_the_same_values():
    md = read_model_description(str(FMU3_PATH))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(FMU3_PATH)),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="v3")
    s.instantiate()
    try:
        with pytest.raises(FMICallException):
            s.enterInitializationMode(startTime=1e300)
        s.reset()  # FMI 3.0 (2.2.3): after fmi3Error the instance is Terminated until reset
        s.enterInitializationMode(startTime=0.0)
        saved = s.getFMUState()
        for name, bad in (("Omega", 1.8e308), ("sigma", 1e308), ("u0", -1e296),
                          ("F_ext", float("nan"))):
            with pytest.raises(FMICallException):
                s.setFloat64([vr[name]], [bad])
            with pytest.raises(FMICallException):  # Terminated: no initialisation to leave
                s.exitInitializationMode()
            s.setFMUState(saved)  # back to Initialization Mode, values as before
        s.freeFMUState(saved)
        s.exitInitializationMode()
        s.doStep(0.0, 1.0)
        assert np.all(np.isfinite(s.getFloat64([vr[n] for n in OUTPUTS_REAL])))
    finally:
        s.terminate()
        s.freeInstance()


# Corners of the valid ranges (Omega up to 1e4). Each combination either runs a short step to
# a finite state, or is refused with a message: never OK with a non-finite output.
CORNERS = list(itertools.product(
    [0.0, 1e6],                 # nu
    [1e-6, 1e4],                # Omega
    [-1.0 + 1e-12, 1e6],        # sigma
    [(1, 1e16), (2, 0.0)],      # (wall, Gamma)
    [-1e6, 0.0],                # u0 (0: on the wall)
    [1e-15, 0.1],               # rtol
))


@pytest.mark.parametrize("nu,Omega,sigma,wallG,u0,rtol", CORNERS)
def test_corners_of_the_valid_ranges_never_give_inf_with_ok(nu, Omega, sigma, wallG, u0, rtol):
    s = LoggedSlave(name="corner")
    try:
        _init(s)
        s.set(nu=nu, Omega=Omega, sigma=sigma, wall=wallG[0], Gamma=wallG[1], u0=u0, v0=-1e6,
              rtol=rtol, atol=1e-30, max_steps_per_time=1e6, max_events_per_time=1e3)
        try:
            s.slave.exitInitializationMode()
            s.t = 0.0
            s.step_to(1e-4)
        except FMICallException as e:
            assert e.status == 3 and s.errors(), "an error without a message"
            return
        values = [s.get(n) for n in OUTPUTS_REAL]
        assert np.all(np.isfinite(values)), dict(zip(OUTPUTS_REAL, values))
        assert np.all(np.abs(s.state()) <= 1e15)
    finally:
        s.close()
