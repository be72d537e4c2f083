"""The closed-form oracle mapcheck.exact against an independent ODE solver and known solutions."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mapcheck.exact import ExactOscillator, forcing_amplitude_phase

FIG9 = (4.605170185988091, 0.3059238689620112)  # (alpha, gamma) = (0.99, 0.01), overdamped
UNDER = (0.196, 7.368)  # figures 6, 7: underdamped


def reference(osc: ExactOscillator, u0: float, v0: float, times, t0: float):
    """solve_ivp(DOP853) with terminal events at u = 0 and the same wall laws.

    Independent of mapcheck: integrates the ODE (53) numerically; only the
    forcing phase and amplitude (5) are shared.
    """
    nu, Om2, k2 = osc.nu, osc.Omega ** 2, osc.kappa ** 2
    F = (1.0 + osc.sigma) * osc.F_g

    def rhs(t, y, inside):
        a = F * math.cos(2 * math.pi * t + osc.phi) - nu * y[1] - Om2 * (y[0] + 1.0)
        return [y[1], a - (k2 * y[0] if inside else 0.0)]

    t, y, inside, count = t0, np.array([u0, v0], float), u0 > 0, 0
    out, counts = [], []
    for T in times:
        while t < T:
            if osc.wall == "none":
                events = None
            else:
                def ev(tt, yy, _inside):
                    return yy[0]
                ev.terminal = True
                ev.direction = -1 if inside else 1
                events = ev
            sol = solve_ivp(rhs, (t, T), y, method="DOP853", rtol=1e-12, atol=1e-14,
                            max_step=0.005, events=events, args=(inside,))
            if events is not None and sol.status == 1:
                t, y = sol.t_events[0][0], sol.y_events[0][0].copy()
                y[0] = 0.0
                if osc.wall == "compliant":
                    if not inside:
                        y[1] *= osc.r
                        count += 1
                    inside = not inside
                else:
                    y[1] *= -osc.r
                    count += 1
            else:
                t, y = T, sol.y[:, -1]
        out.append(y.copy())
        counts.append(count)
    return np.array(out), np.array(counts)


CASES = [
    # (nu, Omega), Gamma, sigma, wall, minimum number of wall contacts in the run
    (FIG9, 10.0, 0.2, "compliant", 5),
    (FIG9, 10.0, 0.2, "rigid", 1),  # one hard impact, then the slow mode (rate 0.02) recovers
    (FIG9, 10.0, 0.2, "none", 0),
    (UNDER, 1000.0, 0.3, "compliant", 5),
    (UNDER, 1000.0, 0.3, "rigid", 5),
    (UNDER, 10.0, 0.05, "compliant", 5),
]


@pytest.mark.parametrize("par, Gamma, sigma, wall, min_contacts", CASES)
def test_against_dop853(par, Gamma, sigma, wall, min_contacts):
    nu, Om = par
    osc = ExactOscillator(nu, Om, sigma, r=0.9, Gamma=Gamma, wall=wall)
    # start on the wall-free orbit half a period before grazing (impacts from the first period on)
    t0 = -0.5
    u0, v0 = osc.wall_free_orbit(t0)
    u0, v0 = float(u0) - 0.01, float(v0)  # plus a transient
    times = t0 + np.linspace(0.3, 12.0, 40)
    states, counts = osc.strobe(u0, v0, times, t0=t0)
    ref, ref_counts = reference(osc, u0, v0, times, t0)
    np.testing.assert_array_equal(counts, ref_counts)
    assert np.max(np.abs(states - ref)) < 1e-9
    assert counts[-1] >= min_contacts  # the comparison did exercise the wall


def test_wall_free_orbit_solves_ode():
    """p(t) of (4) with F_g, phi of (5) solves (3) without a wall (no wall contact for sigma < 0)."""
    nu, Om = UNDER
    osc = ExactOscillator(nu, Om, -0.1, wall="rigid")
    u0, v0 = osc.wall_free_orbit(0.0)
    times = np.linspace(0.1, 7.3, 13)
    states, counts = osc.strobe(float(u0), float(v0), times)
    p, dp = osc.wall_free_orbit(times)
    assert counts[-1] == 0
    assert np.max(np.abs(states[:, 0] - p)) < 1e-13
    assert np.max(np.abs(states[:, 1] - dp)) < 1e-12
    F_g, phi = forcing_amplitude_phase(nu, Om)
    assert math.isclose(math.cos(phi), (Om ** 2 - 4 * math.pi ** 2) / F_g, rel_tol=1e-14)


@pytest.mark.parametrize("wall", ["compliant", "rigid"])
@pytest.mark.parametrize("par", [FIG9, UNDER])
def test_grazing_contact_1e9_deep_is_found(par, wall):
    """On p(t) with sigma = 1e-9 the orbit enters the wall 1e-9 deep at t ~ 0 (footnote 3).

    Before the first contact the orbit is exactly p(t), so the entry time is
    t = -arccos(1/(1+sigma))/(2 pi) in closed form.
    """
    sigma = 1e-9
    osc = ExactOscillator(*par, sigma, r=0.9, Gamma=10.0, wall=wall)
    u0, v0 = osc.wall_free_orbit(-0.5)
    ev = osc.crossings(float(u0), float(v0), -0.5, 0.4)
    t_enter = -math.acos(1.0 / (1.0 + sigma)) / (2 * math.pi)
    first = ev[0]
    assert first[1] in ("enter", "impact")
    assert abs(first[0] - t_enter) < 1e-11
    # and sigma = -1e-9 never touches
    osc_miss = ExactOscillator(*par, -sigma, r=0.9, Gamma=10.0, wall=wall)
    u0, v0 = osc_miss.wall_free_orbit(-0.5)
    assert osc_miss.crossings(float(u0), float(v0), -0.5, 0.4) == []


def test_rigid_chatter_ends_in_sticking_and_release():
    """Chatter: impact intervals shrink by r (2 r v / |a| per flight); sticking, then release
    where F(t) - Omega^2 changes sign, followed by free motion from (0, 0)."""
    nu, Om = FIG9
    r = 0.5
    osc = ExactOscillator(nu, Om, 0.0, r=r, wall="rigid")
    t0 = -osc.phi / (2 * math.pi)  # force maximum: pushes into the wall
    ev = osc.crossings(-1e-4, 0.0, t0, t0 + 2.0)
    kinds = [k for _, k in ev]
    assert kinds.count("stick") == 1 and kinds.count("release") == 1
    t_imp = np.array([t for t, k in ev if k == "impact"])
    dt = np.diff(t_imp)
    ratios = dt[5:-2] / dt[4:-3]
    assert np.all(np.abs(ratios - r) < 2e-3)
    t_stick = [t for t, k in ev if k == "stick"][0]
    t_rel = [t for t, k in ev if k == "release"][0]
    assert abs(osc.net_wall_force(t_rel)) < 1e-10
    assert osc.net_wall_force(t_stick) > 0
    tt = np.linspace(t_stick + 1e-6, t_rel - 1e-6, 5)
    st, _ = osc.strobe(-1e-4, 0.0, tt, t0=t0)
    assert np.all(st == 0.0)
    # after release: free motion from (0, 0), compared with the "none" oscillator
    free = ExactOscillator(nu, Om, 0.0, wall="none")
    later = t_rel + np.array([0.1, 0.3])
    a, _ = osc.strobe(-1e-4, 0.0, later, t0=t0)
    b, _ = free.strobe(0.0, 0.0, later, t0=t_rel)
    assert np.max(np.abs(a - b)) < 1e-12


def test_stepwise_strobing_equals_one_call():
    """Re-anchoring at requested times must not change the solution."""
    osc = ExactOscillator(*UNDER, 0.3, r=0.9, Gamma=1000.0, wall="compliant")
    times = np.linspace(0.05, 4.0, 80)
    all_at_once, c1 = osc.strobe(-0.5, 1.0, times)
    last, c2 = osc.strobe(-0.5, 1.0, times[-1:])
    assert np.max(np.abs(all_at_once[-1] - last[0])) < 1e-11
    assert c1[-1] == c2[-1]


FIG9_NU_OMEGA = dict(nu=FIG9[0], Omega=FIG9[1])


@pytest.mark.parametrize("wall,r,sigma,lin,Gamma,u0", [
    ("compliant", 0.9, 0.5, FIG9_NU_OMEGA, 10.0, -2.5),
    ("rigid", 0.9, 0.5, FIG9_NU_OMEGA, 10.0, -2.5),
    ("none", 0.9, 0.5, FIG9_NU_OMEGA, 10.0, -2.5),
    ("rigid", 0.5, 10.0, dict(nu=0.196, Omega=7.368), 10.0, -0.03),  # chatter and sticking
    ("compliant", 0.0, 0.2, FIG9_NU_OMEGA, 10.0, -1.0),  # r = 0: contacts of zero duration
])
def test_dense_evaluation_equals_strobe(wall, r, sigma, lin, Gamma, u0):
    """ExactOscillator.dense (one crossing search, vectorised stretches) against strobe (one
    search per requested time), including times 1e-9 either side of wall events."""
    osc = ExactOscillator(lin["nu"], lin["Omega"], sigma, r=r, Gamma=Gamma, wall=wall)
    times = np.sort(np.random.default_rng(3).uniform(0.5, 8.5, 200))
    events = [t for t, _ in osc.crossings(u0, 0.0, 0.5, 8.5)]
    times = np.union1d(times, [t + d for t in events[:5] for d in (-1e-9, 1e-9)])
    a, ca = osc.strobe(u0, 0.0, times, t0=0.5)
    b, cb = osc.dense(u0, 0.0, times, t0=0.5)
    assert np.max(np.abs(a - b)) < 1e-11
    np.testing.assert_array_equal(ca, cb)
