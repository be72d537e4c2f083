"""Stable periodic orbits searched by Newton shooting on a grid of sigma at fixed parameters.

The evidence on either side of a window's candidate closing (:mod:`harness.analysis.chart.window_region`):
no continuation, only :func:`.periodic_map.refine_orbit` from many starts -- the orbit found at the
previous sigma, orbit shapes given as seeds, and orbits iterated from the wall-free orbit -- and
the grids it runs on (:func:`sigma_grid`, with points close to known edges).
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from ...errors import FmuError

__all__ = ["norm_seed", "shoot_across", "sigma_grid", "with_near_edges"]


def norm_seed(z: Sequence[float], sigma: float, theta: float) -> np.ndarray:
    """A stroboscopic point as w / (1 + sigma) (w = z - p(theta)): the orbit's shape, which moves
    little with sigma (the coordinates of the extended systems), so a seed at another sigma."""
    from .periodic_map import wall_free_offset

    return (np.asarray(z, float) - wall_free_offset(sigma, theta)) / (1.0 + sigma)


def _good(ev: Any, impacts: int) -> tuple[bool, bool]:
    """(the orbit has the window's contacts, and is stable)."""
    same = int(np.sum(ev.contacts)) == impacts
    return same, same and bool(np.all(np.abs(np.linalg.eigvals(ev.J)) < 1.0))


def shoot_across(pmap: Any, M: int, impacts: int, sigmas: np.ndarray, seeds: Sequence[np.ndarray],
                 iterated: tuple[int, int] = (0, 0)) -> list[dict[str, Any]]:
    """Stable period-M orbits with ``impacts`` wall entries per period found by Newton at each sigma.

    At each sigma (in order) Newton starts from the orbit found at the previous sigma, then from
    each of ``seeds`` (shapes w / (1 + sigma), :func:`norm_seed`); at ``iterated[0]`` sigma spread
    over the grid also from the wall-free orbit and the seeds iterated ``iterated[1]`` periods.
    Returns every stable orbit found: ``{"sigma", "point", "multipliers", "residual", "start"}``.
    """
    from .periodic_map import refine_orbit

    found: list[dict[str, Any]] = []
    prev: np.ndarray | None = None
    spread = set(np.linspace(0, len(sigmas) - 1, iterated[0]).round().astype(int).tolist()) if iterated[0] else set()
    for k, s in enumerate(sigmas):
        s = float(s)
        starts = ([("previous", prev)] if prev is not None else []) + [("seed", w * (1.0 + s)) for w in seeds]
        if k in spread:
            starts += _iterated_starts(pmap, s, seeds, iterated[1])
        prev = None
        for name, w0 in starts:
            try:
                # a start near the orbit converges in a few steps; 8 bound the cost of those that do not
                w, ev, ok, res = refine_orbit(pmap, w0, s, M, tol=1e-10 * (1.0 + abs(s)), max_iter=8)
            except FmuError:
                continue
            same, stable = _good(ev, impacts) if ok else (False, False)
            if same:
                prev = w
            if stable:
                mu = np.linalg.eigvals(ev.J)
                found.append({"sigma": s, "point": ev.points[0].tolist(), "residual": float(res), "start": name,
                              "multipliers": [[float(m.real), float(m.imag)] for m in mu]})
                break
    return found


def _iterated_starts(pmap: Any, sigma: float, seeds: Sequence[np.ndarray], periods: int) -> list[tuple[str, np.ndarray]]:
    """The wall-free orbit and each seed at sigma, iterated ``periods`` periods (w coordinates)."""
    out = []
    for w in [np.zeros(2), *seeds]:
        z0 = w * (1.0 + sigma) + pmap.offset(sigma)
        try:
            pts, _ = pmap.run(sigma, z0, periods)
        except FmuError:
            continue
        if np.all(np.isfinite(pts[-1])):
            out.append(("iterated", pts[-1] - pmap.offset(sigma)))
    return out


def sigma_grid(lo: float, hi: float, widen: float, n: int) -> np.ndarray:
    """``n`` sigma from lo to hi, widened by ``widen`` x the width on each side (geometric where
    positive; at least 1e-6 x sigma wide: a window's tip is thin)."""
    if lo > 0:
        span = max(math.log(hi / lo), 2e-6)
        mid = 0.5 * math.log(hi * lo)
        return np.exp(np.linspace(mid - (0.5 + widen) * span, mid + (0.5 + widen) * span, n))
    span = max(hi - lo, 1e-6 * max(abs(hi), 1.0))
    mid = 0.5 * (hi + lo)
    return np.linspace(max(mid - (0.5 + widen) * span, -0.99), mid + (0.5 + widen) * span, n)


def with_near_edges(grid: np.ndarray, edges: Sequence[float]) -> np.ndarray:
    """The grid with points 1e-7, 1e-5 and 1e-3 (relative) on either side of each edge: a window near
    its closing can be a sliver along one edge, far narrower than the grid's step."""
    near = [e + sgn * max(abs(e), 1e-3) * 10.0 ** -k for e in edges for sgn in (-1.0, 1.0) for k in (3, 5, 7)]
    return np.unique(np.concatenate([grid, np.asarray(near, float)]))
