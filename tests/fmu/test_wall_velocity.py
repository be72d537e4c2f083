"""The wall's velocity as an input, v_wall: in Co-Simulation the wall moves over a step as
u_wall + v_wall (t - t0) from its value at the step's start, as an FMI 2.0 input derivative of
u_wall would move it; restitution, the contact laws and sticking act on v - v_wall.

Truths: the independent DOP853 reference of the ramp wall (``mapcheck.inputs_reference``, its jump
laws written out there), and the FMI 2.0 input derivative (v_wall alone, the input derivative
alone and both together give the same run, bit for bit).  A master that sets u_wall at each communication
point without v_wall gets a wall that jumps: a different run, which the reference tells apart.
"""
from __future__ import annotations

from ctypes import c_double, c_int, c_uint

import numpy as np
import pytest

from mapcheck.inputs_reference import InputsReference, Piece, RefState
from tests.support.fmu import FMU3_PATH, WALLS, LoggedSlave

UNDERDAMPED = dict(nu=0.196, Omega=7.368)
#: (wall, sigma, r, Gamma, u_wall at 0, v_wall, start): impacts on a moving wall in every period
CASES = [
    ("compliant", 0.1, 0.9, 1000.0, 0.2, 0.03, (-0.5, 1.0)),
    ("rigid", 0.1, 0.7, 1000.0, 0.3, -0.02, (-0.5, 1.0)),
]
STEPS = [0.3] * 10 + [0.7] * 4  # 5.8 periods, steps across the integer times


def _run(fmu: LoggedSlave, case, solver: int, how: str) -> np.ndarray:
    """The master sets u_wall at each communication point (its value on the ramp there) and the
    wall's velocity by `how`: "v_wall", "derivative" (FMI 2.0), "both", or "none"."""
    wall, sigma, r, Gamma, w0, dw, (u0, v0) = case
    fmu.start(wall=WALLS[wall], solver=solver, sigma=sigma, r=r, Gamma=Gamma, u_wall=w0,
              u0=u0, v0=v0, **UNDERDAMPED)
    rows, t = [], 0.0
    for h in STEPS:
        fmu.set(u_wall=w0 + dw * t)
        if how in ("v_wall", "both"):
            fmu.set(v_wall=dw)
        if how in ("derivative", "both"):
            fmu.slave.setRealInputDerivatives([fmu.vr["u_wall"]], [1], [dw])
        fmu.step_to(t + h)
        t += h
        rows.append([*fmu.state(), fmu.impacts(), fmu.get("v_impact")])
    return np.array(rows)


def _reference(case) -> np.ndarray:
    wall, sigma, r, Gamma, w0, dw, (u0, v0) = case
    ref = InputsReference(sigma=sigma, r=r, Gamma=Gamma, wall=wall, **UNDERDAMPED)
    st, rows, t = RefState(0.0, u0, v0), [], 0.0
    for h in STEPS:
        ref.run(st, Piece(t, t + h, w=w0 + dw * t, dw=dw))
        t += h
        rows.append([st.u, st.v, st.impacts, st.v_impact])
    return np.array(rows)


@pytest.mark.parametrize("solver", [0, 1], ids=["cvode", "closed-form"])
@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_v_wall_moves_the_wall_as_the_ramp_reference(module_fmu, case, solver):
    """v_wall against the external reference: states to 1e-8, impact counts exact, v_impact (the
    velocity relative to the moving wall) to 1e-8; the input derivative, and both together, give
    the very same run (bit for bit); without the velocity the run is off by far more."""
    want = _reference(case)
    got = _run(module_fmu, case, solver, "v_wall")
    assert want[-1, 2] >= 2
    assert np.abs(got[:, :2] - want[:, :2]).max() < 1e-8, np.abs(got - want).max(axis=0)
    np.testing.assert_array_equal(got[:, 2], want[:, 2])
    assert np.abs(got[:, 3] - want[:, 3]).max() < 1e-8
    for how in ("derivative", "both"):
        other = _run(module_fmu, case, solver, how)
        np.testing.assert_array_equal(other, got, err_msg=how)  # the same ramp: bit for bit
    jumping = _run(module_fmu, case, solver, "none")
    assert np.abs(jumping[:, :2] - want[:, :2]).max() > 1e-4


def test_fmi3_co_simulation_takes_v_wall():
    """FMI 3.0 has no input derivatives: v_wall is its moving wall, the same run as FMI 2.0's."""
    from fmpy import simulate_fmu

    case = CASES[1]
    wall, sigma, r, Gamma, w0, dw, (u0, v0) = case
    t = np.array([0.0, 6.0])
    inputs = np.array([(ti, w0 + dw * ti, dw) for ti in t],
                      dtype=[("time", float), ("u_wall", float), ("v_wall", float)])
    res = simulate_fmu(str(FMU3_PATH), stop_time=6.0, output_interval=0.3, input=inputs,
                       start_values=dict(wall=WALLS[wall], sigma=sigma, r=r, Gamma=Gamma, u0=u0,
                                         v0=v0, **UNDERDAMPED), output=["u", "v", "impacts"])
    ref = InputsReference(sigma=sigma, r=r, Gamma=Gamma, wall=wall, **UNDERDAMPED)
    st = RefState(0.0, u0, v0)
    for k, tk in enumerate(res["time"][1:], start=1):
        ref.run(st, Piece(res["time"][k - 1], tk, w=w0 + dw * res["time"][k - 1], dw=dw))
        assert abs(res["u"][k] - st.u) < 1e-8 and abs(res["v"][k] - st.v) < 1e-8, tk
        assert res["impacts"][k] == st.impacts


def test_an_input_derivative_of_v_wall_is_ignored_with_a_warning(fmu):
    """The wall is unaccelerated over a step: a derivative of v_wall (0 from a master that sends
    every input's) changes nothing, a nonzero one is ignored with a warning."""
    from fmpy.fmi2 import fmi2Warning

    fmu.start(wall=WALLS["rigid"], u0=-0.5, v0=1.0, **UNDERDAMPED)
    fmu.slave.setRealInputDerivatives([fmu.vr["v_wall"]], [1], [0.0])
    status = fmu.slave.fmi2SetRealInputDerivatives(
        fmu.slave.component, (c_uint * 1)(fmu.vr["v_wall"]), 1, (c_int * 1)(1), (c_double * 1)(2.0))
    assert status == fmi2Warning
    fmu.step_to(1.0)
    assert fmu.errors() == []

