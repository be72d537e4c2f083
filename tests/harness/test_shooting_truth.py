"""Window edges of the harness's Newton shooting on the FMU against an independent truth: the same
window found on mapcheck's closed-form flow (``mapcheck.exact.ExactOscillator``, the exact
solution, with ``mapcheck.orbits.window_edge``'s own march, bisection and finite-difference
Newton: no harness code), and the edge kinds checked by the multipliers on each side of each
edge.

Case: a period-4 window, (alpha, gamma) = (0.5, 0.05), r = 0.8,
compliant wall Gamma = 10 (the map's A~ window is the guide the harness starts from).
"""
from __future__ import annotations

import numpy as np
import pytest

from harness.dynamics.maps.shooting import StroboscopicMap, map_guided_windows
from mapcheck.coeffs import coefficients
from mapcheck.exact import ExactOscillator
from mapcheck.linear import invert_alpha_gamma
from mapcheck.orbits import solve_periodic_orbit, window_edge
from tests.support.edges import ExactFlow, continue_orbit

pytestmark = pytest.mark.slow  # Newton shooting on the FMU and on the closed form

GUIDE_M4 = (0.0007036372600123284, 0.004341898116748781)
R, GAMMA, M = 0.8, 10.0, 4
# Newton on the closed form: a stable maximal orbit converges in <= 6 iterations from its
# neighbour's point (quadratically: the map is smooth away from grazing), an unstable one beside a
# flip in as many; past a graze Newton finds nothing, and each such try would run to the default
# 40 iterations (3/4 of this file's time): 12 tell the same.
NEWTON = dict(tol=1e-11, rel_h=1e-6, scale=np.array([1e-2, 1e-1]), max_iter=12)


def _exact_step(nu: float, Omega: float):
    """sigma -> the closed form's one-period map at phase 1/2, in (u, v)."""
    def step_of(sigma: float):
        ex = ExactOscillator(nu, Omega, sigma, r=R, Gamma=GAMMA, wall="compliant")
        return lambda u, v: ex.state_at(u, v, 0.5, 1.5)
    return step_of


@pytest.fixture(scope="module")
def both(model, sim):
    inv = invert_alpha_gamma(0.5, 0.05)
    c = coefficients(inv.nu, inv.Omega, R, "compliant")
    params = {**model.defaults(), "nu": inv.nu, "Omega": inv.Omega, "r": R, "Gamma": GAMMA, "wall": 1}
    harness = map_guided_windows(StroboscopicMap(sim, params, 0.5), c, {M: GUIDE_M4}, (1e-4, 1.0), 1e-5)
    # the exact flow's orbit inside the window: iterate the closed-form map to it, from the
    # harness's own window centre only as a value of sigma (no state taken from the harness)
    step_of = _exact_step(inv.nu, inv.Omega)
    s_in = 0.5 * (harness["windows"][M][0] + harness["windows"][M][1])
    z = np.array([-1.0, 0.0])
    step = step_of(s_in)
    for _ in range(200):
        *z, _n = step(*z)
    orb = solve_periodic_orbit(step, np.array(z), M, **NEWTON)
    assert orb.converged and orb.maximal and orb.stable
    # the closed form's own march and bisection (window_edge, steps of 2e-5, to 1e-7) start 5
    # harness tolerances inside each harness edge, where the orbit is continued to from the centre
    # (continue_orbit asserts it stable and maximal at every step): the harness's edge only says
    # where to start; were it beyond the true edge the continuation fails, were it short of it the
    # march goes on to the true edge and the comparison below fails
    flow = ExactFlow(inv.nu, inv.Omega, R, GAMMA, "compliant")
    truth = []
    for side, (d, lim) in enumerate(((-1.0, 1e-4), (+1.0, 1.0))):
        s_near = harness["windows"][M][side] - d * 5e-5
        near = continue_orbit(flow, M, orb, s_in, s_near)
        truth.append(window_edge(step_of, M, s_near, near.z[0], d, 2e-5, lim, xtol=1e-7, **NEWTON))
    return harness, truth, step_of


def test_edges_match_the_closed_form_shooting(both) -> None:
    """Both edges of the FMU's window lie within the harness's bisection tolerance (1e-5) plus
    the FMU's accuracy effect (1e-7) of the exact flow's edges, and are of the same kind."""
    harness, truth, _ = both
    for edge, kind, (t_edge, t_kind, _orb) in zip(harness["windows"][M], harness["kinds"][M], truth):
        assert t_kind in ("flip", "fold", "graze", "torus", "no-impact")  # a bracketed edge
        assert edge == pytest.approx(t_edge, abs=1e-5 + 1e-7), (edge, t_edge)
        assert kind == t_kind


@pytest.mark.parametrize("side", [0, 1], ids=["lower", "upper"])
def test_edge_kinds_by_the_multipliers_on_each_side(both, side) -> None:
    """A flip edge: inside, the exact orbit is stable with its dominant multiplier near -1;
    just outside, the continued orbit has a multiplier below -1.  A fold: the same through +1.
    A graze: the orbit just outside has an extra contact (it is no longer maximal)."""
    harness, truth, step_of = both
    t_edge, t_kind, orb = truth[side]
    out = -1.0 if side == 0 else 1.0
    gap = 1e-6
    inside = solve_periodic_orbit(step_of(t_edge - out * gap), orb.z[0], M, **NEWTON)
    beyond = solve_periodic_orbit(step_of(t_edge + out * gap), orb.z[0], M, **NEWTON)
    assert inside.converged and inside.stable and inside.maximal
    m_in = inside.multipliers[np.argmax(np.abs(inside.multipliers))]
    if t_kind in ("flip", "fold"):
        sign = -1.0 if t_kind == "flip" else 1.0
        m_out = beyond.multipliers[np.argmax(np.abs(beyond.multipliers))]
        assert abs(m_in.imag) < 1e-9 and abs(m_out.imag) < 1e-9
        assert 0.9 < sign * m_in.real < 1.0 < sign * m_out.real < 1.1
    elif t_kind == "graze":
        assert not beyond.converged or not beyond.maximal
    if side == 0 and t_kind in ("flip", "fold"):
        # the harness's multipliers at its last good sigma of the lower edge say the same
        m_h = np.asarray(harness["multipliers_at_lower_edge"][M])
        m_h = m_h[np.argmax(np.abs(m_h))]
        assert 0.9 < sign * m_h.real < 1.0
