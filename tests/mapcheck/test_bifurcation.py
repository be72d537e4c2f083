"""Vectorized iteration and bifurcation sweeps (fresh, up, down)."""
from __future__ import annotations

import numpy as np

from mapcheck import coefficients, physical_map
from mapcheck.bifurcation import PiecewiseMap, classify, iterate, orbit_diagram
from mapcheck.maps import natural_map
from mapcheck.windows import MapParams, windows

FIG9 = (4.605170185988091, 0.3059238689620112)


def test_inplace_kernel_equals_plain_map():
    c = coefficients(*FIG9, 0.9, "compliant")
    p = MapParams.from_coefficients(c)
    rng = np.random.default_rng(0)
    x0, y0 = rng.uniform(-0.3, 0.3, 500), rng.uniform(-0.01, 0.01, 500)
    rho = rng.uniform(0.05, 0.5, 500)
    for n in (1, 2, 5, 40):
        x, y = iterate(PiecewiseMap(p), x0, y0, rho, n)
        xr, yr = x0.copy(), y0.copy()
        for _ in range(n):
            xr, yr = natural_map(xr, yr, rho, c)
        np.testing.assert_array_equal(x, xr)
        np.testing.assert_array_equal(y, yr)
        xs, ys, _, _ = PiecewiseMap(p).scalar_orbit(float(x0[7]), float(y0[7]), float(rho[7]), n, 0)
        assert abs(xs - xr[7]) < 1e-15 and abs(ys - yr[7]) < 1e-15


def test_classify():
    k = np.arange(60)
    period3 = np.tile([-0.2, -0.1, 0.05], 20)
    fixed = np.full(60, 0.3)
    chaotic = np.sin(1.7 * k ** 1.3)
    per, imp = classify(np.stack([period3, fixed, chaotic]), max_period=12, tol=1e-12)
    assert list(per) == [3, 1, 0]
    assert list(imp) == [1, 1, 0]


def test_up_and_down_sweeps_show_hysteresis():
    """With A~(sigma) at figure 9 the stable period-2 and period-1 windows overlap (orbit
    solver); an up sweep stays on period 2 there, a down sweep on period 1."""
    c = coefficients(*FIG9, 0.9, "compliant")
    p = MapParams.from_coefficients(c)
    rho_t = lambda s: c.rho(s, "tilde")  # noqa: E731
    grid = np.linspace(0.7, 0.9, 401)
    (w1,) = windows(p, 1, grid, rho_t)
    (w2,) = windows(p, 2, grid, rho_t)
    assert w1.lo < w2.hi  # overlap: bistability
    f = PiecewiseMap(p)
    up = orbit_diagram(f, rho_t(grid), -0.1, 0.0, n_transient=1500, n_keep=40, mode="up")
    down = orbit_diagram(f, rho_t(grid), 0.1, 0.0, n_transient=1500, n_keep=40, mode="down")
    # multipliers are close to -1 across the overlap (slow convergence), so classify by the
    # fraction of impacting iterates: 1/2 on the period-2 orbit, 1 on the period-1 orbit
    frac_up = np.mean(up.x[:, 0, :] >= 0, axis=-1)
    frac_down = np.mean(down.x[:, 0, :] >= 0, axis=-1)
    both = (grid > w1.lo + 0.001) & (grid < w2.hi - 0.001)
    assert both.sum() >= 5
    assert np.all(frac_up[both] == 0.5) and np.all(frac_down[both] == 1.0)
    # outside the overlap both sweeps agree
    above = grid > w2.hi + 0.002
    below = grid < w1.lo - 0.002
    assert np.all(frac_up[above] == 1.0) and np.all(frac_down[above] == 1.0)
    assert np.all(frac_up[below] == 0.5) and np.all(frac_down[below] == 0.5)


def test_vectorized_continuation_equals_scalar_path():
    c = coefficients(*FIG9, 0.9, "compliant")
    f = PiecewiseMap(MapParams.from_coefficients(c))
    rho = c.rho(np.linspace(0.1, 0.6, 21))
    one = orbit_diagram(f, rho, -0.1, 0.0, n_transient=200, n_keep=30, mode="down")
    two = orbit_diagram(f, rho, [-0.1, -0.1], 0.0, n_transient=200, n_keep=30, mode="down")
    np.testing.assert_allclose(two.x[:, 0], one.x[:, 0], rtol=0, atol=1e-14)
    np.testing.assert_allclose(two.x[:, 1], one.x[:, 0], rtol=0, atol=1e-14)


def test_any_map_can_be_swept_generic_path():
    """orbit_diagram accepts any vectorized f(x, y, p): here the physical map (31)/(32);
    fresh and continuation results equal plain iteration."""
    c = coefficients(*FIG9, 0.9, "compliant")

    def f(u, v, s):
        return physical_map(u, v, s, c)

    sig = np.array([1e-3, 2e-3, 5e-3])
    d = orbit_diagram(f, sig, -1e-4, 0.0, n_transient=50, n_keep=25)
    up = orbit_diagram(f, sig, -1e-4, 0.0, n_transient=50, n_keep=25, mode="up")
    u, v = np.full(3, -1e-4), np.zeros(3)
    rec = []
    for _ in range(75):
        u, v = physical_map(u, v, sig, c)
        rec.append(u.copy())
    rec = np.array(rec)[50:].T
    np.testing.assert_array_equal(d.x[:, 0, :], rec)
    np.testing.assert_array_equal(up.x[0, 0, :], rec[0])
    assert np.any(rec >= 0) or np.any(rec < 0)
