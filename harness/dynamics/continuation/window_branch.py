"""A stable window's edges from the continuation: the window's orbit continued in sigma from a
seed, and the first event on the way that ends the window.

One location for every edge: ``chart``'s windows (:func:`harness.analysis.chart.edge_curves.windows_at`)
and ``windows``/``compare``/``chart``'s per-value scans (:mod:`harness.analysis.windows.located_edges`) take
their edges from here, so a flip or fold is the root of its test function and a graze the zero of
its defining quantity (:mod:`.graze_location`), located by :func:`.continuation.continue_orbit`.
"""
from __future__ import annotations

from typing import Any, Mapping

from .branch import Branch, Event
from .continue_orbit import continue_orbit
from ..maps.periodic_map import PeriodMap

__all__ = ["EDGE_KINDS", "first_edge", "continue_side"]

#: Events that end a stable window of one contact pattern (a stability change or a contact change).
EDGE_KINDS = ("flip", "fold", "ns", "graze", "stick")


def first_edge(branch: Branch) -> Event | None:
    """The first event of ``branch`` that ends the window its first point is in; None when the
    branch ended first (its ``end`` event says why: the range, the point budget, the orbit lost)."""
    for e in branch.events:
        if e.kind in EDGE_KINDS:
            return e
        if e.kind == "end":
            return None
    return None


def continue_side(sim: Any, params: Mapping[str, Any], M: int, sigma0: float, z0: Any,
                  sigma_range: tuple[float, float], direction: float, theta: float = 0.5,
                  max_points: int = 600, locate_tol: float = 1e-8, ds_max: float | None = None,
                  pmap: PeriodMap | None = None) -> Branch:
    """The period-M orbit through ``z0`` (a state (u, v) at the section) at ``sigma0`` continued in
    sigma towards ``direction`` (-1 down, +1 up) within ``sigma_range``.

    The largest step is a tenth of sigma0 (at least 0.05): Figure 9's windows from sigma = 0.1
    to 1000 are crossed in a few dozen steps without stepping over a narrow one.
    """
    step = max(0.05, 0.1 * sigma0) if ds_max is None else ds_max
    return continue_orbit(sim, params, M, sigma0, z0, "sigma", sigma_range, direction, ds_max=step,
                          max_points=max_points, theta=theta, locate_tol=locate_tol, pmap=pmap)
