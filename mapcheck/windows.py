"""Stability windows of maximal period-M orbits (section 7).

* :func:`window_1d` -- the closed form (64) for the strongly damped 1D map (54)/(55).
* :func:`maximal_orbits` -- the maximal period-M orbits of the square-root map (37)/(38)
  (and of (1)/(2), (54)/(55), which have the same form), solved in closed form, with
  their multipliers and admissibility.
* :func:`windows` -- the sigma- (or rho-) edges of every stable maximal period-M window,
  found by bisection on "an admissible, stable maximal period-M orbit exists"; each edge
  is labelled with the condition that fails beyond it.

A maximal period-M orbit (figure 8) has M - 1 non-impacting steps (x < 0) followed by
one impacting step (x >= 0): x_1 < ... < x_{M-1} < 0 <= x_M, x_{M+1} = x_1 (57).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = [
    "window_1d",
    "MapParams",
    "MaximalOrbits",
    "maximal_orbits",
    "stable_maximal_exists",
    "Window",
    "windows",
]


def window_1d(M: int) -> tuple[float, float]:
    """Stability window (64) of the maximal period-M orbit of the 1D map (54)/(55).

    rho in [1/(4M), 1/M^2]: the lower edge (63) is the loss of stability
    (multiplier -1), the upper edge (60) the extra impact at t = M - 1 (grazing).
    For M = 1 there is no non-impacting passage, so no upper edge: rho_hi = inf.
    The window is empty for M >= 5 (rho_lo > rho_hi) and a single point for M = 4.

    Returns
    -------
    (rho_lo, rho_hi) : tuple of float

    Examples
    --------
    >>> window_1d(3)
    (0.08333333333333333, 0.1111111111111111)
    >>> window_1d(1)
    (0.25, inf)
    """
    if M < 1:
        raise ValueError("M must be >= 1")
    lo = 1.0 / (4.0 * M)
    hi = np.inf if M == 1 else 1.0 / M ** 2
    return lo, hi


@dataclass(frozen=True)
class MapParams:
    """Coefficients of the square-root map (37)/(38)::

        x < 0:   x' = alpha x + y + rho,               y' = -gamma x
        x >= 0:  x' = -c1 sqrt(x) + c2 x + y + rho,    y' = c3 x
    """

    alpha: float
    gamma: float
    c1: float
    c2: float
    c3: float

    @classmethod
    def from_coefficients(cls, c) -> "MapParams":
        """From a :class:`mapcheck.coeffs.Coefficients` ((39) or (48))."""
        return cls(c.alpha, c.gamma, c.c1, c.c2, c.c3)

    @classmethod
    def nordmark(cls, alpha: float, gamma: float, r: float) -> "MapParams":
        """The Nordmark map (1)/(2)."""
        return cls(alpha, gamma, 1.0, 0.0, -r * r * gamma)

    @classmethod
    def damped_1d(cls) -> "MapParams":
        """The 1D map (54)/(55) (y stays 0)."""
        return cls(1.0, 0.0, 1.0, 1.0, 0.0)


@dataclass
class MaximalOrbits:
    """Maximal period-M orbits for an array of rho; ``n_roots`` candidates per rho.

    Attributes (arrays of shape ``(n_roots,) + rho.shape``; NaN where a root is not real)
    ----------
    s : ndarray, shape (n_roots,) + rho.shape
        sqrt(x_M) (a root of the quadratic; must be >= 0).
    x, y : ndarray, shape (n_roots, M) + rho.shape
        Orbit points z_1 .. z_M.
    multipliers : ndarray (complex), shape (n_roots, 2) + rho.shape
        Eigenvalues of the Jacobian of the M-fold map at z_1.
    admissible : ndarray of bool
        x_1..x_{M-1} < 0 <= x_M (57) and sqrt(x_M) >= 0 (a real orbit of the map).
    stable : ndarray of bool
        admissible and both multipliers inside the unit circle.
    """

    M: int
    rho: np.ndarray
    s: np.ndarray
    x: np.ndarray
    y: np.ndarray
    multipliers: np.ndarray
    admissible: np.ndarray
    stable: np.ndarray


def _linear_powers(p: MapParams, M: int) -> tuple[np.ndarray, np.ndarray]:
    """Lambda^k and beta_k = sum_{j<k} Lambda^j e1 for k = 0..M-1 (non-impacting steps)."""
    Lam = np.array([[p.alpha, 1.0], [-p.gamma, 0.0]])
    pows = [np.eye(2)]
    betas = [np.zeros(2)]
    for _ in range(M - 1):
        betas.append(betas[-1] + pows[-1] @ np.array([1.0, 0.0]))
        pows.append(Lam @ pows[-1])
    return np.array(pows), np.array(betas)


def maximal_orbits(p: MapParams, M: int, rho) -> MaximalOrbits:
    """Solve for the maximal period-M orbits in closed form (vectorized over rho).

    With L = Lambda^{M-1} (the M - 1 non-impacting steps, Lambda = [[alpha, 1], [-gamma, 0]]),
    z_M = L z_1 + rho beta, and s = sqrt(x_M) >= 0, the impact step gives
    y_1 = c3 s^2 and x_1 = [-c1 s + (c2 + L22 c3) s^2 + rho (1 + beta_2)] / (1 - L21); then
    x_M = s^2 is the quadratic a2 s^2 + a1 s + a0 = 0 with
    a2 = D - L11 (c2 + L22 c3) - L12 c3 D, a1 = L11 c1, a0 = -rho (L11 (1 + beta_2) + beta_1 D),
    D = 1 - L21.  (For the 1D map a2 = 0 and s = M rho, as in (58)-(63).)

    The Jacobian of the M-fold map at z_1 is DI(z_M) L with
    DI = [[c2 - c1/(2 s), 1], [c3, 0]].
    """
    rho = np.asarray(rho, dtype=float)
    pows, betas = _linear_powers(p, M)
    L = pows[M - 1]
    b1, b2 = betas[M - 1]
    D = 1.0 - L[1, 0]
    a2 = D - L[0, 0] * (p.c2 + L[1, 1] * p.c3) - L[0, 1] * p.c3 * D
    a1 = L[0, 0] * p.c1
    a0 = -rho * (L[0, 0] * (1.0 + b2) + b1 * D)
    if abs(a2) < 1e-14 * max(1.0, abs(a1)):
        s_roots = np.stack([-a0 / a1, np.full(rho.shape, np.nan)])
    else:
        disc = a1 * a1 - 4.0 * a2 * a0
        sq = np.sqrt(np.where(disc >= 0, disc, np.nan))
        # numerically stable pair of roots
        qq = -0.5 * (a1 + np.copysign(1.0, a1) * sq)
        with np.errstate(divide="ignore", invalid="ignore"):
            s_roots = np.stack([qq / a2, np.where(qq != 0, a0 / qq, np.nan)])
    s = s_roots  # shape (2,) + rho.shape
    x1 = (-p.c1 * s + (p.c2 + L[1, 1] * p.c3) * s * s + rho * (1.0 + b2)) / D
    y1 = p.c3 * s * s
    xs = np.stack([pows[k, 0, 0] * x1 + pows[k, 0, 1] * y1 + rho * betas[k, 0] for k in range(M)], axis=1)
    ys = np.stack([pows[k, 1, 0] * x1 + pows[k, 1, 1] * y1 + rho * betas[k, 1] for k in range(M)], axis=1)
    # x_M is s^2 by construction; use it exactly so that the edge x_M = 0 is sharp
    xs[:, M - 1] = s * s
    with np.errstate(invalid="ignore", divide="ignore"):
        j11 = p.c2 - p.c1 / (2.0 * s)
        J11 = j11 * L[0, 0] + L[1, 0]
        J12 = j11 * L[0, 1] + L[1, 1]
        J21 = p.c3 * L[0, 0]
        J22 = p.c3 * L[0, 1]
        tr = J11 + J22
        det = J11 * J22 - J12 * J21
        rt = np.sqrt((tr * tr - 4.0 * det).astype(complex))
        mult = np.stack([(tr + rt) / 2.0, (tr - rt) / 2.0], axis=1)
        ok = np.isfinite(s) & (s >= 0.0)
        if M > 1:
            ok &= np.all(xs[:, : M - 1] < 0.0, axis=1)
        stable = ok & np.all(np.abs(mult) < 1.0, axis=1)
    return MaximalOrbits(M, rho, s, xs, ys, mult, ok, stable)


def stable_maximal_exists(p: MapParams, M: int, rho) -> np.ndarray:
    """True where an admissible, stable maximal period-M orbit exists."""
    return np.any(maximal_orbits(p, M, rho).stable, axis=0)


@dataclass(frozen=True)
class Window:
    """A stable window [lo, hi] in the sweep parameter, with the cause at each edge.

    ``kind_lo``/``kind_hi`` is one of "flip" (a multiplier crosses -1), "fold"/"saddle"
    (+1), "torus" (complex pair), "graze" (an extra impact: some x_k, k < M, reaches 0),
    "no-impact" (x_M reaches 0), "none" (orbit ceases to exist: complex roots), or
    "range" (the edge of the scanned range).
    """

    M: int
    lo: float
    hi: float
    kind_lo: str
    kind_hi: str


def _edge_kind(p: MapParams, M: int, rho_out: float, rho_in: float) -> str:
    """Why the stable orbit is lost just beyond an edge (rho_out outside, rho_in inside)."""
    inside = maximal_orbits(p, M, np.array(rho_in))
    k = int(np.argmax(inside.stable))
    out = maximal_orbits(p, M, np.array(rho_out))
    if not np.isfinite(out.s[k]):
        return "none"
    if out.s[k] < 0:
        return "no-impact"
    if M > 1 and np.any(out.x[k, : M - 1] >= 0):
        return "graze"
    m = out.multipliers[k]
    big = m[np.abs(m) >= 1.0]
    if big.size == 0:
        return "switch"  # a different root takes over (not expected generically)
    mu = big[np.argmax(np.abs(big))]
    if abs(mu.imag) > 1e-9:
        return "torus"
    return "flip" if mu.real < 0 else "fold"


def windows(p: MapParams, M: int, param_grid,
            rho_of_param: Callable[[np.ndarray], np.ndarray] | None = None,
            xtol: float = 1e-13) -> list[Window]:
    """Edges of every stable maximal period-M window over a parameter range.

    The indicator "an admissible stable maximal period-M orbit exists" is evaluated on
    ``param_grid`` (vectorized), and every change of it is bisected to ``xtol``.  Edges
    are thus located from the periodic orbits themselves (loss of stability, grazing /
    extra impact, loss of the impact), not from iterating the map.

    Parameters
    ----------
    p : MapParams
        Map coefficients (independent of the sweep parameter for (37)/(38)).
    M : int
    param_grid : array_like
        Sorted grid in the sweep parameter (sigma or rho); windows narrower than its
        spacing can be missed.
    rho_of_param : callable, optional
        rho as a function of the parameter, e.g. ``c.rho`` or
        ``lambda s: c.rho(s, "tilde")``; identity (the parameter is rho) if omitted.
    xtol : float
        Absolute bisection tolerance in the parameter.

    Returns
    -------
    list of Window
    """
    f = rho_of_param or (lambda q: np.asarray(q, dtype=float))
    grid = np.asarray(param_grid, dtype=float)
    ind = stable_maximal_exists(p, M, f(grid))

    def indicator(q: float) -> bool:
        return bool(stable_maximal_exists(p, M, f(np.array([q])))[0])

    def bisect(a: float, b: float) -> tuple[float, float]:
        fa = indicator(a)
        while abs(b - a) > xtol * max(1.0, abs(a)):
            m = 0.5 * (a + b)
            if m in (a, b):
                break
            if indicator(m) == fa:
                a = m
            else:
                b = m
        return a, b  # a has the indicator of the original a

    out: list[Window] = []
    changes = np.nonzero(ind[1:] != ind[:-1])[0]
    lo, kind_lo = (grid[0], "range") if ind[0] else (None, None)
    for i in changes:
        a, b = bisect(grid[i], grid[i + 1])
        if not ind[i]:  # entering a window at increasing parameter
            lo = b
            kind_lo = _edge_kind(p, M, float(f(np.array(a))), float(f(np.array(b))))
        else:
            kind_hi = _edge_kind(p, M, float(f(np.array(b))), float(f(np.array(a))))
            out.append(Window(M, float(lo), float(a), kind_lo, kind_hi))
            lo = None
    if lo is not None:
        out.append(Window(M, float(lo), float(grid[-1]), kind_lo, "range"))
    return out
