"""Every route to the ODE's attractors, as one list of families to shoot: the up and down scans,
the global search at every sigma of the grid (:mod:`harness.runs.basins.global_search`), the
wall-free orbit where sigma < 0, and the orbits they name told apart by what they are.

1. *Sightings*: at each sigma of the grid, every periodic orbit a route saw there: its period M,
   wall entries per M periods k, its M stroboscopic points, the route, and for the global search
   its basin share.
2. *Attractors at one sigma*: sightings of the same (M, k) whose point sets lie within
   :data:`ID_REL` of the orbit's scale (Hausdorff, max norm) are one attractor, seen by the union
   of their routes; two point sets further apart are two attractors, whatever their kind.
3. *Tracks*: an attractor at one sigma continues the track of the same (M, k) whose last point
   set (at most :data:`MAX_GAP` grid steps back) is nearest, within :data:`CHAIN_REL`; each
   track is a :class:`RouteFamily`, shot and continued to its edges (:mod:`.ode_windows`).
4. After the shooting (:func:`merge_results`): two tracks of one kind that were never seen at
   the same sigma and reach the same edges are one orbit (a scan that lost it and found it
   again); a track seen beyond the window its orbit was continued to holds another orbit there,
   seeded afresh (:func:`beyond_window`).

Each window then carries its routes and its basin share: the fraction of the global search's
starts that reached it, at each searched sigma inside the window.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from ...dynamics.attractors.identity import hausdorff
from .ode_windows import Family

__all__ = ["RouteFamily", "Sighting", "families_from_routes", "merge_results", "beyond_window", "basin_share",
           "wall_free_point", "ROUTE_SEARCH", "ROUTE_WALL_FREE", "route_of_direction"]

#: Two orbits at one sigma are one attractor within this fraction of their scale max(1, |z|).
ID_REL = 1e-2
#: A track goes on at the next sigma to an orbit of its kind within this fraction of the scale.
CHAIN_REL = 0.2
#: Grid steps a track may skip (a scan point still in its transient there).
MAX_GAP = 2
ROUTE_SEARCH = "global search"
ROUTE_WALL_FREE = "wall-free orbit"


def route_of_direction(d: str) -> str:
    """'up' -> 'scan up', 'down-far' -> 'scan down (far start)'."""
    base, _, far = d.partition("-")
    return f"scan {base}" + (" (far start)" if far else "")


@dataclass
class Sighting:
    """One periodic orbit one route saw at grid point ``i``."""

    i: int
    sigma: float
    M: int
    k: int
    points: np.ndarray  # (M, 2), time order, the last sample last
    routes: set[str]
    share: float | None = None


@dataclass
class RouteFamily(Family):
    """A family seen along a track, with the global search's basin share at each sigma where the
    search found it (sigma -> share) and the grid indices where it was seen."""

    shares: dict[float, float] = field(default_factory=dict)
    seen_at: set[int] = field(default_factory=set)


def wall_free_point(sigma: float, theta: float) -> np.ndarray:
    """The wall-free orbit p(theta) (docs/theory.md (4)) at the section: (u, v)."""
    th = 2.0 * math.pi * theta
    s = math.sin(th) if abs(math.sin(th)) > 1e-12 else 0.0
    return np.array([(1.0 + sigma) * math.cos(th) - 1.0, -2.0 * math.pi * (1.0 + sigma) * s])


def _scale(points: np.ndarray) -> float:
    return max(1.0, float(np.max(np.abs(points))))


#: A sampled orbit of period M whose points repeat after d | M to this fraction of its scale is
#: the period-d orbit: a lightly damped start still spiralling onto a fixed point (multipliers
#: near a 5th root of unity) looks periodic with period 5 before its rotation has died out.
COLLAPSE_REL = 1e-3


def collapsed(M: int, k: int, points: np.ndarray) -> tuple[int, int, np.ndarray]:
    """(period, wall entries per period, points) at the orbit's minimal period (see COLLAPSE_REL)."""
    for d in range(1, M):
        if M % d == 0 and (k * d) % M == 0 and \
                float(np.max(np.abs(np.roll(points, -d, axis=0) - points))) <= COLLAPSE_REL * _scale(points):
            return d, k * d // M, points[-d:]
    return M, k, points


def scan_sightings(grid: np.ndarray, ds: Any, M_max: int | None) -> list[Sighting]:
    out = []
    for d in [str(x) for x in ds["direction"].values]:
        sel = ds.sel(direction=d)
        per, imp = np.asarray(sel["period"].values), np.asarray(sel["orbit_impacts"].values)
        u, v = np.asarray(sel["u"].values), np.asarray(sel["v"].values)
        for i in range(len(grid)):
            M = int(per[i])
            if M > 0 and imp[i] >= 0 and (not M_max or M <= M_max):
                pts = np.column_stack([u[i, -M:], v[i, -M:]])
                if np.all(np.isfinite(pts)):
                    out.append(Sighting(i, float(grid[i]), *collapsed(M, int(imp[i]), pts), {route_of_direction(d)}))
    return out


def search_sightings(grid: np.ndarray, searches: Sequence[Any] | None, M_max: int | None) -> list[Sighting]:
    out = []
    for i, res in enumerate(searches or []):
        for a in res.attractors:
            if not M_max or a.period <= M_max:
                out.append(Sighting(i, float(grid[i]), *collapsed(a.period, a.impacts, np.asarray(a.points)),
                                    {ROUTE_SEARCH}, a.share))
    return out


def wall_free_sightings(grid: np.ndarray, theta: float) -> list[Sighting]:
    """The wall-free orbit at every sigma < 0 of the grid: stable (a damped linear oscillator)
    and clear of the wall (its largest u is sigma), so an attractor there by construction."""
    return [Sighting(i, float(s), 1, 0, wall_free_point(float(s), theta)[None, :], {ROUTE_WALL_FREE})
            for i, s in enumerate(grid) if s < 0]


def attractors_at(sightings: Sequence[Sighting]) -> list[Sighting]:
    """The sightings at one sigma merged into attractors (same kind, point sets within ID_REL)."""
    merged: list[Sighting] = []
    for s in sightings:
        for m in merged:
            if (m.M, m.k) == (s.M, s.k) and hausdorff(m.points, s.points) <= ID_REL * _scale(m.points):
                m.routes |= s.routes
                if s.share is not None:
                    m.share = s.share + (m.share or 0.0)
                if ROUTE_SEARCH in s.routes:  # the search's points are converged orbits
                    m.points = s.points
                break
        else:
            merged.append(Sighting(s.i, s.sigma, s.M, s.k, s.points, set(s.routes), s.share))
    return merged


def _chain(by_index: dict[int, list[Sighting]]) -> list[list[Sighting]]:
    """Tracks: each attractor joins the nearest open track of its kind (greedy by distance)."""
    tracks: list[list[Sighting]] = []
    for i in sorted(by_index):
        open_ = [t for t in tracks if i - t[-1].i <= MAX_GAP]
        pairs = []
        for a, s in enumerate(by_index[i]):
            for b, t in enumerate(open_):
                last = t[-1]
                if (last.M, last.k) == (s.M, s.k):
                    d = hausdorff(last.points, s.points)
                    if d <= CHAIN_REL * _scale(last.points):
                        pairs.append((d, a, b))
        used_s, used_t = set(), set()
        for d, a, b in sorted(pairs):
            if a not in used_s and b not in used_t:
                open_[b].append(by_index[i][a])
                used_s.add(a)
                used_t.add(b)
        tracks += [[s] for a, s in enumerate(by_index[i]) if a not in used_s]
    return tracks


def family_of_track(track: Sequence[Sighting], geometric: bool) -> RouteFamily:
    """The track as a family: seeded at its middle, its sightings the Newton guesses."""
    mid = track[len(track) // 2]
    routes = sorted(set().union(*[s.routes for s in track]))
    return RouteFamily(mid.M, mid.k, track[0].sigma, track[-1].sigma, mid.sigma, np.array(mid.points[-1], dtype=float),
                       routes, [(s.sigma, np.array(s.points[-1], dtype=float)) for s in track], geometric,
                       {s.sigma: float(s.share) for s in track if s.share is not None}, {s.i for s in track})


def families_from_routes(grid: np.ndarray, ds: Any, searches: Sequence[Any] | None, M_max: int | None,
                         geometric: bool, theta: float) -> list[RouteFamily]:
    """Every attractor the scans, the global search and the wall-free orbit show, one family per
    track (see the module's docstring)."""
    sightings = scan_sightings(grid, ds, M_max) + search_sightings(grid, searches, M_max)
    sightings += wall_free_sightings(grid, theta)
    by_index: dict[int, list[Sighting]] = {}
    for s in sightings:
        by_index.setdefault(s.i, []).append(s)
    by_index = {i: attractors_at(ss) for i, ss in by_index.items()}
    fams = [family_of_track(t, geometric) for t in _chain(by_index)]
    return sorted(fams, key=lambda f: (f.M, f.impacts, f.lo))


def _edges(r: Mapping[str, Any]) -> tuple[float | None, float | None]:
    return r["lower"].sigma, r["upper"].sigma


def _same_edges(a: Mapping[str, Any], b: Mapping[str, Any], tol: float) -> bool:
    for x, y in zip(_edges(a), _edges(b)):
        if (x is None) != (y is None) or (x is not None and abs(x - y) > tol * max(1.0, abs(x))):
            return False
    return True


def merge_results(results: Sequence[dict[str, Any]], tol: float) -> list[dict[str, Any]]:
    """Shot families that are one orbit merged: same kind, never seen at the same sigma (two
    attractors seen at one sigma are two orbits), and edges equal within ``tol`` (relative to
    max(1, |edge|)).  The merged family keeps the routes, sightings and shares of both."""
    out: list[dict[str, Any]] = []
    for r in results:
        f = r["family"]
        for m in out:
            g = m["family"]
            if (r["resolved"] and m["resolved"] and (g.M, g.impacts) == (f.M, f.impacts)
                    and not (getattr(g, "seen_at", set()) & getattr(f, "seen_at", set()))
                    and _same_edges(m, r, tol)):
                g.found_by = sorted(set(g.found_by) | set(f.found_by))
                g.track = sorted(g.track + f.track, key=lambda t: t[0])
                g.lo, g.hi = min(g.lo, f.lo), max(g.hi, f.hi)
                if isinstance(g, RouteFamily) and isinstance(f, RouteFamily):
                    g.shares.update(f.shares)
                    g.seen_at |= f.seen_at
                break
        else:
            out.append(r)
    return out


def beyond_window(results: Sequence[dict[str, Any]], grid: np.ndarray) -> list[RouteFamily]:
    """The parts of resolved tracks seen outside the window their seed was continued to (more
    than a grid step beyond an edge): another orbit of the kind, as families of their own."""
    out = []
    for r in results:
        f = r["family"]
        if not (r["resolved"] and isinstance(f, RouteFamily)):
            continue
        lo, hi = _edges(r)
        step = float(np.max(np.abs(np.diff(grid)))) if len(grid) > 1 else 0.0
        outside = [(s, z) for s, z in f.track if (lo is not None and s < lo - step) or (hi is not None and s > hi + step)]
        for part in (_below(outside, lo), _above(outside, hi)):
            if part:
                mid = part[len(part) // 2]
                out.append(RouteFamily(f.M, f.impacts, part[0][0], part[-1][0], mid[0], np.array(mid[1]),
                                       list(f.found_by), part, f.geometric,
                                       {s: x for s, x in f.shares.items() if any(s == p[0] for p in part)},
                                       set()))
    return out


def _below(track: list, lo: float | None) -> list:
    return [t for t in track if lo is not None and t[0] < lo]


def _above(track: list, hi: float | None) -> list:
    return [t for t in track if hi is not None and t[0] > hi]


def basin_share(f: Any, lo: float | None, hi: float | None, searched: Sequence[float]) -> dict[str, Any] | None:
    """The window's basin share over the searched sigma inside it: largest share and where,
    the mean, and at how many sigma values (None: no search, or no searched sigma inside)."""
    if not searched:
        return None
    inside = [s for s in searched if (lo is None or s >= lo) and (hi is None or s <= hi)]
    if not inside:
        return None
    shares = getattr(f, "shares", {}) or {}
    vals = [float(shares.get(s, 0.0)) for s in inside]
    j = int(np.argmax(vals))
    return {"max": vals[j], "at_sigma": inside[j], "mean": float(np.mean(vals)), "values": len(inside),
            "found_at": int(sum(v > 0 for v in vals))}


class Routes:
    """The routes of one ``windows`` run, as :func:`harness.analysis.windows.ode_windows.measure`
    uses them: the families to shoot, the refinement after the shooting, each window's share."""

    def __init__(self, grid: np.ndarray, ds: Any, searches: Sequence[Any] | None, M_max: int | None,
                 theta: float) -> None:
        self.grid, self.ds, self.searches, self.M_max, self.theta = grid, ds, searches, M_max, theta
        self.searched = [float(s) for s in grid] if searches else []
        self.transients: list[dict[str, Any]] = []

    def families(self, geometric: bool) -> list[RouteFamily]:
        return families_from_routes(self.grid, self.ds, self.searches, self.M_max, geometric, self.theta)

    def refine(self, results: list[dict[str, Any]], n: int, shoot: Any, xtol_rel: float) -> tuple[list, int]:
        """Tracks seen beyond their windows shot afresh (``shoot(families) -> (results, n)``),
        then one orbit's families merged (edges equal to max(1e-6, 4 xtol_rel), relative)."""
        extra = beyond_window(results, self.grid)
        if extra:
            more, n_more = shoot(extra)
            # a part that Newton does not resolve is the resolved orbit's transient near its edge
            # (critical slowing down at a flip looks like period 2M): kept in the JSON, not as a row
            self._set_aside([r for r in more if not r["resolved"]], "seen beyond its track's window, not resolved")
            results, n = list(results) + [r for r in more if r["resolved"]], n + n_more
        # an orbit only the global search saw that Newton does not resolve is not shown as a window:
        # a start still settling (a long transient, a chaotic orbit close to periodic) can pass as one
        lone = [r for r in results if not r["resolved"] and list(r["family"].found_by) == [ROUTE_SEARCH]]
        self._set_aside(lone, "only the global search saw it, and Newton did not resolve it")
        results = [r for r in results if not any(r is x for x in lone)]
        results = sorted(results, key=lambda r: (r["family"].M, r["family"].impacts, r["family"].lo))
        return merge_results(results, max(1e-6, 4.0 * xtol_rel)), n

    def _set_aside(self, results: Sequence[Mapping[str, Any]], why: str) -> None:
        for r in results:
            f = r["family"]
            self.transients.append({"M": f.M, "impacts": f.impacts, "seen": [f.lo, f.hi], "found_by": f.found_by,
                                    "basin_share": self.share(r), "why": why})

    def share(self, r: Mapping[str, Any]) -> dict[str, Any] | None:
        f = r["family"]
        lo, hi = _edges(r) if r["resolved"] else (f.lo, f.hi)
        return basin_share(f, lo, hi, self.searched)


def search_sampling(theta: float, transient: int, samples: int) -> Any:
    """The global search's sampling: the scans' periods, a periodicity tolerance of 1e-6 of the
    orbit's size (its attractors are told apart at :data:`ID_REL`, far above it)."""
    from ...config import SamplingSpec

    return SamplingSpec(theta=theta, n_transient=transient, n_samples=samples, tol=SEARCH_TOL)


#: Periodicity tolerance of the global search's starts (relative to the orbit's size).
SEARCH_TOL = 1e-6


def run_search(ctx: Any, problem: Any, st: Any, ds: Any) -> list[Any] | None:
    """The global search at every sigma of the scan grid (None when ``st.global_starts`` is 0):
    each over :meth:`Region.around_orbits` of the wall-free orbit and the orbits the scans saw
    at that sigma."""
    from ...runs.basins.global_search import Region, global_search_over

    if not st.global_starts:
        return None
    grid = st.scan_grid
    seen = {i: [] for i in range(len(grid))}
    for s in scan_sightings(grid, ds, None):
        seen[s.i].append(s.points)
    index = {float(x): i for i, x in enumerate(grid)}

    def region_of(sigma: float) -> Region:
        pts = seen[index[sigma]]
        return Region.around_orbits(sigma, problem.theta, problem.wall == "rigid",
                                    np.concatenate(pts) if pts else None)

    params = ctx.params(**problem.fmu_params())
    return global_search_over("sigma", [float(x) for x in grid], params,
                              search_sampling(problem.theta, st.transient, st.samples), region_of,
                              st.global_starts, path=st.global_path, fmu=ctx.fmu, workers=ctx.workers,
                              progress=ctx.progress)


def search_summary(grid: np.ndarray, searches: Sequence[Any] | None) -> dict[str, Any] | None:
    """The JSON's ``global_search``: per sigma, the starts and each attractor's kind and share."""
    if not searches:
        return None
    return {"starts_per_value": int(searches[0].n_starts), "path": searches[0].path,
            "wall_s": float(sum(r.wall_s for r in searches)),
            "values": [{"sigma": float(s), "attractors": [[a.key, a.share] for a in r.attractors], "other": r.other}
                       for s, r in zip(grid, searches)]}


def found_only_by_search(rows: Sequence[Mapping[str, Any]]) -> list[Mapping[str, Any]]:
    """The windows no route but the global search found."""
    return [r for r in rows if list(r.get("found_by", [])) == [ROUTE_SEARCH]]
