"""The FMU's input promises against an independent reference: ramped ports
whose doSteps cross the closed form's re-origin, inputs holding their end-of-step values,
sticking on a moving rigid wall and its release with the wall's velocity, grazing exits from
inside the compliant wall, in both solver modes (``solver`` 0 CVODE, 1 the closed form).

The truth is ``mapcheck.inputs_reference`` (DOP853 at rtol 1e-13 with scipy's event search and
the jump laws written out there), never the FMU's other solver: both solvers share model.c's
jump laws, so comparing them cannot see a wrong law.  Impact counts are exact: every case has
r = 0 sticking or impacts far above the sticking threshold (the smallest relative impact
velocity is asserted), so no chatter can make a count ambiguous.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from mapcheck.exact import forcing_amplitude_phase
from mapcheck.inputs_reference import InputsReference, Piece, RefState
from tests.support.fmu import EVENTS_LOG, WALLS, LoggedSlave

#: the FMU logs from instantiation on (the fixture in conftest reads this)
FMU_LOGGING = True
UNDERDAMPED = dict(nu=0.196, Omega=7.368)
SOLVERS = pytest.mark.parametrize("solver", [0, 1], ids=["cvode", "closed-form"])
STEPS = {"h0.7": [0.7] * 9, "h1.7": [1.7] * 4, "random": list(np.random.default_rng(22).uniform(0.05, 1.9, 8))}


def _drive(fmu, ref: InputsReference, st: RefState, steps, F0, dF, w0, dw, derivatives=True):
    """Steps of the given sizes; before each the master sets the inputs' values at the step start
    (and, with ``derivatives``, their slopes); the reference runs the same piece.  Returns the
    FMU's and the reference's states, impact counts and F_ext/u_wall after each step."""
    got, want, t = [], [], 0.0
    for h in steps:
        F, w = F0 + dF * t, w0 + dw * t
        fmu.set(F_ext=F, u_wall=w)
        if derivatives:
            fmu.slave.setRealInputDerivatives([fmu.vr["F_ext"], fmu.vr["u_wall"]], [1, 1], [dF, dw])
        fmu.step_to(t + h)
        ref.run(st, Piece(t, t + h, F, dF if derivatives else 0.0, w, dw if derivatives else 0.0))
        t += h
        got.append([*fmu.state(), fmu.impacts()])
        want.append([st.u, st.v, st.impacts])
    return np.array(got), np.array(want)


def _start(fmu, wall, solver, sigma, r, Gamma, F, w, y0, **lin):
    fmu.start(wall=WALLS[wall], solver=solver, sigma=sigma, r=r, Gamma=Gamma, F_ext=F, u_wall=w,
              u0=y0[0], v0=y0[1], **lin)


RAMPS = [  # (wall, sigma, r, Gamma, F0, dF, w0, dw, start): impacts in every step of 1.7
    ("compliant", 0.1, 0.9, 1000.0, 5.0, 0.4, 0.2, 0.03, (-0.5, 1.0)),
    ("rigid", 0.1, 0.7, 1000.0, -3.0, 0.5, 0.3, -0.02, (-0.5, 1.0)),
]


@SOLVERS
@pytest.mark.parametrize("steps", list(STEPS), ids=list(STEPS))
@pytest.mark.parametrize("case", RAMPS, ids=[c[0] for c in RAMPS])
def test_ramped_ports_across_the_reorigin(fmu, case, steps, solver):
    """F_ext and u_wall ramped by derivatives, doSteps of 0.7, 1.7 and random sizes: a step of
    1.7 with impacts in it crosses t = k inside the step, where the closed form moves its time
    origin (and must move the ramps' reference time with it).  Against the reference: states to
    1e-8, impact counts exact."""
    wall, sigma, r, Gamma, F0, dF, w0, dw, y0 = case
    _start(fmu, wall, solver, sigma, r, Gamma, F0, w0, y0, **UNDERDAMPED)
    ref = InputsReference(sigma=sigma, r=r, Gamma=Gamma, wall=wall, **UNDERDAMPED)
    st = RefState(0.0, *y0)
    got, want = _drive(fmu, ref, st, STEPS[steps], F0, dF, w0, dw)
    assert want[-1, 2] >= 2
    assert np.max(np.abs(got[:, :2] - want[:, :2])) < 1e-8, np.abs(got - want).max(axis=0)
    np.testing.assert_array_equal(got[:, 2], want[:, 2])
    assert fmu.get("t_impact") == pytest.approx(st.t_impact, abs=1e-9)
    assert fmu.get("v_impact") == pytest.approx(st.v_impact, rel=1e-7)
    assert abs(st.v_impact) > 0.1  # no impact near the sticking threshold: the count is exact


@SOLVERS
@pytest.mark.parametrize("wall", ["compliant", "rigid"])
def test_inputs_hold_their_end_of_step_values(fmu, wall, solver):
    """One step with ramps, then steps with nothing set: the inputs hold the ramp's end values
    (FMI 2.0: a derivative acts within its step); snapping back to the start values is wrong."""
    sigma, r, Gamma, F0, dF, w0, dw, y0 = 0.1, 0.8, 1000.0, 1.0, 2.0, 0.2, -0.1, (-0.5, 1.0)
    _start(fmu, wall, solver, sigma, r, Gamma, F0, w0, y0, **UNDERDAMPED)
    ref = InputsReference(sigma=sigma, r=r, Gamma=Gamma, wall=wall, **UNDERDAMPED)
    st = RefState(0.0, *y0)
    fmu.slave.setRealInputDerivatives([fmu.vr["F_ext"], fmu.vr["u_wall"]], [1, 1], [dF, dw])
    fmu.step_to(1.3)
    ref.run(st, Piece(0.0, 1.3, F0, dF, w0, dw))
    F1, w1 = F0 + 1.3 * dF, w0 + 1.3 * dw
    assert fmu.get("F_ext") == pytest.approx(F1, rel=1e-14)
    assert fmu.get("u_wall") == pytest.approx(w1, rel=1e-14)
    for t in (2.0, 3.1, 4.5):
        fmu.step_to(t)
        ref.run(st, Piece(st.t, t, F1, 0.0, w1, 0.0))
        assert np.max(np.abs(fmu.state() - [st.u, st.v])) < 1e-8, t
        assert fmu.impacts() == st.impacts
        assert (fmu.get("F_ext"), fmu.get("u_wall")) == pytest.approx((F1, w1), rel=1e-14)
    assert st.impacts >= 2


@SOLVERS
@pytest.mark.parametrize("dw", [0.05, -0.05, 0.0])
def test_sticking_on_a_moving_rigid_wall_and_release_with_its_velocity(fmu, dw, solver):
    """r = 0 on a rigid wall moving at constant velocity: each impact sticks (the rebound is 0
    relative to the wall: no chatter, so counts are exact), the mass rides the wall while the net
    force pushes it in, and leaves with the wall's velocity.  A release at rest (v = 0) is off by
    ~|dw| right after the release."""
    lin = UNDERDAMPED
    F_g, _ = forcing_amplitude_phase(**lin)
    sigma, w0, y0 = 10.0, 0.02, (-0.03, 0.0)
    _start(fmu, "rigid", solver, sigma, 0.0, 10.0, 0.0, w0, y0, **lin)
    ref = InputsReference(sigma=sigma, r=0.0, wall="rigid", **lin)
    st = RefState(0.0, *y0)
    got, want = _drive(fmu, ref, st, [0.0125] * 240, 0.0, 0.0, w0, dw)
    kinds = [k for _, k in st.log]
    assert kinds.count("stick") >= 2 and kinds.count("release") >= 2  # rides and leaves, twice
    assert np.max(np.abs(got[:, :2] - want[:, :2])) < 1e-7, np.abs(got - want).max(axis=0)
    np.testing.assert_array_equal(got[:, 2], want[:, 2])


@pytest.mark.parametrize("phase", np.linspace(0.0, 1.0, 8, endpoint=False).round(3))
@pytest.mark.parametrize("depth", [1e-10, -1e-10], ids=["stays-in", "grazes-out"])
@SOLVERS
def test_grazing_exit_from_inside_the_compliant_wall(fmu, phase, depth, solver):
    """The mirror of the 1e-10-deep entry: a mass inside the compliant wall turns back in at
    u - w = depth (1e-10 inside: no event; 1e-10 outside: an exit and an entry, one impact),
    at 8 phases of the forcing.  The start is the inside flow run backwards from that turning
    point over 0.9 of a half inside oscillation (from near the deepest point; the spring's force
    over the ~1e-5 long outside dip is below rounding), the end 0.4 of one after it.  The wall
    event's root direction inside the wall (u - w falling) is what finds the dip."""
    from scipy.integrate import solve_ivp
    lin, sigma, r, Gamma = UNDERDAMPED, 0.1, 0.9, 1000.0
    F_g, _ = forcing_amplitude_phase(**lin)
    Om2 = lin["Omega"] ** 2
    w = -1.0 - 2.0 * (1.0 + sigma) * F_g / Om2 - 0.1  # the net force pushes in at every phase
    half = math.pi / math.sqrt(Om2 * (1.0 + Gamma))  # half an oscillation inside the wall
    t_star = 2.0 + float(phase)
    ref = InputsReference(sigma=sigma, r=r, Gamma=Gamma, wall="compliant", **lin)
    piece = Piece(0.0, 10.0, 0.0, 0.0, w, 0.0)
    t0 = t_star - 0.9 * half
    back = solve_ivp(lambda t, y: [y[1], ref.accel(t, y[0], y[1], piece, True)], (t_star, t0),
                     [w + depth, 0.0], method="DOP853", rtol=1e-13, atol=1e-16)
    y0 = back.y[:, -1]
    assert y0[0] > w + 1e-6  # well inside at the start
    fmu.start(t0=t0, wall=WALLS["compliant"], solver=solver, sigma=sigma, r=r, Gamma=Gamma,
              u_wall=w, u0=y0[0], v0=y0[1], **lin)
    fmu.step_to(t_star + 0.4 * half)
    assert fmu.impacts() == (1 if depth < 0 else 0)
    assert fmu.in_contact()


def _ref_end(sigma: float, dw: float, y0, T: float) -> np.ndarray:
    ref = InputsReference(sigma=sigma, r=0.0, wall="rigid", **UNDERDAMPED)
    st = ref.run(RefState(0.0, *y0), Piece(0.0, T, 0.0, 0.0, 0.02, dw))
    return np.array([st.u, st.v])


@SOLVERS
@pytest.mark.parametrize("dw", [0.05, 0.0])
@pytest.mark.parametrize("T", [0.1, 0.5], ids=["still-stuck", "released"])
def test_sensitivities_over_a_period_that_sticks(fmu, T, dw, solver):
    """sensitivities = true, r = 0 on a rigid wall (moving at dw or still): the mass sticks at
    t ~ 0.03.  Every nearby start sticks too, so J = d(u, v)(T)/d(u0, v0) is exactly 0, still
    stuck or released after; S = d(u, v)(T)/d sigma against central differences of the
    independent reference (the forcing's sigma-derivative does not act while the wall holds the
    mass; the release time moves with sigma, but the state leaves the wall with zero
    acceleration, so the release adds nothing to first order)."""
    sigma, y0 = 10.0, (-0.03, 0.0)
    fmu.start(wall=WALLS["rigid"], solver=solver, sigma=sigma, r=0.0, u_wall=0.02, u0=y0[0], v0=y0[1],
              sensitivities=True, **UNDERDAMPED)
    fmu.slave.setRealInputDerivatives([fmu.vr["u_wall"]], [1], [dw])
    fmu.step_to(T)
    assert [fmu.get(k) for k in ("J_uu", "J_uv", "J_vu", "J_vv")] == [0.0] * 4
    assert fmu.impacts() == 1 and fmu.in_contact() == (T == 0.1)
    h = 1e-5
    want = (_ref_end(sigma + h, dw, y0, T) - _ref_end(sigma - h, dw, y0, T)) / (2 * h)
    got = np.array([fmu.get("S_u"), fmu.get("S_v")])
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-7)


@SOLVERS
def test_a_wall_jumping_onto_a_mass_it_outruns_is_no_impact(fmu, solver):
    """A rigid wall moving away at 0.5 jumps 0.01 past a mass that follows at 0.3: relative to
    the wall the mass moves away (-0.2), so it is placed on the wall without an impact and keeps
    its velocity (the documented rule of model_input_jump, decided on the relative velocity; the
    absolute one, +0.3, would invent an impact, and a rebound into the wall)."""
    fmu.start(wall=WALLS["rigid"], solver=solver, sigma=0.0, r=0.8, u0=-0.5, v0=0.3, u_wall=0.5, nu=0.0,
              Omega=1e-3, F_ext=50.0)  # F_ext beats the forcing (-4 pi^2 at t = 0): pushed towards the wall
    u, v = fmu.state()
    fmu.slave.setRealInputDerivatives([fmu.vr["u_wall"]], [1], [0.5])
    fmu.set(u_wall=u - 0.01)
    fmu.step_to(1e-9)
    assert fmu.impacts() == 0
    assert fmu.state()[0] <= u - 0.01 + 1e-9 * 0.5 and fmu.state()[1] == pytest.approx(v, abs=1e-6)


@SOLVERS
@pytest.mark.parametrize("dw2", [-0.05, 0.0, 0.15])
@pytest.mark.parametrize("jump", [0.002, 0.02])
def test_a_wall_jumping_away_from_a_sticking_mass_leaves_it_with_its_velocity(fmu, jump, dw2,
                                                                               solver):
    """A rigid wall moving at dw1 = 0.05 carries a sticking mass (r = 0); between two steps it
    jumps away by ``jump`` and moves on at dw2.  Only the constraint went away, no impulse acted:
    the mass flies on with its velocity, the wall's before the jump (dw1), until the net force
    brings it back to the wall (an impact, r = 0: it sticks again or leaves with the wall).  The
    reference applies exactly that (velocity continuity) and then its own flight and jump laws;
    at rest or at the wall's new velocity dw2 is off by |dw1 - dw2| or dw1 in
    velocity at once."""
    lin, sigma, w0, y0, dw1, h = UNDERDAMPED, 10.0, 0.02, (-0.03, 0.0), 0.05, 0.0125
    _start(fmu, "rigid", solver, sigma, 0.0, 10.0, 0.0, w0, y0, **lin)
    ref = InputsReference(sigma=sigma, r=0.0, wall="rigid", **lin)
    st = RefState(0.0, *y0)
    t = 0.0

    def step(w: float, dw: float) -> None:
        nonlocal t
        fmu.set(u_wall=w)
        fmu.slave.setRealInputDerivatives([fmu.vr["u_wall"]], [1], [dw])
        fmu.step_to(t + h)
        ref.run(st, Piece(t, t + h, 0.0, 0.0, w, dw))
        t += h
        assert np.max(np.abs(fmu.state() - [st.u, st.v])) < 1e-7, (t, fmu.state(), st)
        assert fmu.impacts() == st.impacts, t
        # a small jump is closed again within the step: the return's time and speed tell
        assert fmu.get("t_impact") == pytest.approx(st.t_impact, abs=1e-8)
        assert fmu.get("v_impact") == pytest.approx(st.v_impact, rel=1e-6, abs=1e-9)

    while st.mode != "stick":  # ride the wall moving at dw1 until the mass sticks on it
        step(w0 + dw1 * t, dw1)
        assert t < 0.5, "meant to stick"
    step(w0 + dw1 * t, dw1)  # one step stuck: the mass moves at dw1 with the wall
    assert fmu.in_contact() and st.mode == "stick" and fmu.state()[1] == pytest.approx(dw1)
    t_jump, w_jump = t, w0 + dw1 * t + jump
    st.mode = "free"  # the wall is gone from under the mass: u and v = dw1 are kept
    for _ in range(24):
        step(w_jump + dw2 * (t - t_jump), dw2)
    assert [k for _, k in st.log].count("impact") >= 2  # it came back to the wall


@SOLVERS
@pytest.mark.parametrize("margin", [1e-6, 0.05, 0.5])
@pytest.mark.parametrize("dw", [0.05, 0.0])
def test_a_sigma_change_that_ends_the_holding_force_releases_at_once(fmu, margin, dw, solver):
    """A mass sticking on the rigid wall (r = 0, the wall still or moving at dw); between two
    steps the master lowers sigma (tunable) so that the net force at that instant pulls away,
    by ``margin`` of the drive (1e-6: the holding force has only just vanished).  No wall event
    is crossed: the restart itself must release the mass (with the wall's velocity), or it would
    stay stuck with a negative holding force until the force next rises and falls.  Against the
    reference, released at the switch."""
    lin, sigma, w0, y0, h = UNDERDAMPED, 10.0, 0.02, (-0.03, 0.0), 0.0125
    F_g, phi = forcing_amplitude_phase(**lin)
    Om2 = lin["Omega"] ** 2
    _start(fmu, "rigid", solver, sigma, 0.0, 10.0, 0.0, w0, y0, **lin)
    ref = InputsReference(sigma=sigma, r=0.0, wall="rigid", **lin)
    st = RefState(0.0, *y0)
    t, stuck = 0.0, 0
    while stuck < 3:  # three steps on the wall
        w = w0 + dw * t
        fmu.set(u_wall=w)
        fmu.slave.setRealInputDerivatives([fmu.vr["u_wall"]], [1], [dw])
        fmu.step_to(t + h)
        ref.run(st, Piece(t, t + h, 0.0, 0.0, w, dw))
        t += h
        stuck += st.mode == "stick"
        assert t < 0.5, "meant to stick"
    assert fmu.in_contact() and fmu.get("F_contact") > 0.0
    w = w0 + dw * t
    # the drive that makes the net force on the wall -margin (1 + sigma) F_g cos(...) at t
    c = math.cos(2 * math.pi * t + phi)
    assert c > 0.1
    new_sigma = (Om2 * (w + 1.0) + lin["nu"] * dw) / (F_g * c) * (1.0 - margin) - 1.0
    fmu.set(sigma=new_sigma)
    t_switch = t
    ref = InputsReference(sigma=new_sigma, r=0.0, wall="rigid", **lin)
    assert ref.push(t, Piece(t, t + h, 0.0, 0.0, w, dw)) < 0.0
    fmu.slave.setDebugLogging(True, ["logEvents"])
    for k in range(8):
        w = w0 + dw * t
        fmu.set(u_wall=w)
        fmu.slave.setRealInputDerivatives([fmu.vr["u_wall"]], [1], [dw])
        fmu.messages.clear()
        fmu.step_to(t + h)
        ref.run(st, Piece(t, t + h, 0.0, 0.0, w, dw))
        t += h
        assert np.max(np.abs(fmu.state() - [st.u, st.v])) < 1e-7, (t, fmu.state(), st)
        assert fmu.impacts() == st.impacts
        if k == 0 and solver == 0 and dw == 0.0:
            # Nothing but sigma changed (with dw != 0 the new slope is an input change, and the
            # input-jump rule releases the mass).  The release is the restart's, not a crossing
            # stepped over: were it left to the side check (solver_cvode.c, mutant M27), the
            # rescue would release the mass 4e-16 later, the same state, but the log would call
            # it a rescued crossing.
            found = [EVENTS_LOG.search(m) for _, _, m in fmu.messages]
            assert [(int(f.group(1)), int(f.group(2))) for f in found if f][:1] == [(1, 0)]
    assert (t_switch, "release") in st.log  # the reference released at the switch


@SOLVERS
@pytest.mark.parametrize("w0,dw", [(0.1, -0.15), (0.1, 0.1), (-0.1, -0.25), (-0.1, 0.05), (-0.1, 0.2)])
def test_sensitivities_over_a_release_from_a_moving_wall(fmu, w0, dw, solver):
    """sensitivities = true, r = 0, one doStep to T = 0.5 that contains the impact, sticking, the
    release from a wall moving at dw and the flight after it.  Leaving a moving wall with zero
    relative velocity, the integrator puts the mass an ulp beyond the wall while the separation
    -|a| t^2 / 2 is below its error: the FMU places it back (model_event_update), no impact, no
    jump in J or S (mutant M50 takes it for a rigid impact).  The CVODE runs here do that (the
    log's events exceed impacts plus releases); J = 0 (every nearby start sticks) and S against
    central differences of the independent reference (agreement measured: 6e-10 at most; M50
    changes S by ~1e-10 only, as the placement comes within the integrator's error window right
    after the release, where S is still ~0: TESTING.md)."""
    sigma, y0, T = 10.0, (w0 - 0.05, 0.0), 0.5
    fmu.start(wall=WALLS["rigid"], solver=solver, sigma=sigma, r=0.0, u_wall=w0, u0=y0[0],
              v0=y0[1], sensitivities=True, **UNDERDAMPED)
    fmu.slave.setDebugLogging(True, ["logEvents"])
    fmu.slave.setRealInputDerivatives([fmu.vr["u_wall"]], [1], [dw])
    fmu.messages.clear()
    fmu.step_to(T)

    def end(sg: float) -> RefState:
        ref = InputsReference(sigma=sg, r=0.0, wall="rigid", **UNDERDAMPED)
        return ref.run(RefState(0.0, *y0), Piece(0.0, T, 0.0, 0.0, w0, dw))
    st = end(sigma)
    kinds = [k for _, k in st.log]
    assert "release" in kinds and fmu.impacts() == st.impacts
    assert np.max(np.abs(fmu.state() - [st.u, st.v])) < 1e-7
    if solver == 0:
        found = [EVENTS_LOG.search(m) for _, _, m in fmu.messages]
        events = sum(int(f.group(1)) for f in found if f)
        assert events > st.impacts + kinds.count("release")  # a placement was made
    assert [fmu.get(k) for k in ("J_uu", "J_uv", "J_vu", "J_vv")] == [0.0] * 4
    h = 1e-5
    hi, lo = end(sigma + h), end(sigma - h)
    want = (np.array([hi.u, hi.v]) - [lo.u, lo.v]) / (2 * h)
    got = np.array([fmu.get("S_u"), fmu.get("S_v")])
    np.testing.assert_allclose(got, want, rtol=1e-8, atol=1e-9)
