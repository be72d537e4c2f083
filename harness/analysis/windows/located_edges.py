"""The edges of a family of stable orbits located by the continuation, in the reports' words.

A family (period M, k contacts per M periods) seen by the scans is continued in sigma both ways
from its seed orbit (:func:`harness.dynamics.continuation.window_branch.continue_side`, the walk that
``continue`` and ``chart`` use), and the first event on each side that ends the stable window is
its edge: a flip or fold is the root of its test function (det(D + I), det(D - I)), located to
:data:`LOCATE_TOL` along the branch, a flip then again at fixed sigma (:func:`polish_flip`); a graze the zero of its defining quantity (the gap of a free passage, the
entry velocity of a contact), with an interval that contains it (:mod:`harness.dynamics.continuation.graze_location`),
or where no such quantity describes it, the contact change bisected along the branch (``located``
says which).
The location does not depend on ``--quick``: only the search (scan grid, transients) does.

The continuation's kinds are mapped onto the reports' vocabulary: flip, fold, torus (ns),
graze (a contact appears or vanishes: its gap or entry velocity reaches 0), period-halving (a
period-2m branch meeting the period-m orbit at its flip), stick.  An impact time crossing the
section phase t = n + theta is not an edge: the orbit, its contacts over a period and its
multipliers go on through it (the continuation steps across, :mod:`harness.dynamics.continuation.orbit_walk`).

The branch is checked before its event is believed: every point before it must be stable with
the family's contacts (a step that crossed a flip and a graze at once would otherwise give the
graze); a side that fails, or whose branch ends before any event (orbit lost, point budget),
is reported as such and left to the march and bisection (:func:`harness.dynamics.maps.shooting.window_edges`).
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from ...dynamics.continuation.arclength import illinois_update
from ...dynamics.continuation.branch import Branch, Event
from ...dynamics.continuation.graze_location import CONTACT_CHANGE_SLACK
from ...dynamics.maps.periodic_map import PeriodMap, refine_orbit
from ...dynamics.maps.shooting import Edge
from ...dynamics.continuation.window_branch import continue_side, first_edge
from ...errors import FmuError

__all__ = ["LOCATE_TOL", "report_kind", "edge_from_event", "locate_side", "located_edges"]

#: Width in sigma to which flips, folds and contact changes are located (quick and full alike).
LOCATE_TOL = 1e-9

#: Continuation steps per segment; a segment that ends on its budget is followed by another,
#: started at its last point with a largest step of a tenth of sigma there (Figure 9's period-1
#: window runs from 0.81 to beyond 1000), up to :data:`SEGMENTS` segments.
SEGMENT_POINTS = 150
SEGMENTS = 6

#: A graze's last orbit with the old contacts counts as stable up to this |multiplier|.
MARGIN = 1e-6


def _minimal_period(points: np.ndarray, rtol: float = 1e-7) -> int:
    """Smallest d dividing M with z_{k+d} = z_k along one orbit's M section points."""
    M = len(points)
    scale = max(1.0, float(np.max(np.abs(points))))
    for d in range(1, M):
        if M % d == 0 and float(np.max(np.abs(np.roll(points, -d, axis=0) - points))) <= rtol * scale:
            return d
    return M


def report_kind(branch: Branch, e: Event, impacts: int) -> str:
    """The report's name of the continuation's event ``e`` ending a window of ``impacts`` contacts."""
    if e.kind == "flip":
        return "period-halving" if _minimal_period(branch.points[e.index]) < branch.M else "flip"
    if e.kind == "ns":
        return "torus"
    # fold, stick; a contact appearing or vanishing is a graze either way (its defining quantity,
    # a gap or an entry velocity, reaches 0); an impact time crossing the section phase is no
    # event at all (the continuation goes on through it)
    return e.kind


def edge_from_event(e: Event, kind: str, direction: float) -> Edge:
    """The :class:`Edge` of a located event on the side ``direction`` (-1 lower, +1 upper):
    ``good``/``bad`` the ends of the event's interval inside/outside the window."""
    v = float(e.value)
    if e.interval is not None:
        lo, hi = sorted(float(x) for x in e.interval)
    elif e.kind in ("graze", "stick"):
        # located by the contact pattern only (an event without its widened interval): the last
        # orbit with the old contacts, and the first parameter without them ``bracket`` beyond it
        lo, hi = sorted((v, v + direction * float(e.bracket)))
    else:
        # the root of the test function lies in the final bracket of width ``bracket`` around
        # the point returned (rounding where the test function itself reached 0)
        half = max(float(e.bracket), 1e-13 * (1.0 + abs(v)))
        lo, hi = v - half, v + half
    good, bad = (hi, lo) if direction < 0 else (lo, hi)
    return Edge(v, kind, hi - lo, np.asarray(e.multipliers), good, bad, np.asarray(e.point, dtype=float))


def _how(e: Event) -> str:
    """How the event was located, for the entry's ``located``: "continuation", with the defining
    quantity of a graze ("gap = 0", "entry velocity = 0"), or "contact change" where no quantity
    describes it (the last orbit with the old contacts and the first parameter without them, the
    corrector's orbits: up to 3e-9 past the exact graze in Figure 9's windows before those were
    located on their gap, hence the interval widened by :data:`CONTACT_CHANGE_SLACK`)."""
    if e.kind not in ("graze", "stick"):
        return "continuation"
    if e.quantity in ("gap", "entry velocity"):
        return f"continuation ({e.quantity} = 0)"
    return f"continuation (contact change; interval widened by {CONTACT_CHANGE_SLACK:g} (1 + |sigma|) each side)"


def polish_flip(pmap: PeriodMap, branch: Branch, e: Event, impacts: int) -> tuple[float, float, float] | None:
    """A flip located again on its test function det(D(F^M) + I) of the orbit solved at fixed sigma
    (Newton to a residual of 1e-13 (1 + |sigma|)), by the Illinois method from the continuation's
    value: (sigma, lo, hi) with the test function changing sign on [lo, hi] (1e-11 (1 + |sigma|)
    wide), or None where no sign change is found within 1e-5 of it.

    The continuation's own location is the root along its corrected points (residual 1e-10) and its
    bracket in arclength: from a seed far away (Figure 9's period 1 seeded at sigma = 17) it was
    6.6e-9 off with a bracket of 8e-12; on both sides of a flip the orbit exists, so the root in
    sigma itself is the honest one."""
    M, v = branch.M, float(e.value)
    w0 = np.asarray(branch.points[e.index][0], dtype=float) - pmap.offset(v)

    def f(s: float) -> float:
        _, ev, ok, _ = refine_orbit(pmap, w0, s, M, tol=1e-13 * (1.0 + abs(s)), max_iter=20)
        same = ok and int(np.asarray(ev.contacts).sum()) == impacts
        return float(np.linalg.det(ev.J + np.eye(2))) if same else math.nan

    d = max(1e-9 * (1.0 + abs(v)), 4.0 * float(e.bracket))
    while d <= 1e-5 * (1.0 + abs(v)):
        lo, hi = v - d, v + d
        flo, fhi = f(lo), f(hi)
        if math.isfinite(flo) and math.isfinite(fhi) and flo * fhi <= 0.0:
            break
        d *= 10.0
    else:
        return None
    side = 0
    for _ in range(60):
        if hi - lo <= 1e-12 * (1.0 + abs(v)) or flo == 0.0 or fhi == 0.0:
            break
        s = (lo * fhi - hi * flo) / (fhi - flo)
        fs = f(s)
        if not math.isfinite(fs):
            return None
        lo, hi, flo, fhi, side = illinois_update(lo, hi, flo, fhi, s, fs, side)
    root = lo if flo == 0.0 else hi if fhi == 0.0 else (lo * fhi - hi * flo) / (fhi - flo)
    # the test function carries the orbit's Newton residual: from five seeds Figure 9's period-1
    # flip came out within 6e-13, so the interval is at least 5e-12 (1 + |sigma|) either side
    half = max(0.5 * (hi - lo), 5e-12 * (1.0 + abs(root)))
    return root, root - half, root + half


def _consistent(branch: Branch, e: Event | None, impacts: int) -> bool:
    """Every point before the event (all, without one) is stable with the family's contacts, and
    a graze's last orbit with the old contacts is not unstable (no flip stepped over)."""
    n = len(branch) if e is None else e.index
    ok = bool(np.all(branch.stable[:n]) and np.all(branch.impacts[:n] == impacts))
    if ok and e is not None and e.kind in ("graze", "stick"):
        ok = bool(np.max(np.abs(e.multipliers)) < 1.0 + MARGIN or np.max(np.abs(e.multipliers)) == 0.0)
    return ok


def locate_side(pmap: PeriodMap, M: int, impacts: int, sigma0: float, z0: Any, sigma_range: tuple[float, float],
                direction: float, ds_max: float | None = None) -> tuple[Edge | None, str]:
    """The edge on one side by the continuation: (Edge, "continuation"), (Edge with kind "range"
    and sigma None, "continuation"): the window runs past the range; or (None, why not)."""
    lo, hi = sigma_range
    s, z = float(sigma0), np.asarray(z0, dtype=float)
    for _ in range(SEGMENTS):
        try:
            br = continue_side(pmap.sim, pmap.params, M, s, z, sigma_range, direction, pmap.theta,
                               max_points=SEGMENT_POINTS, locate_tol=LOCATE_TOL, ds_max=ds_max, pmap=pmap)
        except (ValueError, ArithmeticError, FmuError) as exc:
            return None, f"the continuation failed ({type(exc).__name__}: {exc})"
        e = first_edge(br)
        if not _consistent(br, e, impacts):
            return None, ("the continued branch lost stability or changed contacts before its first located "
                          "event (an event stepped over)")
        if e is not None:
            kind = report_kind(br, e, impacts)
            edge = edge_from_event(e, kind, direction)
            if kind == "flip":
                polished = polish_flip(pmap, br, e, impacts)
                if polished is None:
                    return edge, "continuation (flip not confirmed at fixed sigma)"
                v, lo, hi = polished
                good, bad = (hi, lo) if direction < 0 else (lo, hi)
                edge = Edge(v, kind, hi - lo, edge.multipliers, good, bad, edge.state)
            return edge, _how(e)
        last = float(br.values[-1])
        if not lo <= last <= hi:
            inside = float(br.values[-2]) if len(br) > 1 else float(sigma0)
            limit = lo if direction < 0 else hi
            return Edge(None, "range", abs(limit - inside), br.multipliers[-1], inside, None), "continuation"
        end = br.events[-1].note
        if end != f"{SEGMENT_POINTS} steps done":
            return None, f"the continuation ended before an event: {end}"
        s, z, ds_max = last, br.points[-1][0], max(0.05, 0.1 * abs(last))
    return None, f"no event within {SEGMENTS * SEGMENT_POINTS} continuation steps"


def located_edges(smap: Any, M: int, impacts: int, sigma0: float, z0: Any,
                  sigma_range: tuple[float, float]) -> tuple[list[Edge | None], list[str], int]:
    """Both edges of the window of the stable orbit through ``z0`` (state at the section) at
    ``sigma0`` by the continuation on ``smap``'s FMU: ([lower, upper], [how, how], FMU periods
    run).  A side not located is None, its ``how`` says why.  Where a side fails with the
    default steps it is tried once more with steps 20 times shorter."""
    pmap = PeriodMap(smap.sim, smap.params, "sigma", smap.theta)
    edges: list[Edge | None] = []
    how: list[str] = []
    for d in (-1.0, 1.0):
        e, why = locate_side(pmap, M, impacts, sigma0, z0, sigma_range, d)
        if e is None:
            e, why2 = locate_side(pmap, M, impacts, sigma0, z0, sigma_range, d,
                                  ds_max=max(0.05, 0.1 * abs(sigma0)) / 20.0)
            why = why2 if e is not None else why
        edges.append(e)
        how.append(why)
    return edges, how, int(pmap.evaluations)
