"""Map bifurcation diagrams: vectorized iteration over a parameter grid.

``orbit_diagram`` iterates any map ``f(x, y, p) -> (x, y)`` (vectorized over arrays)
over a grid of its parameter (sigma or rho):

* ``mode="fresh"``: every grid point starts from the same initial state(s); all grid
  points are iterated at once (one numpy call per iteration for the whole grid).
* ``mode="up"`` / ``"down"``: quasi-static continuation; the final state at one
  parameter value is the start at the next, so hysteresis (coexisting attractors)
  shows up as a difference between the two sweeps.  Vectorized over ``n_starts``
  simultaneous sweeps; for the square-root maps a scalar fast path is used when a
  single sweep is run (numpy call overhead would dominate).

``PiecewiseMap`` is a fast (in-place) kernel for (37)/(38), (1)/(2) and (54)/(55).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .windows import MapParams

__all__ = ["PiecewiseMap", "OrbitDiagram", "orbit_diagram", "classify", "iterate"]

MapFn = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


class PiecewiseMap:
    """The square-root map (37)/(38) as a fast callable ``f(x, y, rho) -> (x, y)``.

    Uses that sqrt(max(x, 0)) vanishes on the non-impacting side, so only the linear
    coefficients need selecting: x' = k x - c1 sqrt(max(x,0)) + y + rho, y' = m x with
    (k, m) = (c2, c3) if x >= 0 else (alpha, -gamma).
    """

    def __init__(self, p: MapParams):
        self.p = p

    def __call__(self, x, y, rho):
        p = self.p
        x = np.asarray(x, dtype=float)
        imp = x >= 0.0
        sq = np.sqrt(np.maximum(x, 0.0))
        xn = np.where(imp, p.c2, p.alpha) * x - p.c1 * sq + y + rho
        yn = np.where(imp, p.c3, -p.gamma) * x
        return xn, yn

    def iterate_inplace(self, x: np.ndarray, y: np.ndarray, rho: np.ndarray, n: int) -> None:
        """n iterations on float arrays x, y (modified in place); rho broadcast to x."""
        p = self.p
        imp = np.empty(x.shape, dtype=bool)
        k = np.empty_like(x)
        sq = np.empty_like(x)
        xn = np.empty_like(x)
        rho = np.broadcast_to(rho, x.shape)
        for _ in range(n):
            np.greater_equal(x, 0.0, out=imp)
            np.maximum(x, 0.0, out=sq)
            np.sqrt(sq, out=sq)
            np.copyto(k, p.alpha)
            np.copyto(k, p.c2, where=imp)
            np.multiply(k, x, out=xn)
            xn -= p.c1 * sq if p.c1 != 1.0 else sq
            xn += y
            xn += rho
            np.copyto(k, -p.gamma)
            np.copyto(k, p.c3, where=imp)
            np.multiply(k, x, out=y)
            x, xn = xn, x
        if n % 2 == 1:  # after an odd number of swaps the result sits in the scratch array
            np.copyto(xn, x)

    def scalar_orbit(self, x: float, y: float, rho: float, n: int, keep: int) -> tuple[float, float, list, list]:
        """Pure-Python iteration (fast for a single orbit): n steps, recording the last ``keep``."""
        p = self.p
        a, g, c1, c2, c3 = p.alpha, p.gamma, p.c1, p.c2, p.c3
        xs, ys = [], []
        sqrt = math.sqrt
        start = n - keep
        for i in range(n):
            if x >= 0.0:
                x, y = c2 * x - c1 * sqrt(x) + y + rho, c3 * x
            else:
                x, y = a * x + y + rho, -g * x
            if i >= start:
                xs.append(x)
                ys.append(y)
        return x, y, xs, ys


def iterate(f: MapFn, x, y, p, n: int):
    """n iterations of a vectorized map; returns the final (x, y)."""
    x = np.array(x, dtype=float)
    y = np.array(y, dtype=float)
    if isinstance(f, PiecewiseMap):
        x, y = np.broadcast_arrays(x, y, np.asarray(p, dtype=float))[:2]
        x, y = x.copy(), y.copy()
        f.iterate_inplace(x, y, np.asarray(p, dtype=float), n)
        return x, y
    for _ in range(n):
        x, y = f(x, y, p)
    return x, y


@dataclass
class OrbitDiagram:
    """Result of :func:`orbit_diagram`.

    Attributes
    ----------
    param : ndarray, shape (P,)
        The parameter grid, in the order given.
    x, y : ndarray, shape (P, n_starts, n_keep)
        The last n_keep iterates at each parameter value.
    mode : str
    """

    param: np.ndarray
    x: np.ndarray
    y: np.ndarray
    mode: str

    def classify(self, max_period: int = 12, tol: float = 1e-9):
        """(period, impacts per period) per grid point and start; see :func:`classify`."""
        return classify(self.x, max_period, tol)


def orbit_diagram(f: MapFn, param_grid, x0=0.0, y0=0.0, n_transient: int = 1000, n_keep: int = 64,
                  mode: str = "fresh") -> OrbitDiagram:
    """Iterate a map over a parameter grid.

    Parameters
    ----------
    f : callable or PiecewiseMap
        ``f(x, y, p) -> (x, y)``, vectorized.  For a 1D map pass a wrapper returning y.
    param_grid : array_like, shape (P,)
    x0, y0 : float or array_like, shape (n_starts,)
        Initial state(s): for "fresh" at every grid point; for "up"/"down" at the first
        parameter value of the sweep.
    n_transient, n_keep : int
        Iterations discarded and kept at each parameter value (continuation: per step).
    mode : {"fresh", "up", "down"}
        "up" sweeps the grid in increasing, "down" in decreasing parameter order.

    Returns
    -------
    OrbitDiagram
    """
    grid = np.asarray(param_grid, dtype=float)
    x0 = np.atleast_1d(np.asarray(x0, dtype=float))
    y0 = np.atleast_1d(np.asarray(y0, dtype=float))
    x0, y0 = np.broadcast_arrays(x0, y0)
    S, P = x0.size, grid.size
    xs = np.empty((P, S, n_keep))
    ys = np.empty((P, S, n_keep))
    if mode == "fresh":
        x = np.broadcast_to(x0, (P, S)).copy()
        y = np.broadcast_to(y0, (P, S)).copy()
        pp = np.broadcast_to(grid[:, None], (P, S))
        x, y = iterate(f, x, y, pp, n_transient)
        for k in range(n_keep):
            x, y = iterate(f, x, y, pp, 1)
            xs[:, :, k], ys[:, :, k] = x, y
        return OrbitDiagram(grid, xs, ys, mode)
    if mode not in ("up", "down"):
        raise ValueError("mode must be 'fresh', 'up' or 'down'")
    order = np.argsort(grid, kind="stable")
    if mode == "down":
        order = order[::-1]
    x, y = x0.copy(), y0.copy()
    for i in order:
        if isinstance(f, PiecewiseMap) and S == 1:
            xf, yf, kx, ky = f.scalar_orbit(float(x[0]), float(y[0]), float(grid[i]), n_transient + n_keep, n_keep)
            x[0], y[0] = xf, yf
            xs[i, 0], ys[i, 0] = kx, ky
            continue
        x, y = iterate(f, x, y, grid[i], n_transient)
        for k in range(n_keep):
            x, y = iterate(f, x, y, grid[i], 1)
            xs[i, :, k], ys[i, :, k] = x, y
    return OrbitDiagram(grid, xs, ys, mode)


def classify(xs: np.ndarray, max_period: int = 12, tol: float = 1e-9):
    """Period and number of impacts (x >= 0) per period of recorded orbits.

    Parameters
    ----------
    xs : ndarray, shape (..., n_keep)
        Last iterates of each orbit (n_keep > 2 max_period).
    max_period : int
    tol : float
        Absolute tolerance of |x_{k+T} - x_k| over the record.

    Returns
    -------
    period : ndarray of int, shape xs.shape[:-1]
        Smallest T <= max_period with x_{k+T} = x_k over the record; 0 if none.
    impacts : ndarray of int
        Number of iterates with x >= 0 among the last ``period`` ones (0 if period 0).
    """
    n = xs.shape[-1]
    if n <= 2 * max_period:
        raise ValueError("need more than 2*max_period kept iterates")
    period = np.zeros(xs.shape[:-1], dtype=int)
    for T in range(max_period, 0, -1):  # smallest T wins
        ok = np.max(np.abs(xs[..., T:] - xs[..., :-T]), axis=-1) < tol
        period[ok] = T
    impacts = np.zeros_like(period)
    for T in range(1, max_period + 1):
        sel = period == T
        if np.any(sel):
            impacts[sel] = np.sum(xs[sel][:, -T:] >= 0.0, axis=-1)
    return period, impacts
