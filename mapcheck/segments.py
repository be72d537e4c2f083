"""The closed form of one linear regime of the impact oscillator, and its first wall crossing.

One regime (free, or in a compliant wall with stiffness kappa^2) is the linear ODE

    u'' + nu u' + k2 u + Omega^2 = (1 + sigma) F_g cos(2 pi t + phi),   k2 = Omega^2 [+ kappa^2],

solved exactly as its particular solution plus the homogeneous propagator (docs/theory.md
section 2).  :class:`Segment` anchors it at a state (t_a, u_a, v_a) and writes displacements from
the anchor as ``(P(tau) - I)(z_a - q(t_a)) + (q(t) - q(t_a))``, both brackets accurate to small
relative error for small tau, so that chattering impacts 1e-8 apart are resolved.

:func:`first_crossing` finds a wall crossing as in the paper's footnote 3: the closed form is
sampled on a grid finer than every time scale, each interval is split at the zeros of the
acceleration and then of the velocity (``brentq``), so that u is monotone between consecutive
points; a sign change of u between such points is then bracketed and solved by ``brentq``.  A
contact only 1e-9 deep is therefore never missed.  :class:`mapcheck.exact.ExactOscillator`
strings segments together across the wall events.

The grids are short (<= 49 points), so numpy's cost per call, not per point, sets the speed: a
chunk's grid and what the state needs of tau alone (the entries of P - I, sin(pi tau)) are kept per
mode, the closed form is evaluated once per chunk on arrays, and the refinement points are inserted
with their states computed point by point in pure Python (the same floating-point operations, so the
same numbers as evaluating the whole union again: tests/mapcheck/test_exact_fast_paths.py).
"""
from __future__ import annotations

import bisect
import math

import numpy as np

from .linear import (_SERIES_D, _SERIES_RATE_T, propagator_minus_identity_entries, propagator_minus_identity_scalar,
                     series_point, series_terms, spectral_rate)


def brentq(f, a: float, b: float, **options):
    """scipy's ``brentq``, imported on first use: ``scipy.optimize`` takes a second or more to
    import, and most processes that import this package (every pool worker, through
    ``mapcheck.compare``) never locate a root."""
    from scipy.optimize import brentq as root

    return root(f, a, b, **options)


TWO_PI = 2.0 * math.pi
_GRID_POINTS_PER_CHUNK = 48
_RTOL = 4.0 * np.finfo(float).eps
_GRID_CACHE = 256  # chunk grids kept per mode (~3 kB each)


def forcing_amplitude_phase(nu: float, Omega: float) -> tuple[float, float]:
    """F_g and phi of equation (5): the grazing forcing amplitude and its phase."""
    re = Omega * Omega - 4.0 * math.pi ** 2
    im = TWO_PI * nu
    return math.hypot(re, im), math.atan2(im, re)


class Mode:
    """Constants of one linear regime (free or in-wall) of the ODE."""

    def __init__(self, nu: float, Omega: float, sigma: float, k2: float):
        self.nu, self.k2, self.Om2 = nu, k2, Omega * Omega
        self.amp = 1.0 + sigma
        z0 = complex(self.Om2 - 4.0 * math.pi ** 2, TWO_PI * nu)  # F_g e^{i phi}
        z1 = complex(k2 - 4.0 * math.pi ** 2, TWO_PI * nu)
        g = 1.0 + 0.0j if k2 == self.Om2 else z0 / z1
        # particular solution q = amp (gr cos th - gi sin th) + c0
        self.gr, self.gi = g.real, g.imag
        self.c0 = -self.Om2 / k2
        self.fr, self.fi = z0.real, z0.imag  # external force amp (fr cos th - fi sin th)
        rate = max(2.0 * math.pi, math.sqrt(k2), nu)
        self.h = 0.1 / rate  # grid step: well below every time scale of the solution
        self.rate = spectral_rate(nu, k2)
        self.amp_2pi = self.amp * TWO_PI
        # constants of the scalar closed form (mapcheck.linear._scalar_damped_c_and_s)
        self.b = 0.5 * nu
        self.d = self.b * self.b - k2
        self.sq = math.sqrt(abs(self.d))
        self._grids: dict = {}

    def factors(self, t: np.ndarray) -> tuple[np.ndarray, ...]:
        """What the state at the times ``t`` (1-D) needs of t alone: the entries of P(t) - I,
        pi t and sin(pi t)."""
        half = math.pi * t
        return (*propagator_minus_identity_entries(t, self.nu, self.k2, self.rate), half, np.sin(half))

    def grid(self, tau_s: float, tau_e: float, n: int) -> tuple[np.ndarray, tuple]:
        """linspace(tau_s, tau_e, n + 1) and its :meth:`factors`, kept for full chunks of the
        crossing search (the same chunks recur in every segment of this mode); read-only."""
        key = (tau_s, tau_e, n)
        hit = self._grids.get(key)
        if hit is None:
            tau = np.linspace(tau_s, tau_e, n + 1)
            hit = (tau, self.factors(tau))
            for a in (tau, *hit[1]):
                a.flags.writeable = False
            if len(self._grids) < _GRID_CACHE:
                self._grids[key] = hit
        return hit

    def minus_identity(self, t: float) -> tuple[float, float, float, float]:
        """The entries of P(t) - I at one time, in pure Python (for root finding): the series
        where rate |t| <= 0.05, summed until the next term is below 1e-18 of the sum, else
        the closed form (as :func:`mapcheck.linear.propagator_minus_identity`)."""
        nu, k2 = self.nu, self.k2
        if self.rate * abs(t) <= _SERIES_RATE_T:  # the series, written once in mapcheck.linear
            return propagator_minus_identity_scalar(t, nu, k2, self.rate)
        b, d = self.b, self.d
        z = d * t * t
        E = math.exp(-b * t)
        if abs(z) <= _SERIES_D:
            c = 1.0 + z * (1.0 / 2 + z * (1.0 / 24 + z / 720))
            eC, eS = E * c, E * (1.0 + z * (1.0 / 6 + z * (1.0 / 120 + z / 5040))) * t
        elif d > 0:
            q = self.sq
            if abs(q * t) > 30.0:
                ep, em = math.exp((q - b) * t), math.exp(-(q + b) * t)
                eC, eS = 0.5 * (ep + em), 0.5 * (ep - em) / q
            else:
                eC, eS = E * math.cosh(q * t), E * math.sinh(q * t) / q
        else:
            w = self.sq
            eC, eS = E * math.cos(w * t), E * math.sin(w * t) / w
        bS = b * eS
        return eC + bS - 1.0, eS, -k2 * eS, eC - bS - 1.0

    def q(self, th: float) -> tuple[float, float]:
        c, s = math.cos(th), math.sin(th)
        return (self.amp * (self.gr * c - self.gi * s) + self.c0,
                self.amp * TWO_PI * (-self.gr * s - self.gi * c))

    def force(self, th) -> np.ndarray:
        """External force (1 + sigma) F_g cos(th + phi)."""
        return self.amp * (self.fr * np.cos(th) - self.fi * np.sin(th))


class Segment:
    """Closed-form solution of one mode, anchored at (t_a, u_a, v_a)."""

    def __init__(self, mode: Mode, t_a: float, u_a: float, v_a: float):
        self.m, self.t_a, self.u_a, self.v_a = mode, t_a, u_a, v_a
        # forcing phase from the fractional part of t: cos(2 pi t) is ill-conditioned at large t
        self.th_a = TWO_PI * (t_a - math.floor(t_a))
        qu, qv = mode.q(self.th_a)
        self.wu, self.wv = u_a - qu, v_a - qv

    def delta(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(u(t_a + tau) - u_a, v(t_a + tau) - v_a), accurate for small tau."""
        tau = np.asarray(tau, dtype=float)
        du, dv = self.delta_from(self.m.factors(tau.reshape(-1)))
        return du.reshape(tau.shape), dv.reshape(tau.shape)

    def delta_from(self, factors: tuple) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`delta` from the :meth:`Mode.factors` of the times."""
        m = self.m
        e11, e12, e21, e22, half, s_half = factors  # half = delta/2 with delta = 2 pi tau
        mid = self.th_a + half
        dcos = -2.0 * s_half * np.sin(mid)
        dsin = 2.0 * s_half * np.cos(mid)
        dqu = m.amp * (m.gr * dcos - m.gi * dsin)
        dqv = m.amp_2pi * (-m.gr * dsin - m.gi * dcos)
        du = e11 * self.wu + e12 * self.wv + dqu
        dv = e21 * self.wu + e22 * self.wv + dqv
        return du, dv

    def state(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        du, dv = self.delta(tau)
        return self.u_a + du, self.v_a + dv

    def point_state(self, tau: float, x_series: float | None = None) -> tuple[float, float]:
        """:meth:`state` at one time, in pure Python with the same operations (in the series
        range of P - I too, unlike :meth:`scalar_state`).  ``x_series``: rate * the largest |tau|
        in the series range of the times this one is evaluated with (default: this one)."""
        m = self.m
        x = m.rate * abs(tau)
        if x <= _SERIES_RATE_T:
            A, B = series_point(tau, m.nu, m.k2, series_terms(x if x_series is None else x_series))
            return self._compose(tau, B, A, -m.k2 * A, B - m.nu * A)
        return self._compose(tau, *m.minus_identity(tau))

    def accel(self, tau, u, v) -> np.ndarray:
        m = self.m
        return m.force(self.th_a + TWO_PI * tau) - m.nu * v - m.k2 * u - m.Om2

    # scalar helpers for brentq (pure Python: called ~10 times per root)
    def scalar_state(self, tau: float) -> tuple[float, float]:
        return self._compose(tau, *self.m.minus_identity(tau))

    def _compose(self, tau: float, e11: float, e12: float, e21: float, e22: float) -> tuple[float, float]:
        """The state at tau from the entries of P(tau) - I (the arithmetic of :meth:`delta_from`)."""
        m = self.m
        half = math.pi * tau
        s_half = math.sin(half)
        mid = self.th_a + half
        dcos = -2.0 * s_half * math.sin(mid)
        dsin = 2.0 * s_half * math.cos(mid)
        du = e11 * self.wu + e12 * self.wv + m.amp * (m.gr * dcos - m.gi * dsin)
        dv = e21 * self.wu + e22 * self.wv + m.amp_2pi * (-m.gr * dsin - m.gi * dcos)
        return self.u_a + du, self.v_a + dv

    def u_at(self, tau: float) -> float:
        return self.scalar_state(tau)[0]

    def v_at(self, tau: float) -> float:
        return self.scalar_state(tau)[1]

    def a_at(self, tau: float) -> float:
        u, v = self.scalar_state(tau)
        m = self.m
        th = self.th_a + TWO_PI * tau
        return m.amp * (m.fr * math.cos(th) - m.fi * math.sin(th)) - m.nu * v - m.k2 * u - m.Om2


def _root(f, lo: float, hi: float) -> float:
    # xtol relative to the bracket: ~1e-16 of its width, plus brentq's 4 eps relative
    return brentq(f, lo, hi, xtol=max(1e-16 * (hi - lo), 1e-300), rtol=_RTOL, maxiter=200)


def refine(tau, vals, f) -> list[float]:
    """Roots of f in every grid interval where ``vals`` changes sign strictly (sequences of floats)."""
    return [_root(f, tau[i], tau[i + 1]) for i in range(len(vals) - 1) if vals[i] * vals[i + 1] < 0]


def _insert(seg: Segment, P: list, U: list, V: list, new: list[float]) -> bool:
    """Insert the roots ``new`` (ascending) with their states into the strictly increasing times
    P and their states U, V, where that gives what :meth:`Segment.state` gives on the union:
    each new point strictly inside an interval of its own and, in the series range of P - I,
    below an old point of that range, or the old points there all at tau = 0 (the series length
    is set by the largest point in the range; at tau = 0 the sums vanish at any length).
    Returns False, leaving the lists alone, where it does not."""
    m = seg.m
    at, prev = [], 0
    for x in new:
        i = bisect.bisect_left(P, x)
        if not (prev < i < len(P) and P[i - 1] < x < P[i]):
            return False
        at.append(i)
        prev = i
    x_series = None
    if m.rate * min(abs(x) for x in new) <= _SERIES_RATE_T:
        x_old = max((m.rate * abs(p) for p in P if m.rate * abs(p) <= _SERIES_RATE_T), default=0.0)
        x_new = max(m.rate * abs(x) for x in new if m.rate * abs(x) <= _SERIES_RATE_T)
        if x_new > x_old > 0.0:
            return False  # the old points' series would get more terms
        x_series = max(x_old, x_new)
    for i, x in zip(reversed(at), reversed(new)):
        u, v = seg.point_state(x, x_series)
        P.insert(i, x)
        U.insert(i, u)
        V.insert(i, v)
    return True


def _with_points(seg: Segment, P: list, U: list, V: list, new: list[float]) -> tuple[list, list, list]:
    """The sorted union of the strictly increasing times P (states U, V) and the roots ``new``,
    and the states on it: inserted (:func:`_insert`) or else computed afresh."""
    if new and not _insert(seg, P, U, V, new):
        pts = np.unique(np.array(P + new))
        u, v = seg.state(pts)
        return pts.tolist(), u.tolist(), v.tolist()
    return P, U, V


def _grid_states(seg: Segment, tau_s: float, tau_e: float, tau_end: float) -> tuple[list, list, list, list]:
    """The chunk's grid (about one point per h), strictly increasing, the states and the
    acceleration there, as lists."""
    n = max(2, int(math.ceil((tau_e - tau_s) / seg.m.h)))
    if tau_e < tau_end:
        tau, factors = seg.m.grid(tau_s, tau_e, n)
    else:
        tau = np.linspace(tau_s, tau_e, n + 1)
        factors = seg.m.factors(tau)
    du, dv = seg.delta_from(factors)
    u, v = seg.u_a + du, seg.v_a + dv
    a = seg.accel(tau, u, v)
    if not (tau[1:] > tau[:-1]).all():  # a chunk narrower than a few ulp: drop the repeats
        tau = np.unique(tau)
        u, v = seg.state(tau)
        a = seg.accel(tau, u, v)
    return tau.tolist(), u.tolist(), v.tolist(), a.tolist()


def first_crossing(seg: Segment, sgn: float, tau_end: float) -> float | None:
    """Smallest tau in [0, tau_end] where sgn*u becomes > 0, or None.

    ``sgn = +1`` looks for entering the wall (u rising through 0), ``-1`` for leaving.
    An anchor on the wall (u = 0 just after an event, or rounding noise across it)
    counts as a crossing at tau = 0 only if its velocity heads across; a release
    from sticking (v = 0) never does.
    """
    h = seg.m.h
    released = seg.u_a == 0.0 and seg.v_a == 0.0
    tau_s = 0.0
    while tau_s < tau_end:
        tau_e = min(tau_end, tau_s + _GRID_POINTS_PER_CHUNK * h)
        pts, u, v, a = _grid_states(seg, tau_s, tau_e, tau_end)
        # split at inflection points, so that v is monotone between points ...
        pts, u, v = _with_points(seg, pts, u, v, refine(pts, a, seg.a_at))
        # ... then at turning points, so that u is monotone between points
        pts, u, v = _with_points(seg, pts, u, v, refine(pts, v, seg.v_at))
        g = [sgn * x for x in u]
        first = tau_s == 0.0
        if first:
            g[0] = min(sgn * seg.u_a, 0.0)
        hits = [i for i in range(len(g) - 1) if g[i] <= 0.0 and g[i + 1] > 0.0]
        if released:
            # after a release from sticking u ~ -|jerk| tau^3/6 is below rounding noise for
            # a while; the net force pulls away for at least half a period (it is
            # F - Omega^2 with Omega^2 > 0), so no real contact occurs within one grid step.
            hits = [i for i in hits if pts[i + 1] > h]
        for i in hits:
            if g[i] == 0.0:
                if first and i == 0:
                    if sgn * seg.v_a > 0.0:
                        return 0.0
                    continue  # on the wall but heading away: rounding noise in g[1]
                return pts[i]
            return _root(lambda x: sgn * seg.u_at(x), pts[i], pts[i + 1])
        tau_s = tau_e
    return None
