"""Windows of maximal period-M orbits: (64) and the 2D maps, against brute-force iteration."""
from __future__ import annotations

import math

import numpy as np
import pytest

from mapcheck import coefficients, window_1d
from mapcheck.bifurcation import PiecewiseMap, classify, orbit_diagram
from mapcheck.maps import damped_1d_map
from mapcheck.windows import MapParams, maximal_orbits, windows

FIG9 = (4.605170185988091, 0.3059238689620112)


def brute_force_sets(f, grid, param_to_rho, M_max=5, n_transient=4000, starts=np.linspace(-0.3, 0.3, 16)):
    """For each M: grid values where fresh starts or up/down continuation settle on a
    maximal period-M orbit (period M, exactly one impact per period)."""
    rho = param_to_rho(grid)
    fresh = orbit_diagram(f, rho, starts, 0.0, n_transient=n_transient, n_keep=40)
    up = orbit_diagram(f, rho, -0.1, 0.0, n_transient=1500, n_keep=40, mode="up")
    down = orbit_diagram(f, rho, -0.1, 0.0, n_transient=1500, n_keep=40, mode="down")
    found = {}
    for M in range(1, M_max + 1):
        hit = np.zeros(grid.size, dtype=bool)
        for d in (fresh, up, down):
            per, imp = d.classify(12, 1e-9)
            hit |= np.any((per == M) & (imp == 1), axis=1)
        found[M] = grid[hit]
    return found


def test_window_1d_closed_form():
    assert window_1d(1) == (0.25, math.inf)
    assert window_1d(2) == (1 / 8, 1 / 4)
    assert window_1d(3) == (1 / 12, 1 / 9)
    lo, hi = window_1d(4)
    assert lo == hi == 1 / 16  # degenerate: M_max = 3
    lo, hi = window_1d(5)
    assert lo > hi  # empty


def test_orbit_solver_reproduces_64_for_the_1d_map():
    """The 2D orbit solver on (54)/(55) gives (64) with flip (lower) and grazing (upper) edges."""
    p = MapParams.damped_1d()
    grid = np.linspace(0.02, 0.6, 2901)
    for M in (1, 2, 3):
        (w,) = windows(p, M, grid)
        lo, hi = window_1d(M)
        assert abs(w.lo - lo) < 1e-12
        assert w.kind_lo == "flip"
        if M == 1:
            assert w.kind_hi == "range"
        else:
            assert abs(w.hi - hi) < 1e-12 and w.kind_hi == "graze"
    assert windows(p, 4, grid) == [] and windows(p, 5, grid) == []
    # the orbit itself: sqrt(x_M) = M rho (docs/theory.md section 6)
    orb = maximal_orbits(p, 3, np.array([0.1]))
    k = int(np.argmax(orb.stable))
    assert math.isclose(orb.s[k, 0], 0.3, rel_tol=1e-12)


def test_64_against_iteration_of_the_1d_map():
    """Iterate (54)/(55) from 16 starts on a rho grid: maximal period-M orbits are found
    exactly inside the windows (64), up to a margin for slow convergence at the edges."""
    rho = np.arange(0.03, 0.40, 0.001)

    def f(x, y, r):
        return damped_1d_map(x, r), y

    d = orbit_diagram(f, rho, np.linspace(-0.5, 0.5, 16), 0.0, n_transient=3000, n_keep=40)
    per, imp = classify(d.x, 12, 1e-10)
    margin = 0.004
    for M in range(1, 6):
        hit = np.any((per == M) & (imp == 1), axis=1)
        lo, hi = window_1d(M)
        inside = (rho > lo + margin) & (rho < hi - margin)
        outside = (rho < lo - margin) | (rho > hi + margin)
        assert np.all(hit[inside]), M
        assert not np.any(hit[outside]), M
    assert np.any(np.any((per == 3) & (imp == 1), axis=1))


def _cases():
    cc = coefficients(*FIG9, 0.9, "compliant")
    cr = coefficients(*FIG9, 0.9, "rigid")
    sig = np.arange(0.05, 1.2, 0.0025)
    return [
        ("fig9 compliant (48), sigma", MapParams.from_coefficients(cc), sig, cc.rho),
        ("fig9 compliant (48), A~(sigma)", MapParams.from_coefficients(cc), sig, lambda s: cc.rho(s, "tilde")),
        ("fig9 rigid (39), rho", MapParams.from_coefficients(cr), np.arange(0.02, 0.6, 0.0015), None),
        # at (0.99, 0.01) the Nordmark map's period-3 window has multipliers ~ -0.99 and a
        # tiny basin: use parameters where sweeps converge within the test's budget
        ("Nordmark (1)/(2), rho", MapParams.nordmark(0.8, 0.2, 0.5), np.arange(0.07, 1.2, 0.0025), None),
    ]


@pytest.mark.parametrize("name, p, grid, rho_of", _cases(), ids=[c[0] for c in _cases()])
def test_2d_window_edges_against_brute_force_sweeps(name, p, grid, rho_of):
    """Edges from the orbits (bisection) agree with fresh-start and up/down sweeps of the map
    to within a few grid steps; lower edges are flips, upper edges grazing (extra impact)."""
    to_rho = rho_of or (lambda q: q)
    step = grid[1] - grid[0]
    found = brute_force_sets(PiecewiseMap(p), grid, to_rho)
    n_windows = 0
    for M in range(1, 6):
        ws = windows(p, M, grid, rho_of)
        wide = [w for w in ws if w.hi - w.lo > 4 * step]
        if not wide:
            # no (resolvable) window: the sweeps must not find a wide stable maximal orbit either
            assert found[M].size <= 2, (M, found[M])
            continue
        (w,) = wide
        n_windows += 1
        assert w.kind_lo == "flip"
        assert abs(found[M].min() - w.lo) < 3 * step, (M, found[M].min(), w.lo)
        if w.kind_hi != "range":
            assert w.kind_hi == "graze"
            assert abs(found[M].max() - w.hi) < 3 * step, (M, found[M].max(), w.hi)
    assert n_windows >= 3  # period 1, 2, 3 at least


def test_narrow_period4_window_of_the_2d_map():
    """(64) gives M = 4 only as a point; the 2D map (48) at figure 9 has a narrow window.
    A fine local brute-force scan confirms its edges."""
    c = coefficients(*FIG9, 0.9, "compliant")
    p = MapParams.from_coefficients(c)
    (w,) = windows(p, 4, np.linspace(0.05, 0.3, 2001), c.rho)
    assert 0.0005 < w.hi - w.lo < 0.01
    grid = np.linspace(w.lo - 0.0008, w.hi + 0.0008, 61)
    step = grid[1] - grid[0]
    # multipliers are ~ -0.99 across this window: long transients are needed
    d = orbit_diagram(PiecewiseMap(p), c.rho(grid), np.linspace(-0.3, 0.3, 12), 0.0, n_transient=40000, n_keep=40)
    per, imp = d.classify(12, 1e-9)
    hit = grid[np.any((per == 4) & (imp == 1), axis=1)]
    assert hit.size > 10
    assert abs(hit.min() - w.lo) < 3 * step and abs(hit.max() - w.hi) < 3 * step


def test_tilde_variant_moves_windows_up():
    """At figure 9, |A~(sigma)| = (1+sigma)4pi^2 - sigma Omega^2 lowers rho at given sigma, so
    every window sits at larger sigma: e.g. the period-1 lower edge rho = 1/4 moves from
    sigma = 0.445 (linear rho) to about 0.80 (the paper's 'sigma 0.15-0.8')."""
    c = coefficients(*FIG9, 0.9, "compliant")
    assert math.isclose(float(c.sigma_of_rho(0.25)), 0.25 / c.rho_per_sigma, rel_tol=1e-14)
    s_t = float(c.sigma_of_rho(0.25, "tilde"))
    assert 0.79 < s_t < 0.81
    assert math.isclose(float(c.rho(s_t, "tilde")), 0.25, rel_tol=1e-12)
