"""Newton periodic-orbit solver and window edges by continuation, for maps without closed forms."""
from __future__ import annotations

import numpy as np

from mapcheck import coefficients
from mapcheck.exact import ExactOscillator
from mapcheck.maps import chi, from_natural, natural_map, physical_map
from mapcheck.orbits import map_step, solve_periodic_orbit, window_edge
from mapcheck.windows import MapParams, maximal_orbits, windows

FIG9 = (4.605170185988091, 0.3059238689620112)


def _natural_step_of(c):
    def step_of(s):
        rho = float(c.rho(s))

        def st(x, y):
            xn, yn = natural_map(x, y, rho, c)
            return float(xn), float(yn), int(x >= 0)
        return st
    return step_of


def test_newton_orbit_equals_closed_form_orbit():
    c = coefficients(*FIG9, 0.9, "compliant")
    p = MapParams.from_coefficients(c)
    for M, s in [(1, 0.6), (2, 0.3), (3, 0.17)]:
        o = maximal_orbits(p, M, c.rho(np.array([s])))
        k = int(np.argmax(o.stable[:, 0]))
        exact_z = np.array([o.x[k, :, 0], o.y[k, :, 0]]).T
        orb = solve_periodic_orbit(_natural_step_of(c)(s), exact_z[0] * 1.05, M)
        assert orb.converged and orb.maximal and orb.stable
        np.testing.assert_allclose(orb.z, exact_z, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(np.sort(np.abs(orb.multipliers)), np.sort(np.abs(o.multipliers[k, :, 0])),
                                   rtol=1e-5, atol=1e-8)


def test_window_edges_by_continuation_equal_closed_form_edges():
    c = coefficients(*FIG9, 0.9, "compliant")
    p = MapParams.from_coefficients(c)
    M, s = 3, 0.17
    (w,) = windows(p, M, np.linspace(0.0, 1.0, 2001), c.rho)
    o = maximal_orbits(p, M, c.rho(np.array([s])))
    k = int(np.argmax(o.stable[:, 0]))
    z0 = [o.x[k, 0, 0], o.y[k, 0, 0]]
    lo, kind_lo, _ = window_edge(_natural_step_of(c), M, s, z0, -1, 0.01, 0.0, xtol=1e-9)
    hi, kind_hi, _ = window_edge(_natural_step_of(c), M, s, z0, +1, 0.01, 1.0, xtol=1e-9)
    assert abs(lo - w.lo) < 1e-8 and kind_lo == "flip"
    assert abs(hi - w.hi) < 1e-8 and kind_hi == "graze"


def test_physical_map_orbit_is_a_periodic_orbit_of_31():
    """The solver works on the physical map (31)/(32) (no closed-form orbit); its natural-map
    counterpart is a good initial guess."""
    c = coefficients(*FIG9, 0.9, "compliant")
    p = MapParams.from_coefficients(c)
    s = 0.6  # inside the period-1 window of the natural map
    o = maximal_orbits(p, 1, c.rho(np.array([s])))
    k = int(np.argmax(o.stable[:, 0]))
    u0, v0 = from_natural(o.x[k, 0, 0], o.y[k, 0, 0], s, c)
    step = map_step(physical_map, s, c, contact=lambda u, v: chi(u, v) >= 0)
    orb = solve_periodic_orbit(step, [float(u0), float(v0)], 1, scale=np.array([1e-2, 1e-1]))
    assert orb.converged and orb.maximal
    u1, v1 = physical_map(orb.z[0, 0], orb.z[0, 1], s, c)
    assert abs(u1 - orb.z[0, 0]) < 1e-13 and abs(v1 - orb.z[0, 1]) < 1e-12


def test_exact_map_period2_orbit_is_periodic_in_the_ode():
    """A period-2 orbit of the exact pre-impact map (Newton) is a period-2 solution of the ODE:
    strobing the closed form at t = 0, 1, 2 returns to the start, with one wall entry."""
    nu, Om = FIG9
    s = 0.5
    osc = ExactOscillator(nu, Om, s, r=0.9, Gamma=10.0, wall="compliant")

    def st(u, v):
        u1, v1, k = osc.pre_impact_map(u, v)
        return float(u1), float(v1), int(k)

    c = coefficients(nu, Om, 0.9, "compliant")
    o = maximal_orbits(MapParams.from_coefficients(c), 2, c.rho(np.array([s]), "tilde"))
    k = int(np.argmax(o.stable[:, 0]))
    u0, v0 = from_natural(o.x[k, 0, 0], o.y[k, 0, 0], s, c, "tilde")
    orb = solve_periodic_orbit(st, [float(u0), float(v0)], 2, tol=1e-11, scale=np.array([1e-2, 1e-1]))
    assert orb.converged and orb.maximal and orb.stable
    # no contact near the time of z_j, so z_j is a real (not only virtual) state: strobe the
    # ODE from it at t = 0; at t = 2 the orbit is back (the contact near t = 1 is over by 3/2)
    j = int(np.argmin(orb.contacts))
    z = orb.z[j]
    states, counts = osc.strobe(float(z[0]), float(z[1]), [1.0, 2.0], t0=0.0)
    np.testing.assert_allclose(states[1], z, rtol=0, atol=1e-10)
    assert counts[1] == 1


def test_ode_period1_window_edge_needs_the_tilde_variant():
    """Figure 9, compliant wall Gamma = 10: the flip edge of the period-1 window of the exact
    ODE map (Newton + bisection on the closed-form map) agrees with the 2D map using A~(sigma)
    to < 0.5 %, while the paper's linear rho(sigma) puts it at sigma ~ 0.45 instead of ~ 0.81."""
    nu, Om = FIG9
    c = coefficients(nu, Om, 0.9, "compliant")
    p = MapParams.from_coefficients(c)
    grid = np.linspace(0.0, 1.5, 3001)
    (w_t,) = windows(p, 1, grid, lambda s: c.rho(s, "tilde"))
    (w_p,) = windows(p, 1, grid, c.rho)

    def step_of(s):
        osc = ExactOscillator(nu, Om, s, r=0.9, Gamma=10.0, wall="compliant")

        def st(u, v):
            u1, v1, k = osc.pre_impact_map(u, v)
            return float(u1), float(v1), int(k)
        return st

    s0 = 0.86
    o = maximal_orbits(p, 1, c.rho(np.array([s0]), "tilde"))
    k = int(np.argmax(o.stable[:, 0]))
    u0, v0 = from_natural(o.x[k, 0, 0], o.y[k, 0, 0], s0, c, "tilde")
    lo, kind, _ = window_edge(step_of, 1, s0, [float(u0), float(v0)], -1.0, 0.02, 0.0, xtol=2e-4,
                              tol=1e-11, scale=np.array([1e-2, 1e-1]))
    assert kind == "flip"
    assert abs(lo - w_t.lo) < 0.005 * w_t.lo, (lo, w_t.lo)
    assert lo - w_p.lo > 0.3
