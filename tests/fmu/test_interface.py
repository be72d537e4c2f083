"""The C FMU as an FMI 2.0 component: packaging, state save/restore, tunable sigma, bad input,
several instances. Physics is checked in test_physics.py (same folder)."""
from __future__ import annotations

import math
import subprocess
import zipfile

import numpy as np
import pytest
from fmpy.validation import validate_fmu

from mapcheck.exact import ExactOscillator
from tests.support.fmu import (FMU_PATH, LoggedSlave, expect_error, on_orbit,
                               refused_and_restored)

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)


# -- packaging ---------------------------------------------------------------------------------

def test_fmpy_validate_reports_no_problem():
    assert validate_fmu(str(FMU_PATH)) == []


def test_cvode_is_linked_statically_and_kept_private(tmp_path):
    with zipfile.ZipFile(FMU_PATH) as z:
        z.extract("binaries/linux64/ImpactOscillator.so", tmp_path)
    so = tmp_path / "binaries/linux64/ImpactOscillator.so"
    ldd = subprocess.run(["ldd", str(so)], capture_output=True, text=True, check=True).stdout
    assert "sundials" not in ldd.lower()
    exported = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True,
                              text=True, check=True).stdout.split()
    assert "fmi2DoStep" in exported
    assert not [s for s in exported if s.startswith(("CVode", "N_V", "SUN"))]


def test_model_description_declares_capabilities():
    from fmpy import read_model_description
    md = read_model_description(str(FMU_PATH))
    cs = md.coSimulation
    assert cs.canHandleVariableCommunicationStepSize
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate
    assert not cs.canBeInstantiatedOnlyOncePerProcess
    names = {v.name: v for v in md.modelVariables}
    assert names["sigma"].variability == "tunable"
    assert {u.variable.name for u in md.outputs} == {"u", "v", "impacts", "in_contact",
                                                     "F_contact", "v_impact", "t_impact",
                                                     "J_uu", "J_uv", "J_vu", "J_vv", "S_u", "S_v"}
    assert cs.canInterpolateInputs  # fmi2SetRealInputDerivatives, order 1
    assert {v.name for v in md.modelVariables if v.causality == "input"} == {"F_ext", "u_wall",
                                                                                   "v_wall"}
    assert {u.variable.name for u in md.initialUnknowns} >= {"u", "v", "F_g", "phi", "kappa"}
    assert md.defaultExperiment.stepSize == "1"


def test_calculated_parameters_follow_eq_5(fmu):
    nu, Om = 0.196, 7.368
    fmu.start(nu=nu, Omega=Om, Gamma=1000.0)
    w2 = 4 * math.pi**2
    F_g = math.hypot(Om**2 - w2, 2 * math.pi * nu)
    assert fmu.get("F_g") == pytest.approx(F_g, rel=1e-14)
    assert fmu.get("phi") == pytest.approx(math.acos((Om**2 - w2) / F_g), rel=1e-14)
    assert fmu.get("kappa") == pytest.approx(math.sqrt(1000.0) * Om, rel=1e-14)


# -- FMU state ---------------------------------------------------------------------------------

def _run(fmu: LoggedSlave, until: float, dt: float = 0.37) -> list[np.ndarray]:
    out = []
    while fmu.t < until - 1e-12:
        fmu.step_to(min(until, fmu.t + dt))
        out.append(np.append(fmu.state(), [fmu.impacts(), fmu.in_contact()]))
    return out


def _inside_the_wall(fmu: LoggedSlave) -> None:
    """Advance in small steps until the mass is inside the compliant wall."""
    for _ in range(20000):
        fmu.step_to(fmu.t + 1e-3)
        if fmu.in_contact():
            return
    raise AssertionError("never entered the wall")


def test_state_restore_reproduces_the_continuation_exactly(fmu):
    fmu.start(t0=0.5, sigma=0.5, **on_orbit(0.5, 0.5))
    fmu.step_to(5.0)
    _inside_the_wall(fmu)  # save in the middle of a contact: the wall mode must be restored
    t_saved = fmu.t
    state = fmu.slave.getFMUstate()
    first = _run(fmu, t_saved + 4.0)
    fmu.slave.setFMUstate(state)
    fmu.t = t_saved
    assert fmu.in_contact()
    second = _run(fmu, t_saved + 4.0)
    fmu.slave.freeFMUstate(state)
    assert np.array_equal(np.array(first), np.array(second))  # to the last bit


def test_serialized_state_restores_in_another_instance(fmu):
    fmu.start(t0=0.5, sigma=0.2, r=0.8, Gamma=20.0, **on_orbit(0.2, 0.5))
    fmu.step_to(3.0)
    _inside_the_wall(fmu)
    t_saved = fmu.t
    state = fmu.slave.getFMUstate()
    blob = fmu.slave.serializeFMUstate(state)
    fmu.slave.freeFMUstate(state)
    expected = _run(fmu, t_saved + 3.0)

    other = LoggedSlave(name="other")
    try:
        other.start(sigma=0.9)  # different parameters: the state carries its own
        restored = other.slave.deSerializeFMUstate(blob)
        other.slave.setFMUstate(restored)
        other.slave.freeFMUstate(restored)
        other.t = t_saved
        assert other.get("r") == 0.8 and other.get("Gamma") == 20.0
        assert np.array_equal(np.array(_run(other, t_saved + 3.0)), np.array(expected))
    finally:
        other.close()


def test_garbage_is_not_a_serialized_state(fmu):
    fmu.start()
    expect_error(fmu.slave.deSerializeFMUstate, b"\x00" * 16)
    assert any("not a serialised state" in m for m in fmu.errors())


# -- tunable sigma -----------------------------------------------------------------------------

def test_sigma_change_acts_from_that_time_with_the_state_carried(fmu):
    nu, Om = FIG9["nu"], FIG9["Omega"]
    fmu.start(t0=0.5, sigma=0.5, **on_orbit(0.5, 0.5))
    fmu.step_to(10.5)
    x, k = fmu.state(), fmu.impacts()
    fmu.set(sigma=0.2)
    fmu.step_to(20.5)
    exact, count = ExactOscillator(nu, Om, 0.2).strobe(x[0], x[1], [20.5], t0=10.5)
    assert np.max(np.abs(fmu.state() - exact[0])) < 1e-8
    assert fmu.impacts() - k == count[0]


def test_fixed_parameters_cannot_change_after_initialisation(fmu):
    fmu.start(r=0.9)
    fmu.step_to(1.0)
    expect_error(lambda: fmu.set(r=0.5))
    assert fmu.get("r") == 0.9
    assert any("only sigma is tunable" in m for m in fmu.errors())


# -- bad input ---------------------------------------------------------------------------------

@pytest.mark.parametrize("name,value,why", [
    ("r", 2.0, "[0, 1]"),
    ("r", -0.1, "[0, 1]"),
    ("r", float("nan"), "finite"),
    ("Omega", 0.0, "[1e-06, 10000]"),
    ("Omega", float("inf"), "finite"),
    ("nu", -1.0, "[0, 1e+06]"),
    ("Gamma", -1.0, "[0, 1e+16]"),
    ("sigma", -1.5, "(-1, 1e+06]"),
    ("rtol", 0.0, "[1e-15, 0.1]"),
    ("u0", float("nan"), "finite"),
    ("wall", 3, "[0, 2]"),
])
def test_bad_parameter_is_rejected_with_a_message_and_nothing_lost(fmu, name, value, why):
    fmu.slave.reset()
    fmu.slave.setupExperiment(startTime=0.0)
    fmu.slave.enterInitializationMode()
    before = fmu.slave.getInteger([fmu.vr[name]])[0] if name == "wall" else fmu.get(name)
    saved = fmu.slave.getFMUstate()
    expect_error(lambda: fmu.set(**{name: value}))
    msg = fmu.errors()[-1]
    assert name in msg and why in msg, msg
    after = fmu.slave.getInteger([fmu.vr[name]])[0] if name == "wall" else fmu.get(name)
    assert after == before  # the rejected value was not stored
    # FMI 2.0.4 section 2.1.3: after fmi2Error the simulation cannot go on with this instance
    # (it is in the Error state) ...
    expect_error(fmu.slave.exitInitializationMode)
    # ... unless a state saved before is restored: then it goes on with the old value.
    fmu.slave.setFMUstate(saved)
    fmu.slave.freeFMUstate(saved)
    fmu.slave.exitInitializationMode()
    fmu.step_to(1.0)


def test_zero_stiffness_is_an_error_only_with_a_compliant_wall(fmu):
    fmu.slave.reset()
    fmu.slave.setupExperiment(startTime=0.0)
    fmu.slave.enterInitializationMode()
    fmu.set(Gamma=0.0, wall="compliant")
    expect_error(fmu.slave.exitInitializationMode)
    assert "Gamma" in fmu.errors()[-1]
    fmu.start(Gamma=0.0, wall="rigid")  # no spring needed
    fmu.step_to(2.0)


def test_rigid_wall_start_inside_the_wall_is_an_error(fmu):
    fmu.slave.reset()
    fmu.slave.setupExperiment(startTime=0.0)
    fmu.slave.enterInitializationMode()
    fmu.set(wall="rigid", u0=0.1)
    expect_error(fmu.slave.exitInitializationMode)
    assert "inside the rigid wall" in fmu.errors()[-1]


def test_unknown_value_reference_and_wrong_types(fmu):
    fmu.start()
    expect_error(fmu.slave.getReal, [999])
    expect_error(fmu.slave.getInteger, [fmu.vr["u"]])
    expect_error(fmu.slave.setReal, [999], [1.0])
    expect_error(fmu.slave.getString, [0])
    assert any("value reference 999" in m for m in fmu.errors())


def test_calls_in_the_wrong_state(fmu):
    fmu.slave.reset()  # instantiated, not initialised
    expect_error(fmu.slave.doStep, 0.0, 1.0)
    assert "not allowed in Instantiated" in fmu.errors()[-1]
    expect_error(fmu.slave.exitInitializationMode)  # now in Error (FMI 2.0.4 2.1.3)
    assert "not allowed in Error" in fmu.errors()[-1]
    fmu.start()  # fmi2Reset leads out of Error
    refused_and_restored(fmu, fmu.slave.doStep, 5.0, 1.0)  # not the FMU's time
    refused_and_restored(fmu, fmu.slave.doStep, 0.0, -1.0)
    refused_and_restored(fmu, fmu.slave.doStep, 0.0, 0.0)  # both standards: h > 0
    refused_and_restored(fmu, fmu.slave.doStep, 0.0, -0.0)
    fmu.step_to(1.0)  # restored, usable


def test_tolerances_cvode_cannot_meet_are_rejected_where_they_enter():
    """rtol at round-off (1e-18) once failed the step inside CVODE; it is now refused when set,
    with the valid range in the message, and the instance goes on with its previous value.
    (A step that exceeds the work bound fails with fmi2Error: see test_bounds.py.)"""
    fmu = LoggedSlave(name="hard")
    try:
        fmu.slave.reset()
        fmu.slave.setupExperiment(startTime=0.0)
        fmu.slave.enterInitializationMode()
        refused_and_restored(fmu, lambda: fmu.set(rtol=1e-18))
        assert "rtol" in fmu.errors()[-1] and "[1e-15, 0.1]" in fmu.errors()[-1]
        fmu.set(atol=1e-30, sigma=0.5)
        fmu.slave.exitInitializationMode()
        fmu.t = 0.0
        fmu.step_to(2.0)
        assert np.all(np.isfinite(fmu.state()))
    finally:
        fmu.close()


# -- several instances ---------------------------------------------------------------------------

def test_several_instances_in_one_process_are_independent():
    params = [dict(sigma=0.2, **on_orbit(0.2, 0.25)),
              dict(sigma=0.5, wall="rigid", r=0.7, **on_orbit(0.5, 0.25)),
              dict(sigma=0.9, Gamma=50.0, **on_orbit(0.9, 0.25))]
    times = np.arange(0.5, 30.01, 0.25)
    alone = []
    for p in params:
        s = LoggedSlave(name="alone")
        s.start(t0=0.25, **p)
        for t in times:
            s.step_to(float(t))
        alone.append(np.append(s.state(), s.impacts()))
        s.close()
    assert all(a[2] > 0 for a in alone), "every case was meant to hit the wall"
    together = [LoggedSlave(name=f"i{k}") for k in range(len(params))]
    try:
        for s, p in zip(together, params):
            s.start(t0=0.25, **p)
        for t in times:  # interleaved steps
            for s in together:
                s.step_to(float(t))
        for s, ref in zip(together, alone):
            assert np.array_equal(np.append(s.state(), s.impacts()), ref)
    finally:
        for s in together:
            s.close()
