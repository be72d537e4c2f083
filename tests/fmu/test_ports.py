"""The FMU's ports: inputs F_ext and u_wall, outputs F_contact, v_impact, t_impact.

Independent truths: the closed form with constant ports (mapcheck.exact.ExactOscillator(F_ext=,
u_wall=), an exact scaling of the port-free problem), scipy's DOP853 for ramps given as input
derivatives, the contact law itself for F_contact, and the oracle's crossing times for t_impact.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mapcheck.exact import ExactOscillator, forcing_amplitude_phase
from tests.support.fmu import (FMU3_PATH, LoggedSlave, at_times, expect_error,
                               refused_and_restored, simulate)

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)
UNDERDAMPED = dict(nu=0.196, Omega=7.368)
WALL = {"none": 0, "compliant": 1, "rigid": 2}

# (wall, linear part, sigma, Gamma, r, F_ext, u_wall, start): the ports shift the equilibrium
# (F_ext / Omega^2) and the wall; each case has wall contacts in the window.
CASES = [
    ("compliant", FIG9, 0.5, 10.0, 0.9, 0.02, -0.1, (-0.4, 0.0)),
    ("rigid", FIG9, 0.5, 10.0, 0.9, 0.02, -0.1, (-0.4, 0.0)),
    ("compliant", UNDERDAMPED, 0.1, 1000.0, 0.9, 5.0, 0.2, (-0.5, 1.0)),
    ("rigid", UNDERDAMPED, 0.1, 1000.0, 0.7, -3.0, 0.3, (-0.5, 1.0)),
    ("none", UNDERDAMPED, 0.1, 1000.0, 0.9, 2.5, 0.0, (-0.5, 1.0)),
]
IDS = [f"{c[0]}-{'fig9' if c[1] is FIG9 else 'under'}-F{c[5]}-w{c[6]}" for c in CASES]


def _start(fmu, wall, lin, sigma, Gamma, r, F, w, start, **extra):
    fmu.start(wall=WALL[wall], sigma=sigma, Gamma=Gamma, r=r, u0=start[0], v0=start[1],
              F_ext=F, u_wall=w, **lin, **extra)


@pytest.mark.parametrize("solver", [0, 1], ids=["cvode", "closed-form"])
@pytest.mark.parametrize("wall,lin,sigma,Gamma,r,F,w,start", CASES, ids=IDS)
def test_constant_ports_match_the_closed_form(fmu, wall, lin, sigma, Gamma, r, F, w, start,
                                              solver):
    """FMI 2.0 CS with constant F_ext, u_wall against the exact solution (the scaled oracle),
    20 periods, with either of the FMU's solvers (CVODE; its own closed form, which takes the
    ports as a shifted equilibrium and wall in its particular solution)."""
    if solver:
        lin = dict(lin, solver=solver)
    _start(fmu, wall, lin, sigma, Gamma, r, F, w, start)
    lin = {k: x for k, x in lin.items() if k != "solver"}
    ex = ExactOscillator(sigma=sigma, r=r, Gamma=Gamma, wall=wall, F_ext=F, u_wall=w, **lin)
    times = np.arange(1.0, 21.0)
    want, impacts = ex.strobe(start[0], start[1], times)
    got = []
    for t in times:
        fmu.step_to(t)
        got.append(fmu.state())
    err = np.max(np.abs(np.array(got) - want))
    assert err < (1e-11 if solver else 1e-8), err
    assert fmu.impacts() == impacts[-1]
    if wall != "none":
        assert impacts[-1] > 0  # the wall is exercised


@pytest.mark.parametrize("fmi_type", ["CoSimulation", "ModelExchange"])
@pytest.mark.parametrize("case", [CASES[0], CASES[3]], ids=[IDS[0], IDS[3]])
def test_fmi3_ports_match_the_closed_form(fmi_type, case):
    """FMI 3.0 (CS and ME through fmpy, inputs at their start values) against the oracle; ME is
    integrated by fmpy's own CVODE, hence its looser bound."""
    wall, lin, sigma, Gamma, r, F, w, start = case
    res = simulate(FMU3_PATH, fmi_type, 0.0, 10.0, 0.5, rtol=1e-10, wall=wall, sigma=sigma,
                   Gamma=Gamma, r=r, u0=start[0], v0=start[1], F_ext=F, u_wall=w, **lin)
    times = np.arange(1.0, 11.0)
    got, impacts = at_times(res, times)
    want, n = ExactOscillator(sigma=sigma, r=r, Gamma=Gamma, wall=wall, F_ext=F, u_wall=w,
                              **lin).strobe(start[0], start[1], times)
    tol = 1e-8 if fmi_type == "CoSimulation" else 1e-5
    assert np.max(np.abs(got - want)) < tol
    assert impacts[-1] == n[-1]


def test_zero_inputs_set_every_step_change_nothing_bit_for_bit():
    """A master that writes F_ext = u_wall = 0 before every step gets the port-free run to the
    last bit (unchanged inputs do not restart CVODE)."""
    runs = []
    for write in (False, True):
        s = LoggedSlave(name=f"zero{write}")
        try:
            s.start(wall=WALL["rigid"], sigma=0.05, r=0.9, u0=-0.5, v0=1.0, **UNDERDAMPED)
            out = []
            for k in range(1, 200):
                if write:
                    s.set(F_ext=0.0, u_wall=0.0)
                s.step_to(0.1 * k)
                out.append(np.append(s.state(), [s.impacts(), s.get("F_contact")]))
            runs.append(np.array(out))
        finally:
            s.close()
    assert runs[0][-1, 2] > 0
    assert np.array_equal(runs[0], runs[1])


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


# -- outputs -------------------------------------------------------------------------------------

def test_contact_force_is_the_spring_in_the_wall_and_zero_in_flight(fmu):
    """Compliant linear wall: F_contact = kappa^2 (u - u_wall) inside, 0 outside, at every
    sampled point of a run with many contacts."""
    _start(fmu, "compliant", FIG9, 0.5, 10.0, 0.9, 0.02, -0.1, (-0.4, 0.0))
    k2 = 10.0 * FIG9["Omega"] ** 2
    inside = 0
    for k in range(1, 1500):
        fmu.step_to(0.0137 * k)
        u, F = fmu.state()[0], fmu.get("F_contact")
        if fmu.in_contact():
            inside += 1
            assert F == pytest.approx(k2 * (u + 0.1), rel=1e-12, abs=1e-300)
        else:
            assert F == 0.0
    assert inside >= 5


def test_contact_force_while_sticking_is_the_holding_force(fmu):
    """Rigid wall, chatter into sticking (r = 0): on the wall F_contact is the net force the
    wall holds back, F(t) + F_ext - Omega^2 (u_wall + 1) > 0."""
    lin = UNDERDAMPED
    F_g, phi = forcing_amplitude_phase(**lin)
    fmu.start(wall=WALL["rigid"], sigma=10.0, r=0.0, u0=-0.03, v0=0.0, F_ext=1.0, u_wall=0.05,
              **lin)
    stuck = 0
    for k in range(1, 200):
        t = 0.005 * k
        fmu.step_to(t)
        if fmu.in_contact():
            stuck += 1
            want = 11.0 * F_g * math.cos(2 * math.pi * t + phi) + 1.0 - lin["Omega"] ** 2 * 1.05
            assert fmu.get("F_contact") == pytest.approx(want, rel=1e-9)
            assert fmu.get("F_contact") > 0.0
            assert fmu.state()[0] == 0.05  # on the wall, exactly
    assert stuck > 5


@pytest.mark.parametrize("case", [c for c in CASES if c[0] != "none"],
                         ids=[i for c, i in zip(CASES, IDS) if c[0] != "none"])
def test_impact_time_and_velocity(fmu, case):
    """t_impact is the oracle's last entry time and v_impact the relative velocity just before it
    (the closed form's state 1e-10 before the entry; the wall is at rest), at every one of 1000
    communication points over 20 periods, with the impact count equal to the oracle's at each (no chatter here:
    the smallest entry velocity is asserted well above the sticking threshold)."""
    wall, lin, sigma, Gamma, r, F, w, start = case
    _start(fmu, wall, lin, sigma, Gamma, r, F, w, start)
    ex = ExactOscillator(sigma=sigma, r=r, Gamma=Gamma, wall=wall, F_ext=F, u_wall=w, **lin)
    kind = "impact" if wall == "rigid" else "enter"
    entries = [t for t, k in ex.crossings(start[0], start[1], 0.0, 20.0) if k == kind]
    assert entries
    before, _ = ex.strobe(start[0], start[1], [t - 1e-10 for t in entries])
    v_in = before[:, 1]
    assert np.all(v_in > 1e-3)
    for k in range(1, 1001):
        fmu.step_to(0.02 * k)
        n = sum(1 for t in entries if t <= fmu.t)
        assert fmu.impacts() == n, (fmu.t, fmu.impacts(), n)
        if n:
            assert abs(fmu.get("t_impact") - entries[n - 1]) < 1e-9
            assert fmu.get("v_impact") == pytest.approx(v_in[n - 1], rel=1e-7)
        else:
            assert (fmu.get("t_impact"), fmu.get("v_impact")) == (0.0, 0.0)


# -- a wall that jumps into the mass between steps ------------------------------------------------

def _after_jump(fmu, wall: str, w: float, y: tuple[float, float], t: float, r: float = 0.9,
                Gamma: float = 1000.0, sigma: float = 0.1, lin: dict = UNDERDAMPED,
                T: float = 3.0, n0: int = 0) -> None:
    """From the state the rule gives right after a jump, the run to T against the closed form
    with the wall held at w: states every 0.01 to 1e-8, impact counts exact, the rigid wall
    never penetrated."""
    ex = ExactOscillator(sigma=sigma, r=r, Gamma=Gamma, wall=wall, u_wall=w, **lin)
    times = np.round(np.arange(t + 0.01, T + 1e-12, 0.01), 12)
    want, counts = ex.dense(y[0], y[1], times, t0=t)
    for x, c, tk in zip(want, counts, times):
        fmu.step_to(float(tk))
        got = fmu.state()
        assert np.max(np.abs(got - x)) < 1e-8, (tk, got, x)
        assert fmu.impacts() == n0 + c, tk
        if wall == "rigid":
            assert got[0] <= w
    assert counts[-1] > 0  # the wall is hit again after the jump


@pytest.mark.parametrize("t_jump", [0.01, 0.03, 0.05])
@pytest.mark.parametrize("depth", [0.01, 0.1, 0.3])
def test_rigid_wall_jumping_into_the_mass_places_it_on_the_wall_with_an_impact(fmu, t_jump, depth):
    """Documented rule (model.c, model_input_jump): the mass is put on the new wall position and
    the impact law acts on its velocity relative to the wall (v -> -r v, counted, with v_impact and
    t_impact). Jumps 0.01 .. 0.3 deep at three times while the mass moves towards the wall; the
    run after the jump against the closed form."""
    fmu.start(wall=WALL["rigid"], sigma=0.1, r=0.8, u0=-0.5, v0=1.0, **UNDERDAMPED)
    fmu.step_to(t_jump)
    u, v = fmu.state()
    assert v > 0.1  # the mass moves into the jumping wall: the impact rule must act
    w = u - depth
    fmu.set(u_wall=w)
    fmu.step_to(t_jump + 1e-9)
    u1, v1 = fmu.state()
    assert u1 <= w and u1 == pytest.approx(w, abs=1e-8)  # placed, then moved off
    assert fmu.impacts() == 1 and fmu.get("v_impact") == v
    assert fmu.get("t_impact") == t_jump
    assert v1 == pytest.approx(-0.8 * v, rel=1e-6)
    _after_jump(fmu, "rigid", w, (w, -0.8 * v), t_jump, r=0.8, n0=1)


@pytest.mark.parametrize("t_jump", [0.01, 0.05])
@pytest.mark.parametrize("depth", [0.01, 0.05, 0.2])
def test_rigid_wall_jump_onto_a_receding_mass_places_it_without_rebound(fmu, t_jump, depth):
    """The wall jumps past a mass that moves away from it: placed on the wall, no impact, its
    velocity kept; then against the closed form."""
    fmu.start(wall=WALL["rigid"], sigma=0.1, u0=-0.5, v0=-1.0, **UNDERDAMPED)
    fmu.step_to(t_jump)
    u, v = fmu.state()
    assert v < -0.1
    fmu.set(u_wall=u - depth)
    fmu.step_to(t_jump + 1e-9)
    assert fmu.impacts() == 0 and fmu.state()[0] <= u - depth
    _after_jump(fmu, "rigid", u - depth, (u - depth, v), t_jump)


@pytest.mark.parametrize("t_jump", [0.02, 0.05, 0.1])
@pytest.mark.parametrize("depth", [0.001, 0.01, 0.05])
def test_compliant_wall_jumping_into_the_mass_starts_a_contact_without_a_jump(fmu, t_jump, depth):
    """The mass is inside the compliant wall after the jump, as after a start inside it: no
    entry jump, no impact; F_contact answers the new wall at once (direct feedthrough); the run
    on against the closed form started inside the wall."""
    fmu.start(wall=WALL["compliant"], sigma=0.1, Gamma=1000.0, u0=-0.5, v0=1.0, **UNDERDAMPED)
    fmu.step_to(t_jump)
    u, v = fmu.state()
    fmu.set(u_wall=u - depth)
    k2 = 1000.0 * UNDERDAMPED["Omega"] ** 2
    assert fmu.get("F_contact") == pytest.approx(k2 * depth, rel=1e-9)
    fmu.step_to(t_jump + 1e-14)  # the spring changes v by ~ kappa^2 depth 1e-14 < 3e-11 here
    assert fmu.in_contact() and fmu.impacts() == 0
    assert fmu.state() == pytest.approx([u, v], abs=1e-10)  # no jump in the state
    _after_jump(fmu, "compliant", u - depth, (u, v), t_jump)


def test_sticking_mass_follows_a_wall_pushed_into_it_and_is_freed_when_it_recedes(fmu):
    lin = UNDERDAMPED
    fmu.start(wall=WALL["rigid"], sigma=10.0, r=0.0, u0=-0.03, v0=0.0, **lin)
    for k in range(1, 200):
        fmu.step_to(0.005 * k)
        if fmu.in_contact():
            break
    assert fmu.in_contact() and fmu.state()[0] == 0.0
    fmu.set(u_wall=-0.01)  # pushed along
    fmu.step_to(fmu.t + 1e-9)
    assert fmu.state()[0] == -0.01
    fmu.set(u_wall=0.5)  # the wall leaves: the mass flies on with its velocity (0, the wall's)
    t = fmu.t
    fmu.step_to(t + 1e-9)
    assert not fmu.in_contact()
    _after_jump(fmu, "rigid", 0.5, (-0.01, 0.0), t, r=0.0, sigma=10.0, T=t + 2.0,
                n0=fmu.impacts())


def test_inputs_are_validated_where_they_enter(fmu):
    fmu.start()
    for name, bad in (("F_ext", float("nan")), ("F_ext", 1e300), ("u_wall", float("inf")),
                      ("u_wall", 2e6)):
        refused_and_restored(fmu, lambda: fmu.set(**{name: bad}))
        assert name in fmu.errors()[-1]
    assert fmu.get("F_ext") == 0.0 and fmu.get("u_wall") == 0.0
    fmu.step_to(1.0)


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


def test_model_structure_declares_outputs_on_inputs():
    from fmpy import read_model_description

    from tests.support.fmu import FMU_PATH
    for path in (FMU_PATH, FMU3_PATH):
        md = read_model_description(str(path))
        deps = {o.variable.name: sorted(d.name for d in (o.dependencies or []))
                for o in md.outputs}
        assert deps["F_contact"] == ["F_ext", "u", "u_wall", "v", "v_wall"], (path, deps)
        assert set(deps) >= {"u", "v", "impacts", "in_contact", "v_impact", "t_impact"}


def test_model_exchange_wall_jump_is_an_event_with_the_same_rule():
    """ME: the importer sets u_wall beyond the mass (rigid wall) and handles the event the
    indicator's sign change asks for: the mass is put on the wall, v reflected relative to it."""
    import ctypes

    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Model

    from tests.support.fmu import FMU_PATH
    md = read_model_description(str(FMU_PATH))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    me = FMU2Model(guid=md.guid, unzipDirectory=extract(str(FMU_PATH)),
                   modelIdentifier=md.modelExchange.modelIdentifier, instanceName="mej")
    me.instantiate()
    try:
        me.setupExperiment(startTime=0.0)
        me.enterInitializationMode()
        me.setInteger([vr["wall"]], [2])
        me.setReal([vr["u0"], vr["v0"], vr["r"]], [-0.5, 1.0, 0.8])
        me.exitInitializationMode()
        me.newDiscreteStates()
        me.enterContinuousTimeMode()
        g = (ctypes.c_double * 1)()
        me.getEventIndicators(g, 1)
        assert g[0] == -0.5
        me.setReal([vr["u_wall"]], [-0.6])  # the wall jumps 0.1 into the mass
        me.getEventIndicators(g, 1)
        assert g[0] == pytest.approx(0.1)  # sign change: the importer enters event mode
        me.enterEventMode()
        info = me.newDiscreteStates()
        assert info[3]  # valuesOfContinuousStatesChanged
        x = (ctypes.c_double * 2)()
        me.getContinuousStates(x, 2)
        assert x[0] <= -0.6 and x[0] == pytest.approx(-0.6, abs=1e-15)
        assert x[1] == pytest.approx(-0.8 * 1.0)
        assert me.getInteger([vr["impacts"]])[0] == 1
        assert me.getReal([vr["v_impact"]])[0] == 1.0
    finally:
        me.terminate()
        me.freeInstance()
