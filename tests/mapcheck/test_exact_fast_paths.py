"""The exact flow's fast paths against the straightforward formulas they stand for.

:mod:`mapcheck.segments` evaluates the closed form in four ways: on a chunk grid from factors kept
per mode, at one point in pure Python (:meth:`Segment.point_state`), at refinement points inserted
into a grid (:func:`mapcheck.segments._with_points`), and the crossing search on Python lists.  Each
is checked here against the plain formula -- P(t) - I as a matrix from :func:`propagator_k2`, the
states of the whole union recomputed, the crossing search written with numpy arrays and np.unique --
over random oscillators: rigid and compliant walls, light and heavy damping, r near 1, sigma below
and above 0, grazing starts, sticking and chatter.  The fast paths do the same floating-point
operations, so the results agree to rounding (bit for bit where numpy's and the C library's
sin/cos/exp agree, as on x86-64 without AVX-512).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import mapcheck.exact as exact_module
from mapcheck.exact import ExactOscillator
from mapcheck.linear import propagator_k2, propagator_minus_identity, spectral_rate
from mapcheck.segments import _GRID_POINTS_PER_CHUNK, Mode, Segment, _root, _with_points, first_crossing

TWO_PI = 2.0 * math.pi


def _random_mode(rng: np.random.Generator) -> tuple[Mode, float]:
    """A free or in-wall mode: light or heavy damping (under- and overdamped), slow or fast."""
    nu = float(10.0 ** rng.uniform(-1.5, 0.8))
    Omega = float(rng.uniform(0.3, 4.0))
    k2 = Omega ** 2 * (1.0 + (float(10.0 ** rng.uniform(1, 4)) if rng.random() < 0.5 else 0.0))
    sigma = float(rng.uniform(-0.5, 1.5))
    return Mode(nu, Omega, sigma, k2), sigma


def _straight_state(seg: Segment, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """u, v at t_a + tau: (P(tau) - I) w + q(t) - q(t_a) with P - I as a matrix (propagator_k2
    minus the identity past the series range) and q(t) - q(t_a) as a plain difference."""
    m = seg.m
    E = propagator_minus_identity(tau, m.nu, m.k2)
    far = spectral_rate(m.nu, m.k2) * np.abs(tau) > 0.05
    E[far] = propagator_k2(tau[far], m.nu, m.k2) - np.eye(2)
    w = np.array([seg.wu, seg.wv])
    q_a = np.array(m.q(seg.th_a))
    q = np.array([m.q(seg.th_a + TWO_PI * t) for t in tau]).reshape(-1, 2)
    z = E @ w + (q - q_a) + np.array([seg.u_a, seg.v_a])
    return z[:, 0], z[:, 1]


def _scale(seg: Segment) -> float:
    return 1.0 + abs(seg.u_a) + abs(seg.v_a) + abs(seg.wu) + abs(seg.wv) + seg.m.amp_2pi


def _numpy_is_libm() -> bool:
    """Whether numpy's sin, cos, exp, cosh, sinh give the C library's results (no SIMD variants):
    then the pure-Python paths must agree with the array paths bit for bit."""
    x = np.random.default_rng(0).uniform(-30.0, 30.0, 2000)
    return all(np.array_equal(getattr(np, f)(x), [getattr(math, f)(t) for t in x.tolist()])
               for f in ("sin", "cos", "exp", "cosh", "sinh"))


#: relative tolerance between a pure-Python path and the array path it stands for
POINT_RTOL = 0.0 if _numpy_is_libm() else 1e-15


@pytest.mark.parametrize("seed", range(40))
def test_grid_and_point_states_are_the_plain_formula(seed: int) -> None:
    rng = np.random.default_rng(seed)
    m, _ = _random_mode(rng)
    seg = Segment(m, float(rng.uniform(0.0, 50.0)), float(rng.uniform(-2.0, 0.5)), float(rng.uniform(-8.0, 8.0)))
    tau, factors = m.grid(0.0, _GRID_POINTS_PER_CHUNK * m.h, _GRID_POINTS_PER_CHUNK)
    du, dv = seg.delta_from(factors)
    u, v = seg.u_a + du, seg.v_a + dv
    us, vs = _straight_state(seg, tau)
    tol = 1e-14 * _scale(seg)
    assert np.max(np.abs(u - us)) <= tol and np.max(np.abs(v - vs)) <= tol
    # the same through Segment.state, and point by point in pure Python (series range included)
    u2, v2 = seg.state(tau)
    assert np.array_equal(u2, u) and np.array_equal(v2, v)
    for t in np.concatenate([tau[:3], tau[-2:], [1e-9, 0.3 * 0.05 / m.rate, 3.0]]):
        up, vp = seg.point_state(float(t))
        ua, va = seg.state(np.array([t]))
        tol = POINT_RTOL * _scale(seg)
        assert abs(up - ua[0]) <= tol and abs(vp - va[0]) <= tol


@pytest.mark.parametrize("seed", range(40))
def test_inserted_points_carry_the_states_of_the_union(seed: int) -> None:
    """Points inserted into a grid with their pure-Python states are what recomputing the whole
    union gives -- inside the series range of P - I (slow modes: several grid points there) too."""
    rng = np.random.default_rng(1000 + seed)
    m, _ = _random_mode(rng)
    seg = Segment(m, float(rng.uniform(0.0, 5.0)), float(rng.uniform(-2.0, 0.5)), float(rng.uniform(-8.0, 8.0)))
    tau = np.linspace(0.0, _GRID_POINTS_PER_CHUNK * m.h, _GRID_POINTS_PER_CHUNK + 1)
    u, v = seg.state(tau)
    cells = np.sort(rng.choice(np.arange(_GRID_POINTS_PER_CHUNK), size=3, replace=False))
    if rng.random() < 0.5:  # into the series range where it has more than one grid point
        cells[0] = 0
    new = [float(tau[i] + rng.uniform(0.05, 0.95) * (tau[i + 1] - tau[i])) for i in cells]
    pts, um, vm = _with_points(seg, tau.tolist(), u.tolist(), v.tolist(), new)
    union = np.unique(np.concatenate([tau, new]))
    assert np.array_equal(np.array(pts), union)
    us, vs = seg.state(union)
    tol = POINT_RTOL * _scale(seg)
    assert np.max(np.abs(np.array(um) - us)) <= tol and np.max(np.abs(np.array(vm) - vs)) <= tol


def _plain_refine(tau: np.ndarray, vals: np.ndarray, f) -> list[float]:
    return [_root(f, tau[i], tau[i + 1]) for i in np.nonzero(vals[:-1] * vals[1:] < 0)[0]]


def _plain_first_crossing(seg: Segment, sgn: float, tau_end: float) -> float | None:
    """The crossing search of mapcheck.segments.first_crossing written plainly: numpy arrays,
    np.unique of grid and refinement points, the states of every union recomputed."""
    h = seg.m.h
    released = seg.u_a == 0.0 and seg.v_a == 0.0
    tau_s = 0.0
    while tau_s < tau_end:
        tau_e = min(tau_end, tau_s + _GRID_POINTS_PER_CHUNK * h)
        tau = np.linspace(tau_s, tau_e, max(2, int(math.ceil((tau_e - tau_s) / h))) + 1)
        u, v = seg.state(tau)
        pts = np.unique(np.array(list(tau) + _plain_refine(tau, seg.accel(tau, u, v), seg.a_at)))
        u, v = seg.state(pts)
        pts = np.unique(np.array(list(pts) + _plain_refine(pts, v, seg.v_at)))
        u, v = seg.state(pts)
        g = sgn * u
        first = tau_s == 0.0
        if first:
            g[0] = min(sgn * seg.u_a, 0.0)
        hits = np.nonzero((g[:-1] <= 0.0) & (g[1:] > 0.0))[0]
        if released:
            hits = hits[pts[hits + 1] > h]
        for i in hits:
            if g[i] == 0.0:
                if first and i == 0:
                    if sgn * seg.v_a > 0.0:
                        return 0.0
                    continue
                return float(pts[i])
            return _root(lambda x: sgn * seg.u_at(x), pts[i], pts[i + 1])
        tau_s = tau_e
    return None


def _plain_point_state(seg: Segment, tau: float, x_series: float | None = None) -> tuple[float, float]:
    u, v = seg.state(np.array([tau]))
    return float(u[0]), float(v[0])


def _cases() -> list[tuple[str, ExactOscillator, float, float, float]]:
    """(name, oscillator, u0, v0, t0): random oscillators plus the hard starts."""
    rng = np.random.default_rng(7)
    out = []
    for k in range(24):
        light = k % 2 == 0
        nu = float(10.0 ** rng.uniform(-1.3, -0.3 if light else 0.7))
        Omega = float(rng.uniform(0.4, 4.0))
        r = float(rng.uniform(0.95, 0.995) if k % 3 == 0 else rng.uniform(0.3, 0.95))
        wall = "rigid" if k % 4 < 2 else "compliant"
        sigma = float(rng.uniform(-0.4, 1.0))
        osc = ExactOscillator(nu, Omega, sigma, r=r, Gamma=float(10.0 ** rng.uniform(1, 4)), wall=wall)
        out.append((f"random-{k}-{wall}", osc, float(rng.uniform(-2.5, -0.1)), float(rng.uniform(-6, 6)), 0.3))
    for wall in ("rigid", "compliant"):
        # the wall-free orbit (4) at sigma = 1e-8 reaches 1e-8 into the wall at every integer time
        osc = ExactOscillator(0.2, 2.5, 1e-8, r=0.8, Gamma=100.0, wall=wall)
        out.append((f"grazing-{wall}", osc, -2.0 - 1e-8, 0.0, 0.5))
        # at sigma = 0 it touches the wall: a start just off it
        osc = ExactOscillator(0.2, 2.5, 0.0, r=0.8, Gamma=100.0, wall=wall)
        out.append((f"grazing-nearby-{wall}", osc, -1e-9, 1e-7, 0.0))
    # chatter ending in sticking, and a start stuck on the wall
    out.append(("chatter", ExactOscillator(0.3, 2.0, 0.6, r=0.5, wall="rigid"), -0.2, 1.0, 0.1))
    out.append(("stuck-start", ExactOscillator(0.3, 2.0, 0.6, r=0.5, wall="rigid"), 0.0, 0.0, 0.95))
    out.append(("r-near-1", ExactOscillator(0.05, 1.3, 0.4, r=0.999, wall="rigid"), -1.0, 2.0, 0.0))
    out.append(("fig9-overdamped", ExactOscillator(4.605170185988091, 0.3059238689620112, 0.8, r=0.8,
                                                   Gamma=10.0, wall="compliant"), -0.1, 0.5, -0.5))
    return out


@pytest.mark.parametrize("case", _cases(), ids=lambda c: c[0])
def test_strobe_and_events_match_the_plain_search(case, monkeypatch) -> None:
    _name, osc, u0, v0, t0 = case
    times = t0 + np.arange(1, 13) * 1.0
    fast = osc.strobe(u0, v0, times, t0)
    fast_events = osc.crossings(u0, v0, t0, float(times[-1]))
    monkeypatch.setattr(exact_module, "first_crossing", _plain_first_crossing)
    monkeypatch.setattr(Segment, "point_state", _plain_point_state)
    plain = osc.strobe(u0, v0, times, t0)
    plain_events = osc.crossings(u0, v0, t0, float(times[-1]))
    # bit for bit where numpy is the C library; else rounding, which a graze amplifies (the map
    # has a square-root singularity there)
    rtol, ttol = (0.0, 0.0) if POINT_RTOL == 0.0 else (1e-9, 1e-9) if "grazing" in _name else (1e-13, 1e-14)
    assert np.array_equal(fast[1], plain[1])
    scale = 1.0 + np.abs(plain[0])
    assert np.max(np.abs(fast[0] - plain[0]) / scale) <= rtol
    assert [k for _, k in fast_events] == [k for _, k in plain_events]
    assert np.max(np.abs(np.array([t for t, _ in fast_events] + [0.0])
                         - np.array([t for t, _ in plain_events] + [0.0]))) <= ttol
    if not _name.startswith("random"):  # the hard starts do meet the wall
        assert len(plain_events) > 0


@pytest.mark.parametrize("seed", range(30))
def test_first_crossing_matches_the_plain_search(seed: int) -> None:
    """Segments started anywhere (on the wall too), searched for entering and for leaving."""
    rng = np.random.default_rng(2000 + seed)
    m, _ = _random_mode(rng)
    u_a = 0.0 if seed % 5 == 0 else float(rng.uniform(-1.5, 0.3))
    seg = Segment(m, float(rng.uniform(0.0, 20.0)), u_a, float(rng.uniform(-6.0, 6.0)))
    for sgn in (1.0, -1.0):
        for tau_end in (0.37, 1.0, 2.5):
            fast, plain = first_crossing(seg, sgn, tau_end), _plain_first_crossing(seg, sgn, tau_end)
            assert (fast is None) == (plain is None)
            if fast is not None:
                assert abs(fast - plain) <= (0.0 if POINT_RTOL == 0.0 else 1e-14)


@pytest.mark.parametrize("seed", range(10))
def test_p_minus_i_entries_are_the_matrix_form(seed: int) -> None:
    """propagator_minus_identity_entries (four arrays; the series per point when few points are in
    its range, on arrays when many) against P(t) - I from propagator_k2 past the series range, and
    against the series summed on arrays inside it -- with as many terms (set by the largest point)."""
    from mapcheck.linear import propagator_minus_identity_entries, series_terms

    def plain_series(ts: np.ndarray, n_terms: int) -> tuple[np.ndarray, np.ndarray]:
        A, B, a_k, b_k, fac = np.zeros_like(ts), np.zeros_like(ts), 1.0, 0.0, ts.copy()
        for k in range(1, n_terms + 1):
            A, B = A + a_k * fac, B + b_k * fac
            a_k, b_k = -m.nu * a_k + b_k, -m.k2 * a_k
            fac = fac * ts / (k + 1)
        return A, B

    rng = np.random.default_rng(3000 + seed)
    m, _ = _random_mode(rng)
    rate = spectral_rate(m.nu, m.k2)
    for n_small in (1, 3, 20):
        t = np.concatenate([np.sort(rng.uniform(0.0, 0.05 / rate, n_small)), rng.uniform(0.05 / rate, 3.0, 30)])
        t[0] = 0.0 if seed % 2 else t[0]
        e = np.stack(propagator_minus_identity_entries(t, m.nu, m.k2, rate), axis=-1)
        small = rate * t <= 0.05
        P = propagator_k2(t[~small], m.nu, m.k2) - np.eye(2)
        assert np.array_equal(e[~small], P.reshape(-1, 4))
        A, B = plain_series(t[small], series_terms(rate * float(np.max(t[small]))))
        assert np.array_equal(e[small], np.stack([B, A, -m.k2 * A, B - m.nu * A], axis=-1))
