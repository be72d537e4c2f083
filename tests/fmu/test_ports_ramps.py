"""The FMU's input ports as ramps: F_ext and u_wall given by values and first derivatives
(FMI 2.0 canInterpolateInputs), and a wall moving at constant velocity.

Independent truths: scipy's DOP853 on the FMU's equation written out independently, with
scipy's event location and the restitution law in the wall's frame for the moving wall.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mapcheck.exact import forcing_amplitude_phase
from tests.support.fmu import WALLS as WALL
from tests.support.fmu import refused_and_restored

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)
UNDERDAMPED = dict(nu=0.196, Omega=7.368)


# -- input derivatives (FMI 2.0 canInterpolateInputs) ------------------------------------------

def _rhs_free(lin, sigma, F0, F1, w0=None, w1=0.0, kappa2=0.0):
    """u'' + nu u' + Omega^2 (u + 1) [+ kappa^2 (u - w(t))] = (1+sigma) F_g cos(2 pi t + phi)
    + F(t), F = F0 + F1 t, w = w0 + w1 t: the FMU's equation, written out independently."""
    nu, Om = lin["nu"], lin["Omega"]
    F_g, phi = forcing_amplitude_phase(nu, Om)

    def f(t, y):
        k = Om**2 * (y[0] + 1.0)
        if w0 is not None:
            k += kappa2 * (y[0] - (w0 + w1 * t))
        return [y[1], (1 + sigma) * F_g * math.cos(2 * math.pi * t + phi) - nu * y[1] - k
                + F0 + F1 * t]
    return f


def _ramp_run(fmu, h, T, F0, F1, w0, w1, with_derivatives):
    """Steps of size h to T; before each, the master sets the inputs' values at the step start
    and (optionally) their slopes."""
    out = []
    n = int(round(T / h))
    for k in range(n):
        t = k * h
        fmu.set(F_ext=F0 + F1 * t, u_wall=w0 + w1 * t)
        if with_derivatives:
            fmu.slave.setRealInputDerivatives([fmu.vr["F_ext"], fmu.vr["u_wall"]], [1, 1],
                                              [F1, w1])
        fmu.step_to(t + h)
        out.append(fmu.state())
    return np.array(out)


def test_a_force_ramp_given_as_input_derivative_is_integrated_exactly(fmu):
    """F_ext(t) = 0.5 + 0.3 t by values and first derivatives at h = 1: the FMU matches an
    independent integration of the ramp; holding the inputs instead is off by O(h)."""
    lin, sigma = UNDERDAMPED, 0.1
    F0, F1 = 0.5, 0.3
    sol = solve_ivp(_rhs_free(lin, sigma, F0, F1), (0, 8), [-0.5, 1.0], method="DOP853",
                    rtol=1e-13, atol=1e-13, t_eval=np.arange(1.0, 9.0))
    fmu.start(wall=WALL["none"], sigma=sigma, u0=-0.5, v0=1.0, **lin)
    got = _ramp_run(fmu, 1.0, 8.0, F0, F1, 0.0, 0.0, True)
    err = np.max(np.abs(got - sol.y.T))
    assert err < 1e-9, err
    fmu.start(wall=WALL["none"], sigma=sigma, u0=-0.5, v0=1.0, **lin)
    held = _ramp_run(fmu, 1.0, 8.0, F0, F1, 0.0, 0.0, False)
    assert np.max(np.abs(held - sol.y.T)) > 1e-4  # the derivative is what makes it exact


def test_a_wall_ramp_acts_on_the_spring_exactly(fmu):
    """u_wall(t) = w0 + w1 t given by values and derivatives, the mass held inside a stiff
    compliant wall the whole time (linear problem, no events): against DOP853."""
    lin, sigma, Gamma = FIG9, 0.2, 1e4
    Om2 = lin["Omega"] ** 2
    k2 = Gamma * Om2
    w0, w1 = -5000.0, 0.05
    u_eq = (-Om2 + k2 * w0) / (Om2 + k2)  # static equilibrium in the wall
    sol = solve_ivp(_rhs_free(lin, sigma, 0.0, 0.0, w0, w1, k2), (0, 6), [u_eq, 0.0],
                    method="DOP853", rtol=1e-13, atol=1e-12, t_eval=np.arange(1.0, 7.0))
    fmu.start(wall=WALL["compliant"], sigma=sigma, Gamma=Gamma, u0=u_eq, v0=0.0,
              u_wall=w0, **lin)
    got = _ramp_run(fmu, 1.0, 6.0, 0.0, 0.0, w0, w1, True)
    assert fmu.in_contact() and fmu.impacts() == 0
    err = np.max(np.abs(got - sol.y.T))
    assert err < 1e-8 * abs(w0), err
    # F_contact is the spring's force on u - u_wall (repulsive positive)
    u = fmu.state()[0]
    assert fmu.get("F_contact") == pytest.approx(k2 * (u - fmu.get("u_wall")), rel=1e-12)


def test_input_derivative_errors_and_higher_orders(fmu):
    fmu.start()
    sd = fmu.slave.setRealInputDerivatives
    refused_and_restored(fmu, sd, [fmu.vr["sigma"]], [1], [1.0])
    refused_and_restored(fmu, sd, [fmu.vr["F_ext"]], [1], [float("nan")])
    refused_and_restored(fmu, sd, [fmu.vr["F_ext"]], [0], [1.0])
    # order 2 is accepted with a warning and ignored (the ramp is first order); the warning is
    # logged only with debug logging on (FMI 2.0.4 2.1.5), under a declared category
    fmu.messages.clear()
    sd([fmu.vr["F_ext"]], [2], [1.0])
    assert fmu.messages == []
    fmu.slave.setDebugLogging(True, ["logStatusWarning"])
    sd([fmu.vr["F_ext"]], [2], [1.0])
    assert any(s == 1 and c == "logStatusWarning" and "order 2" in m for s, c, m in fmu.messages)
    fmu.slave.setDebugLogging(False, [])


# -- a moving wall: restitution relative to the wall ---------------------------------------------

def _moving_wall_reference(lin, sigma, Gamma, r, wall, w0, w1, y0, times):
    """An independent event-driven integration (DOP853 with scipy's event location) of the
    oscillator against a wall at w0 + w1 t: the compliant wall's spring acts on u - w, its entry
    jump is v - w1 -> r (v - w1); the rigid wall's impact is v - w1 -> -r (v - w1)."""
    Om2 = lin["Omega"] ** 2
    k2 = Gamma * Om2
    inside = False
    t, y, out = 0.0, np.array(y0, float), []
    for T in times:
        while t < T:
            f = _rhs_free(lin, sigma, 0.0, 0.0, w0 if inside else None, w1, k2)

            def g(tt, yy):
                return yy[0] - (w0 + w1 * tt)
            g.terminal = True
            g.direction = -1 if inside else 1
            sol = solve_ivp(f, (t, T), y, method="DOP853", rtol=1e-13, atol=1e-14, events=g,
                            max_step=0.01)
            if sol.status == 1 and sol.t_events[0].size and sol.t_events[0][0] > t + 1e-12:
                t = sol.t_events[0][0]
                y = sol.y_events[0][0].copy()
                rel = y[1] - w1
                if wall == "compliant":
                    if not inside:
                        y[1] = w1 + r * rel
                    inside = not inside
                else:
                    y[1] = w1 - r * rel
                y[0] = w0 + w1 * t
            else:
                t, y = T, sol.y[:, -1]
        out.append(y.copy())
    return np.array(out)


@pytest.mark.parametrize("wall,r", [("compliant", 0.9), ("rigid", 0.7)])
def test_a_moving_wall_reflects_relative_to_its_velocity(fmu, wall, r):
    """u_wall(t) = -0.1 - 0.05 t (values and derivatives each step): the impacts and contacts
    against an independent event-driven integration."""
    lin, sigma, Gamma = UNDERDAMPED, 0.05, 1000.0
    w0, w1 = -0.1, -0.05
    times = np.arange(1.0, 6.0)
    want = _moving_wall_reference(lin, sigma, Gamma, r, wall, w0, w1, (-0.5, 1.0), times)
    fmu.start(wall=WALL[wall], sigma=sigma, Gamma=Gamma, r=r, u0=-0.5, v0=1.0, u_wall=w0, **lin)
    got = _ramp_run(fmu, 1.0, 5.0, 0.0, 0.0, w0, w1, True)
    assert fmu.impacts() >= 3
    err = np.max(np.abs(got - want))
    assert err < 1e-7, err
    # the same wall held still each step (no derivatives) is a different run
    fmu.start(wall=WALL[wall], sigma=sigma, Gamma=Gamma, r=r, u0=-0.5, v0=1.0, u_wall=w0, **lin)
    held = _ramp_run(fmu, 1.0, 5.0, 0.0, 0.0, w0, w1, False)
    assert np.max(np.abs(held - want)) > 1e-4
