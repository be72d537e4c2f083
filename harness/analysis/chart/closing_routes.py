"""A window's closing held against every route of the run, and a second, one-parameter route to it.

The closing of a window is the largest p2 at which a stable orbit of the window exists.  The edge
curves propose it and shooting confirms it (:mod:`.window_region`), one candidate at a time; this
module holds the answer against all the evidence of the same run:

* **no closing below a stable orbit**: every p2 at which a route of the run found a stable orbit of
  the window -- the per-value scans (their windows, each shot to its edges), a contradiction settled
  "scans right" by shooting, the confirmation's own shots below a candidate, the orbit found above a
  hand-over -- is a lower bound of the closing;
* **the one-parameter route**: at a fixed p2 the window's branch is continued over sigma (Newton on
  a local sigma grid, each orbit from its neighbour's) and the smallest spectral radius rho(p2)
  along it is found (bounded Brent around the grid's smallest); the window exists iff
  rho(p2) < 1.  Between the largest p2 with a stable orbit and a p2 where rho >= 1 (or the branch
  is gone) the closing is bisected in ln p2 (:func:`bisect_closing`);
* **coincidence**: the bisected closing must coincide, within :data:`FEATURE_TOL`, with a located
  boundary feature of the edge curves (a turning point, a corner where two edge curves meet, a
  grazing orbit losing stability); else the closing is "unresolved", with both numbers.

:func:`reconcile_closings` applies this to each window of a chart and records, per window, the
closing and the routes that agree on it (``closes[M]["routes"]``, the report's top).
"""
from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np

from ...dynamics.maps.sigma_search import norm_seed
from .closing_evidence import boundary_features, curve_sets, stable_evidence

__all__ = ["branch_radius", "bisect_closing", "reconcile_closings",
           "closing_route_lines", "FEATURE_TOL", "BISECT_TOL"]

#: A bisected closing and a boundary feature of the edge curves coincide within this (relative in p2).
FEATURE_TOL = 2e-3
#: The bisection in ln p2 stops at this relative bracket.
BISECT_TOL = 1e-6
#: Values of sigma on the local grid along the branch.
BRANCH_GRID = 17
#: An asymptote's one-parameter route evaluates the branch this many times beyond the edge's last charted sigma,
#: at most at :data:`FAR_MAX` (the FMU takes states up to 1e6, the orbit's u reaches ~2 (1 + sigma)).
FAR, FAR_MAX = 2.0, 1e5
#: Growth of p2 per step while looking for a p2 where the window is gone above the evidence.
MARCH = 1.02


def _orbit(pmap: Any, w: np.ndarray, s: float, M: int, impacts: int) -> tuple[np.ndarray, float] | None:
    """Newton at sigma ``s`` from ``w``: (w, spectral radius) of an orbit with ``impacts`` contacts."""
    from ...dynamics.maps.periodic_map import refine_orbit

    if not np.all(np.isfinite(w)):
        return None
    w_new, ev, ok, _ = refine_orbit(pmap, w, s, M, tol=1e-11 * (1.0 + abs(s)))
    if not ok or int(ev.contacts.sum()) != impacts:
        return None
    return w_new, float(np.max(np.abs(np.linalg.eigvals(ev.J))))


def branch_radius(pmap: Any, M: int, impacts: int, lo: float, hi: float,
                  seeds: Sequence[tuple[float, np.ndarray]]) -> dict[str, Any] | None:
    """The smallest spectral radius of the window's branch over sigma in [lo, hi] at the p2 of ``pmap``.

    ``seeds``: (sigma, shape w / (1 + sigma)) of known orbits of the window.  The branch is followed
    across a local grid of :data:`BRANCH_GRID` sigma (each Newton from its neighbour's orbit, the
    seeds where the walk has none), then the smallest radius refined by bounded Brent between the
    grid's neighbours of the smallest.  Returns ``{"rho", "sigma", "point"}``, None where no orbit
    with the window's contacts is found."""
    grid = np.geomspace(lo, hi, BRANCH_GRID) if lo > 0 else np.linspace(lo, hi, BRANCH_GRID)
    order = sorted(range(len(grid)), key=lambda i: min(abs(grid[i] - s) for s, _ in seeds))
    found: dict[int, tuple[np.ndarray, float]] = {}
    for i in [order[0]] + sorted(range(len(grid)), key=lambda i: abs(i - order[0]))[1:]:
        s = float(grid[i])
        starts = [found[j][0] for j in (i - 1, i + 1) if j in found]
        starts += [shape * (1.0 + s) for _, shape in sorted(seeds, key=lambda x: abs(x[0] - s))[:3]]
        for w0 in starts:
            got = _orbit(pmap, np.asarray(w0, float), s, M, impacts)
            if got is not None:
                found[i] = got
                break
    if not found:
        return None
    i = min(found, key=lambda j: found[j][1])
    a, b = float(grid[max(i - 1, 0)]), float(grid[min(i + 1, len(grid) - 1)])
    last = {"w": found[i][0]}

    def rho(s: float) -> float:
        got = _orbit(pmap, last["w"], s, M, impacts)
        if got is None:
            return 10.0  # no orbit with the window's contacts there: outside the branch's stretch
        last["w"] = got[0]
        return got[1]

    best = (found[i][1], float(grid[i]), found[i][0])
    if a < b:
        from scipy.optimize import minimize_scalar  # on first use: a second or more to import

        r = minimize_scalar(rho, bounds=(a, b), method="bounded", options={"xatol": 1e-10 * (1.0 + abs(b))})
        got = _orbit(pmap, found[i][0], float(r.x), M, impacts)
        if got is not None and got[1] < best[0]:
            best = (got[1], float(r.x), got[0])
    rho_min, s_min, w_min = best
    return {"rho": float(rho_min), "sigma": s_min, "point": (w_min + pmap.offset(s_min)).tolist()}


def _interval(s0: float, width: float, edges: Sequence[float]) -> tuple[float, float]:
    """Where the branch's smallest radius is sought: between the two edge crossings that bound the
    window around ``s0`` at that p2, widened by a quarter of their distance (the window is there);
    where the edges do not cross that p2 (beyond a turning point), within ``width`` of ``s0``."""
    from .window_region import bracketing

    b = bracketing(edges, s0) if len(edges) >= 2 else []
    if len(b) == 2 and b[0] < b[1] and (b[0] > 0) == (s0 > 0):
        if b[0] > 0:
            q = max(0.25 * math.log(b[1] / b[0]), 1e-4)
            return b[0] * math.exp(-q), b[1] * math.exp(q)
        q = max(0.25 * (b[1] - b[0]), 1e-4)
        return max(b[0] - q, -0.99), b[1] + q
    return (s0 / (1.0 + width), s0 * (1.0 + width)) if s0 > 0 else (max(s0 - width, -0.99), s0 + width)


def _radius_at(sim: Any, params: Mapping[str, Any], param2: str, theta: float, M: int, impacts: int, p2: float,
               around: Mapping[str, Any], width: float, edges: Sequence[float] = ()) -> dict[str, Any] | None:
    """:func:`branch_radius` at ``p2``, over sigma between the edges crossing it (``edges``) or within
    ``width`` (relative; absolute below grazing) of the last minimum ``around``, seeded with its orbit;
    the interval moved (up to ten times) while the smallest radius lies at one of its ends."""
    from ...dynamics.maps.periodic_map import PeriodMap

    pmap = PeriodMap(sim, {**params, param2: float(p2)}, "sigma", theta)
    seeds = [(float(around["sigma"]), norm_seed(around["point"], float(around["sigma"]), theta))]
    r = None
    for k in range(10):
        s0 = float(around["sigma"] if r is None else r["sigma"])
        lo, hi = _interval(s0, width, edges if k == 0 else ())
        r = branch_radius(pmap, M, impacts, lo, hi, seeds)
        if r is None:
            return None
        step = (hi / lo) ** (1.0 / (BRANCH_GRID - 1)) if lo > 0 else (hi - lo) / (BRANCH_GRID - 1)
        at_end = (r["sigma"] <= lo * step or r["sigma"] >= hi / step) if lo > 0 else \
            (r["sigma"] <= lo + step or r["sigma"] >= hi - step)
        if not at_end:
            break
        seeds = [(r["sigma"], norm_seed(r["point"], r["sigma"], theta))] + seeds
    return r


def bisect_closing(sim: Any, params: Mapping[str, Any], param2: str, theta: float, M: int, impacts: int,
                   p_lo: float, orbit_lo: Mapping[str, Any], p_hi: float, p_max: float, width: float,
                   crossings: Any = None) -> dict[str, Any]:
    """Where rho(p2) (:func:`branch_radius`) reaches 1 above ``p_lo`` (a stable orbit ``orbit_lo``
    there: {"sigma", "point"}): rho is checked below 1 at ``p_lo``, marched up by :data:`MARCH` from
    ``p_hi`` (at most to ``p_max``) until it is >= 1 or the branch is gone, and the bracket bisected
    in ln p2 to :data:`BISECT_TOL`.  Returns ``{"status", "p2", "bracket", "rho_lo", "sigma",
    "evaluations"}``; status "bisected", "open" (rho < 1 up to ``p_max``) or "no stable orbit" (rho >= 1
    at ``p_lo`` on the branch through ``orbit_lo``)."""
    n = [0]

    def at(p: float, around: Mapping[str, Any]) -> dict[str, Any] | None:
        n[0] += 1
        edges = crossings(p) if crossings is not None else ()
        return _radius_at(sim, params, param2, theta, M, impacts, p, around, width, edges)

    low = at(p_lo, orbit_lo)
    if low is None or low["rho"] >= 1.0:
        return {"status": "no stable orbit", "p2": p_lo, "bracket": [p_lo, p_lo], "evaluations": n[0],
                "note": f"no orbit of the window with radius below 1 found along sigma at {p_lo:.8g}, where it starts",
                "rho_lo": None if low is None else low["rho"], "sigma": float(orbit_lo["sigma"])}
    hi_p = max(p_hi, p_lo * (1.0 + BISECT_TOL))
    while True:
        high = at(hi_p, low)
        if high is None or high["rho"] >= 1.0:
            break
        p_lo, low = hi_p, high
        if hi_p >= p_max:
            return {"status": "open", "p2": p_lo, "bracket": [p_lo, p_max], "rho_lo": low["rho"],
                    "sigma": low["sigma"], "evaluations": n[0]}
        hi_p = min(hi_p * MARCH, p_max)
    while hi_p / p_lo > 1.0 + BISECT_TOL:
        mid = math.sqrt(p_lo * hi_p)
        r = at(mid, low)
        if r is not None and r["rho"] < 1.0:
            p_lo, low = mid, r
        else:
            hi_p = mid
    return {"status": "bisected", "p2": math.sqrt(p_lo * hi_p), "bracket": [p_lo, hi_p], "rho_lo": low["rho"],
            "sigma": low["sigma"], "point": low["point"], "evaluations": n[0]}


def _width_at(w: Mapping[str, Any], p2: float, sigma: float) -> float:
    """The sigma interval searched along the branch at ``p2``, relative to ``sigma`` (absolute below
    grazing): three times the window's width there (its continued edges' crossings of ``p2`` on
    either side of ``sigma``), at least 0.02 and at most 1."""
    from .window_region import edge_crossings

    xs = sorted({x for cs in curve_sets(w) for x in edge_crossings(cs, p2)})
    lo = max((x for x in xs if x <= sigma), default=None)
    hi = min((x for x in xs if x >= sigma), default=None)
    if lo is None or hi is None:
        return 0.25
    width = math.log(hi / lo) if lo > 0 else hi - lo
    return float(min(max(3.0 * width, 0.02), 1.0))


def _reconcile(sim: Any, problem: Any, w: Mapping[str, Any], cl: dict[str, Any], evidence: list[dict[str, Any]],
               features: list[dict[str, Any]]) -> dict[str, Any]:
    """The one-parameter route from the highest stable orbit of the run, and its agreement."""
    reported = cl.get("closes")
    seeded = [e for e in evidence if e["point"] is not None]
    if reported is None:
        # nothing to hold: the edges bound no closing in the range (a window's flip edge entering the
        # sigma range from outside is no closing, and a local minimum of the radius says nothing there)
        return {"status": "not checked", "note": "no closing reported by the edge curves and shooting"}
    if not seeded:
        return {"status": "not checked", "note": "no stable orbit of the window kept by any route of the run"}
    top = max(evidence, key=lambda e: e["p2"])
    start = max(seeded, key=lambda e: e["p2"])
    if "asymptote" in str(cl.get("kind", "")):
        return _asymptote_route(sim, problem, w, cl, top)
    p_lo = start["p2"]
    p_hi = reported * (1.0 + 1e-3) if reported is not None and reported > p_lo else p_lo * MARCH
    p_max = float(problem.values[-1])
    from .window_region import edge_crossings

    def crossings(p: float) -> list[float]:
        return sorted({x for cs in curve_sets(w) for x in edge_crossings(cs, p)})

    res = bisect_closing(sim, problem.params, problem.param2, problem.theta, int(w["M"]), 1, p_lo, start,
                         min(p_hi, p_max), p_max, _width_at(w, p_lo, start["sigma"]), crossings)
    res["from"] = {k: start[k] for k in ("p2", "sigma", "route")}
    res["evidence_top"] = {k: top[k] for k in ("p2", "sigma", "route")}
    if res["status"] != "bisected":
        return res
    pb = res["p2"]
    near = min(features, key=lambda f: abs(f["p2"] - pb), default=None)
    res["feature"] = near
    res["status"] = "resolved" if near is not None and abs(near["p2"] - pb) <= FEATURE_TOL * pb else "unresolved"
    return res


def _asymptote_route(sim: Any, problem: Any, w: Mapping[str, Any], cl: Mapping[str, Any],
                     top: Mapping[str, Any]) -> dict[str, Any]:
    """The one-parameter route to a closing where the lower edge runs off to sigma -> infinity: the
    window then lies above that edge, and as sigma grows the oscillator becomes scale-invariant (the
    wall's offset negligible beside the forcing amplitude), so the branch's radius at a sigma
    :data:`FAR` times the edge's last charted one is near its limit; bisected in ln p2 from the orbit shot
    below the candidate, scaled there, it reaches 1 at the asymptote (within c / sigma of it)."""
    from ...dynamics.maps.periodic_map import PeriodMap, wall_free_offset

    o = ((cl.get("confirmation") or {}).get("below") or {}).get("orbit")
    if not o:
        return {"status": "not checked", "note": "an asymptote, and no orbit shot below it", "evidence_top": top}
    s_far = min(FAR * float(cl["sigma"]), FAR_MAX)
    p_lo = float(cl["confirmation"]["below"]["p2"])
    M = int(w["M"])
    w_far = _walk_up(PeriodMap(sim, {**problem.params, problem.param2: p_lo}, "sigma", problem.theta), M,
                     norm_seed(o["point"], float(o["sigma"]), problem.theta), float(o["sigma"]), s_far)
    if w_far is None:
        return {"status": "not checked", "note": f"an asymptote, and its orbit not followed to sigma = {s_far:.3g}",
                "evidence_top": top}
    far = {"sigma": s_far, "point": (w_far + wall_free_offset(s_far, problem.theta)).tolist()}
    res = bisect_closing(sim, problem.params, problem.param2, problem.theta, M, 1, p_lo, far,
                         float(cl["closes"]) * (1.0 + 1e-3), float(problem.values[-1]), 0.02)
    res["from"] = {"p2": p_lo, "sigma": s_far, "route": "shooting below the candidate closing, scaled to large sigma"}
    res["evidence_top"] = {k: top[k] for k in ("p2", "sigma", "route")}
    if res["status"] != "bisected":
        return res
    near = {"p2": float(cl["closes"]), "sigma": float(cl["sigma"]),
            "kind": "asymptote of the lower edge running off to sigma -> infinity"}
    res["feature"] = near
    res["status"] = "resolved" if abs(near["p2"] - res["p2"]) <= FEATURE_TOL * res["p2"] else "unresolved"
    return res


def _walk_up(pmap: Any, M: int, shape: np.ndarray, s_from: float, s_to: float) -> np.ndarray | None:
    """The window's orbit followed from ``s_from`` to ``s_to`` (w at ``s_to``) in steps of at most 3x in
    sigma, each from the last orbit's shape (which settles like 1 / sigma: each step's guess is off by
    a bounded amount, within Newton's damped steps)."""
    n = max(1, int(math.ceil(math.log(max(s_to / s_from, 1.0)) / math.log(3.0))))
    for s in np.geomspace(s_from, s_to, n + 1)[1:]:
        got = _orbit(pmap, shape * (1.0 + s), float(s), M, 1)
        if got is None:
            return None
        shape = got[0] / (1.0 + s)
    return shape * (1.0 + s_to)


def _agreeing(cl: Mapping[str, Any], r: Mapping[str, Any], reported: float | None) -> list[str]:
    """The routes that agree on the closing, in words."""
    pb = r["p2"]
    out = [f"one-parameter route: the smallest spectral radius of the branch over sigma reaches 1 at {pb:.7g} "
           f"(bisection in ln p2 between {r['bracket'][0]:.9g} and {r['bracket'][1]:.9g}, from the stable orbit of the "
           f"{r['from']['route']} at {r['from']['p2']:.6g})"]
    f = r.get("feature")
    if f is not None and abs(f["p2"] - pb) <= FEATURE_TOL * pb:
        out.append(f"edge curves: {f['kind']} at {f['p2']:.7g} (sigma = {f['sigma']:.5g}; {abs(f['p2'] / pb - 1):.1e} "
                   "from it)")
    if reported is not None and abs(reported - pb) <= FEATURE_TOL * pb and cl.get("confirmation"):
        out.append(f"shooting on either side of the candidate at {reported:.7g} ({cl.get('kind')})")
    out.append(f"stable orbits of the window found by the run's routes up to {r['evidence_top']['p2']:.6g} "
               f"({r['evidence_top']['route']}), below it")
    return out


def reconcile_closings(source: Any, problem: Any, out: dict[str, Any], per_value: Sequence[Mapping[str, Any]]) -> bool:
    """Hold each window's closing (chart.json ``closes[M]``) against every route of the run: the
    one-parameter route bisected from the highest stable orbit any route found, checked against the
    edge curves' boundary features.  Each ``closes[M]`` gets ``routes`` (``status``: resolved,
    unresolved, open, not checked, failed; ``agree``: the routes that agree, in words); a closing
    below a stable orbit of the run, or off the one-parameter route's, is replaced (the candidate's
    kept in ``superseded``).  Returns whether any closing changed."""
    from ...fmu.simulator import FmuSimulator

    sim = FmuSimulator(source, instance_name="chart-closing-routes")
    found = (out.get("contradictions") or {}).get("found", [])
    changed = False
    for key, cl in out["closes"].items():
        mine = [w for w in out["windows"] if str(w["M"]) == key and w.get("impacts", 1) == 1]
        if not mine:
            continue
        reported = cl.get("closes")
        try:
            ev = stable_evidence(int(key), cl, per_value, found)
            r = _reconcile(sim, problem, mine[0], cl, ev, boundary_features(mine[0]))
        except Exception as exc:  # noqa: BLE001  (one window's failure is a line of the report)
            cl["routes"] = {"status": "failed", "note": f"{type(exc).__name__}: {exc}"}
            continue
        cl["routes"] = r
        if r["status"] in ("resolved", "unresolved"):
            r["agree"] = _agreeing(cl, r, reported)
            if reported is None or abs(reported - r["p2"]) > FEATURE_TOL * r["p2"]:
                changed = True
                cl["superseded"] = {k: cl.get(k) for k in ("closes", "sigma", "how", "kind")}
                cl["confirmation"] = None
                cl.update({"closes": r["p2"], "sigma": r["sigma"], "kind": "one-parameter route",
                           "how": "the smallest spectral radius along the window's branch over sigma reaches 1"
                           + ("" if r["status"] == "resolved" else " (unresolved: no boundary feature of the edge "
                              "curves there)"),
                           "note": None if reported is None else
                           f"the candidate {reported:.7g} ({cl['superseded']['kind']}) stood below a stable orbit of "
                           f"the run or off the one-parameter route; superseded"})
        elif r["status"] == "open" and reported is not None:
            changed = True
            cl["superseded"] = {k: cl.get(k) for k in ("closes", "sigma", "how", "kind")}
            cl.update({"closes": None, "sigma": None, "how": None, "confirmation": None,
                       "note": f"stable along sigma up to the range's end (one-parameter route); the candidate "
                       f"{reported:.7g} superseded"})
        elif reported is not None and r.get("evidence_top") and reported < r["evidence_top"]["p2"]:
            changed = True  # no number to put in its place, but this one stands below a stable orbit
            cl["superseded"] = {k: cl.get(k) for k in ("closes", "sigma", "how", "kind")}
            cl.update({"closes": None, "sigma": None, "how": None, "confirmation": None,
                       "note": f"unresolved: the candidate {reported:.7g} stands below a stable orbit of the run at "
                       f"{r['evidence_top']['p2']:.6g} ({r['evidence_top']['route']}); {r.get('note') or r['status']}"})
    return changed


def closing_route_lines(closes: Mapping[str, Any], param2: str) -> list[str]:
    """report.md's top: per window, the closing and the routes that agree on it."""
    from .wall_free import row_label

    lines = ["## Where each window closes, and the routes that agree", ""]
    for key, cl in closes.items():
        r = cl.get("routes")
        if r is None:
            continue
        head = (f"- M = {row_label(key)}: " + (f"closes at {param2} = {cl['closes']:.7g}" if cl.get("closes") is not None
                                               else "no closing in the range"))
        st = r.get("status")
        if st in ("resolved", "unresolved"):
            f = r.get("feature")
            extra = "" if st == "resolved" else (
                f" -- **unresolved**: one-parameter route {r['p2']:.7g}, nearest boundary feature "
                + ("none" if f is None else f"{f['kind']} at {f['p2']:.7g}"))
            lines.append(head + extra + ". Agreeing: " + "; ".join(r.get("agree", [])) + ".")
        else:
            lines.append(head + f" ({st}: {r.get('note') or ''}"
                         + (f"; one-parameter route open up to {r['p2']:.6g}" if st == "open" else "") + ").")
        if cl.get("superseded") and cl["superseded"].get("closes") is not None:
            lines.append(f"  (the edge curves' candidate confirmed by shooting, {cl['superseded']['closes']:.7g}, "
                         "is superseded)")
    return lines + [""] if len(lines) > 2 else []
