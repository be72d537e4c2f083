"""Where ``chart``'s two routes disagree, and which one is right: contradictions are results.

The chart measures each window twice: the continuation of its edges in (sigma, p2) from the first
value of p2 (:mod:`.chart_curves`), and per-value brute-force scans (:func:`.chart.chart_value_task`).
At each scanned value and for each window (period M with one impact, and the wall-free orbit of
:mod:`.chart_wall_free`):

* **presence**: the continuation says the window is there where both continued edges exist at that
  p2 (interpolated on the curves; an edge that was open at the start stays open) and p2 lies before
  the window's closing; the scans say so where they found it.  Only windows overlapping the scanned
  sigma grid count (the scans cannot see beyond it).  Where the two disagree, direct Newton
  shooting at that value decides (:func:`search_orbit`): a stable period-M orbit with the window's
  impacts on a sigma grid across the interval the present route gives, started from the nearest
  known orbit points (the continued curves' points at the nearest p2, the scans' own states).  Found:
  the route that saw the window is right; not found: the other, with the search's extent recorded.
* **edges**: where both see it, each edge pair differing by more than the tolerance (twice the
  scans' tolerance, at least 1e-3 x |sigma|, plus the chord error of the continued edge, which is
  read between two points of its curve: :mod:`.curve_interpolation`) is shot at the midpoint sigma between the two: a stable orbit with the window's
  contacts there says the route with the wider window is right, none says the narrower one.

:func:`contradictions` returns chart.json's ``contradictions``; :func:`contradiction_lines` the
report's first section; :func:`scan_seeds` the scans' states the shooting starts from.
"""
from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np

from ...config.defaults import WALLS
from .wall_free import WALL_FREE, _stretch_at, continued_intervals, why_not_continued, window_key_label
from .curve_interpolation import chord_error

__all__ = ["scan_seeds", "search_orbit", "contradictions", "contradiction_lines", "cross_checks", "count_line", "EDGE_REL"]

#: the smallest relative edge difference called a contradiction (the continued edge is linear
#: interpolation between points of its curve)
EDGE_REL = 1e-3
SEARCH_SIGMAS = 9


def scan_seeds(grid: np.ndarray, ds: Any, M_max: int, keep: int = 12) -> list[dict[str, Any]]:
    """The scans' states per family (M, impacts): ``{"M", "impacts", "track": [[sigma, u, v], ...]}``
    (at most ``keep`` states, evenly thinned): where the shooting that settles a contradiction starts."""
    from ..windows.ode_windows import families_from_scans

    out = []
    for f in families_from_scans(np.asarray(grid, float), ds, M_max, bool(grid[0] > 0)):
        tr = f.track[:: max(1, math.ceil(len(f.track) / keep))]
        out.append({"M": f.M, "impacts": f.impacts, "track": [[float(s), float(z[0]), float(z[1])] for s, z in tr]})
    return out


def _minimal(points: np.ndarray, M: int) -> bool:
    scale = max(1e-12, float(np.max(np.abs(points))))
    return not any(M % d == 0 and np.max(np.abs(np.roll(points, -d, axis=0) - points)) <= 1e-6 * scale
                   for d in range(1, M))


def search_orbit(pmap: Any, M: int, impacts: int, sigmas: Sequence[float],
                 starts: Sequence[tuple[float, Sequence[float], str]], transient: int = 120) -> dict[str, Any]:
    """A stable period-M orbit with ``impacts`` wall entries per M periods at one of ``sigmas``.

    From each start (sigma, absolute state (u, v), where from), Newton (:func:`refine_orbit`, residual
    1e-10 x (1 + |sigma|)) walks to the nearest target in four steps, then across the targets in order
    of distance, each solve started from the last converged orbit.  Newton from a point near a fold
    may land on the unstable partner, so where the walks find nothing, each start is also iterated
    ``transient`` periods at each target (the stable orbit attracts) before Newton.  Returns the
    evidence: ``found``, and ``sigma``, ``residual``, ``multipliers``, ``contacts``, ``start`` when
    found; else the search's ``range``, ``sigmas``, ``starts``, ``newton_solves``, ``tol``."""
    targets = [float(s) for s in sigmas]
    n = [0]
    for s0, z0, where in starts:
        w = np.asarray(z0, float) - pmap.offset(s0)
        order = sorted(targets, key=lambda t: abs(t - s0))
        for s in list(np.linspace(s0, order[0], 5)[1:-1]) + order:
            w, hit = _solve(pmap, w, s, M, impacts, n, s in targets)
            if hit is not None:
                return {**hit, "start": {"sigma": float(s0), "from": where}}
    for s0, z0, where in starts:
        for s in targets:
            z = np.asarray(z0, float) - pmap.offset(s0) + pmap.offset(s)
            if int(pmap.params.get("wall", WALLS["compliant"])) == WALLS["rigid"] and z[0] > float(pmap.params.get("u_wall", 0.0)):
                continue  # inside a rigid wall: not a state
            pts, _ = pmap.run(s, z, transient)  # one run of the flow: onto the attractor
            _, hit = _solve(pmap, pts[-1] - pmap.offset(s), s, M, impacts, n, True)
            if hit is not None:
                return {**hit, "start": {"sigma": float(s0), "from": f"{where}, iterated {transient} periods"}}
    return {"found": False, "range": [min(targets), max(targets)], "sigmas": len(targets), "starts": len(starts),
            "newton_solves": n[0], "iterated": transient, "tol": "1e-10 x (1 + |sigma|) in max|F^M(w) - w|"}


def _solve(pmap: Any, w: np.ndarray, s: float, M: int, impacts: int, n: list[int],
           target: bool) -> tuple[np.ndarray, dict[str, Any] | None]:
    """Newton at ``s`` from ``w``: (the converged w, or ``w`` itself; the evidence when it is the
    stable orbit sought at a target)."""
    from ...dynamics.maps.periodic_map import refine_orbit

    if not np.all(np.isfinite(w)):
        return w, None
    tol = 1e-10 * (1.0 + abs(s))
    w_new, ev, ok, res = refine_orbit(pmap, w, s, M, tol=tol)
    n[0] += 1
    if not ok:
        return w, None
    mult = np.linalg.eigvals(ev.J)
    if target and int(ev.contacts.sum()) == impacts and bool(np.all(np.abs(mult) < 1.0)) and _minimal(ev.points, M):
        return w_new, {"found": True, "sigma": s, "point": ev.points[0].tolist(), "residual": res, "tol": tol,
                       "contacts": ev.contacts.tolist(),
                       "multipliers": [[float(m.real), float(m.imag)] for m in mult], "newton_solves": n[0]}
    return w_new, None


def _starts(w: Mapping[str, Any] | None, seeds: Sequence[Mapping[str, Any]], M: int, impacts: int, v: float,
            sigma_ref: float, side: str | None = None, n: int = 3) -> list[tuple[float, list[float], str]]:
    """Known orbit points nearest (v, sigma_ref): the continued curves' points at the nearest p2
    (one side only with ``side``), the scans' states of the same (M, impacts) nearest sigma_ref."""
    out: list[tuple[float, list[float], str]] = []
    if w is not None:
        for sd in (side,) if side else ("lower", "upper"):
            c = (w.get("curves") or {}).get(sd)
            if not c or "failed" in c or not c.get("p2"):
                continue
            i = int(np.argmin([abs(math.log(p / v)) if p > 0 and v > 0 else abs(p - v) for p in c["p2"]]))
            out.append((float(c["sigma"][i]), c["points"][i], f"continued {sd} {c['kind']} edge at p2 = {c['p2'][i]:.6g}"))
        if w.get("impacts", 1) == 0:
            out.append((float(w["seed_sigma"]), w["seed"], "the wall-free point"))
    tr = [t for s in seeds if s["M"] == M and s["impacts"] == impacts for t in s["track"]]
    for t in sorted(tr, key=lambda t: abs(t[0] - sigma_ref))[:n]:
        out.append((t[0], t[1:], f"scan state at sigma = {t[0]:.6g}"))
    return out


def _grid_interval(lo: float | None, hi: float | None, g0: float, g1: float) -> list[float]:
    """Interior sigma values of [lo, hi] within the scanned grid [g0, g1] (an open end: the grid's);
    the window's own interval where it lies beyond the grid."""
    a = g0 if lo is None else max(lo, g0)
    b = g1 if hi is None else min(hi, g1)
    if b <= a:
        a, b = (g0 if lo is None else lo), (g1 if hi is None else hi)
    between = np.geomspace if a > 0 else np.linspace  # as the scans' grid: geometric above grazing
    return list(between(a, b, SEARCH_SIGMAS + 2)[1:-1])


def _scan_windows(res: Mapping[str, Any], M: int, impacts: int) -> list[dict[str, Any]]:
    return [e for e in res["all"] if e["M"] == M and e["impacts"] == impacts and e["resolved"]]


def _in_grid(lo: float | None, hi: float | None, g0: float, g1: float) -> bool:
    return (lo is None or lo < g1) and (hi is None or hi > g0)


def _presence(sim: Any, problem: Any, v: float, key: str, cont: list, scans: list,
              seeds: list, windows: Sequence[Mapping[str, Any]], closes: Mapping[str, Any] | None) -> dict[str, Any]:
    """A presence contradiction at ``v``, settled by :func:`search_orbit`."""
    from ...dynamics.maps.periodic_map import PeriodMap

    g0, g1 = float(problem.sigma_grid[0]), float(problem.sigma_grid[-1])
    M, impacts = (1, 0) if key == WALL_FREE else (int(key), 1)
    if cont:
        c = cont[0]
        sigmas, saw = _grid_interval(c["lo"], c["hi"], g0, g1), "continuation"
        w, ref = c["window"], 0.5 * (sigmas[0] + sigmas[-1])
    else:
        e = scans[0]
        sigmas, saw, w = _grid_interval(e["lo"], e["hi"], g0, g1), "scans", None
        ref = e["seed_sigma"]
    pmap = PeriodMap(sim, {**problem.params, problem.param2: v}, "sigma", problem.theta)
    ev = search_orbit(pmap, M, impacts, sigmas, _starts(w, seeds, M, impacts, v, ref))
    right = saw if ev["found"] else ("scans" if saw == "continuation" else "continuation")
    return {"p2": v, "window": key, "label": window_key_label(key), "type": "presence",
            "continuation": bool(cont), "scans": bool(scans), "right": right,
            "why": (why_not_continued(windows, M, impacts, v, closes) if not cont else
                    "the scans saw no such attractor at this value"),
            "continued": None if not cont else [cont[0]["lo"], cont[0]["hi"]],
            "scanned": None if not scans else [scans[0]["lo"], scans[0]["hi"]], "evidence": ev}


def _edges(sim: Any, problem: Any, v: float, key: str, c: Mapping[str, Any], e: Mapping[str, Any],
           seeds: list) -> list[dict[str, Any]]:
    """Edge contradictions of one matched (continued, scanned) pair at ``v``."""
    from ...dynamics.maps.periodic_map import PeriodMap

    M, impacts = (1, 0) if key == WALL_FREE else (int(key), 1)
    out = []
    for side, s_c, s_s, j in (("lower", c["lo"], e["lo"], 0), ("upper", c["hi"], e["hi"], 1)):
        if s_c is None or s_s is None:
            continue
        # the continued edge is read on a chord of its curve: the chord's own error widens the tolerance
        chord = chord_error(_stretch_at(c["window"], v)[1].get(side), v, v > 0)
        tol = max(2.0 * float(e.get("xtol") or 0.0), EDGE_REL * abs(s_c), 1e-9) + chord
        if abs(s_s - s_c) <= tol:
            continue
        mid = 0.5 * (s_s + s_c)
        pmap = PeriodMap(sim, {**problem.params, problem.param2: v}, "sigma", problem.theta)
        ev = search_orbit(pmap, M, impacts, [mid], _starts(c["window"], seeds, M, impacts, v, mid, side))
        wider = ("scans" if s_s < s_c else "continuation") if side == "lower" else \
            ("scans" if s_s > s_c else "continuation")
        narrower = "continuation" if wider == "scans" else "scans"
        out.append({"p2": v, "window": key, "label": window_key_label(key), "type": "edge", "side": side,
                    "continued_edge": s_c, "scan_edge": s_s, "scan_kind": e["kinds"][j], "tolerance": tol,
                    "chord_error": chord,
                    "right": wider if ev["found"] else narrower, "evidence": ev})
    return out


def contradictions(source: Any, problem: Any, windows: Sequence[Mapping[str, Any]],
                   per_value: Sequence[Mapping[str, Any]], closes: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Every disagreement between the continuation and the scans, each settled by shooting.

    ``windows``: the continued windows (the wall-free one included, ``impacts`` 0); ``per_value``:
    the scans' results (``all``, ``seeds``); ``closes``: chart.json's, where each window closes.  Returns ``{"found": [...], "compared": {...}}``."""
    from ...fmu.simulator import FmuSimulator

    sim = FmuSimulator(source, instance_name="chart-contradictions")
    g0, g1 = float(problem.sigma_grid[0]), float(problem.sigma_grid[-1])
    keys = [str(M) for M in range(1, problem.M_max + 1)] + ([WALL_FREE] if g0 < 0 else [])
    found: list[dict[str, Any]] = []
    n_pres = n_edge = 0
    for res in per_value:
        v = float(res["value"])
        cont_all = continued_intervals(windows, v, closes, g1, g0)
        for key in keys:
            M, impacts = (1, 0) if key == WALL_FREE else (int(key), 1)
            cont = [c for c in cont_all if c["M"] == M and c["impacts"] == impacts and _in_grid(c["lo"], c["hi"], g0, g1)]
            scans = _scan_windows(res, M, impacts)
            n_pres += 1
            if bool(cont) != bool(scans):
                found.append(_presence(sim, problem, v, key, cont, scans, res.get("seeds", []), windows, closes))
                continue
            for c in cont:  # each continued window against the scanned window overlapping it most
                e = max(scans, key=lambda e: _overlap_len(c, e), default=None)
                if e is not None and _overlap_len(c, e) > 0:
                    n_edge += 2
                    found += _edges(sim, problem, v, key, c, e, res.get("seeds", []))
    return {"found": found, "compared": {"values": len(per_value), "windows": keys, "presence": n_pres,
                                         "edges": n_edge, "edge_rel": EDGE_REL}}


def _overlap_len(c: Mapping[str, Any], e: Mapping[str, Any]) -> float:
    lo = max(-1e300 if c["lo"] is None else c["lo"], -1e300 if e["lo"] is None else e["lo"])
    hi = min(1e300 if c["hi"] is None else c["hi"], 1e300 if e["hi"] is None else e["hi"])
    return hi - lo


def _fmt(x: float | None) -> str:
    return "open" if x is None else f"{x:.7g}"


def _evidence_text(ev: Mapping[str, Any]) -> str:
    if ev["found"]:
        mult = ", ".join(f"{abs(complex(*m)):.4g}" for m in ev["multipliers"])
        return (f"stable orbit at sigma = {ev['sigma']:.7g} (residual {ev['residual']:.1e}, |multipliers| {mult}, "
                f"contacts per period {ev['contacts']}; from the {ev['start']['from']})")
    where = (f"at sigma = {ev['range'][0]:.7g}" if ev["sigmas"] == 1 else
             f"at {ev['sigmas']} sigma in {ev['range'][0]:.6g} .. {ev['range'][1]:.6g}")
    return (f"no stable orbit with its contacts {where}: {ev['starts']} starts, each walked by Newton and iterated "
            f"{ev['iterated']} periods, {ev['newton_solves']} Newton solves to {ev['tol']}")


def contradiction_lines(con: Mapping[str, Any], param2: str) -> list[str]:
    """report.md's first section: every contradiction with its resolution, or 'none' with what was compared."""
    cmp_ = con.get("compared")
    if not cmp_:
        return []  # a chart.json from before the check
    what = (f"presence of {len(cmp_['windows'])} windows ({', '.join(window_key_label(k) for k in cmp_['windows'])}) "
            f"at {cmp_['values']} values of {param2} ({cmp_['presence']} comparisons) and {cmp_['edges']} edges "
            f"(tolerance: 2 x the scans' tolerance, at least {cmp_['edge_rel']:g} x |sigma|, plus the continued edge's "
            "chord error: it is read between two points of its curve)")
    lines = ["## Contradictions between the continuation and the per-value scans", ""]
    if not con["found"]:
        return lines + [f"None: compared the {what}; the two routes agree.", ""]
    lines += [f"{len(con['found'])} found, comparing the {what}; each settled by direct Newton shooting at that value "
              "(`contradictions` in chart.json):", ""]
    for c in con["found"]:
        if c["type"] == "presence":
            said = ("the continuation has it " + f"[{_fmt(c['continued'][0])}, {_fmt(c['continued'][1])}], the scans do not"
                    if c["continuation"] else
                    "the scans found it " + f"[{_fmt(c['scanned'][0])}, {_fmt(c['scanned'][1])}], the continuation does "
                    f"not ({c['why']})")
        else:
            said = (f"{c['side']} edge: continued {c['continued_edge']:.7g} (interpolated between its curve's points), scans {c['scan_edge']:.7g} "
                    f"({c['scan_kind']}), tolerance {c['tolerance']:.2g}")
        lines.append(f"- {param2} = {c['p2']:.6g}, {c['label']}: {said}. **{c['right']} right**: "
                     f"{_evidence_text(c['evidence'])}.")
    return lines + [""]


def cross_checks(source: Any, problem: Any, out: dict[str, Any], per_value: Sequence[Mapping[str, Any]],
                 search: tuple[float, float]) -> None:
    """:func:`harness.analysis.chart.run.run_chart`'s second routes, into ``out``: the wall-free window
    (``wall_free``; ``scans`` and ``closes`` under ``"1/0"``), the ``contradictions`` between the
    continuation and the scans, each settled by shooting, and the ``coexistence`` per value
    (``search``: the scans' shooting range, where an open window is taken to end)."""
    from .wall_free import coexistence_by_value, wall_free_scans, wall_free_window

    wf = wall_free_window(source, problem.params, problem.param2, [float(v) for v in problem.values],
                          problem.sigma_grid, problem.theta)
    out["wall_free"] = wf
    windows = list(out["windows"]) + ([wf] if wf is not None else [])
    if float(problem.sigma_grid[0]) < 0:
        out["scans"][WALL_FREE] = wall_free_scans(problem.values, per_value)
        out["closes"][WALL_FREE] = (
            {**wf["closing"], "window_at_start": [None, {"kind": "graze", "sigma": wf["upper"]["sigma"]}],
             "impacts": 0, "label": wf["label"]} if wf is not None else
            {"closes": None, "sigma": None, "how": None, "searched": wf_searched(problem), "impacts": 0,
             "label": window_key_label(WALL_FREE),
             "note": "no stable wall-free orbit found by Newton from the wall-free point at the first value"})
    out["contradictions"] = contradictions(source, problem, windows, per_value, out["closes"])
    out["coexistence"] = coexistence_by_value([float(v) for v in problem.values], per_value, windows, search,
                                              out["closes"])


def wf_searched(problem: Any) -> list[float]:
    return [float(problem.values[0]), float(problem.values[-1])]


def count_line(con: Mapping[str, Any]) -> str:
    """stdout's one line: how many contradictions, and which route each settled for."""
    f = con["found"]
    if not f:
        return (f"contradictions between the continuation and the scans: none ({con['compared']['presence']} presences, "
                f"{con['compared']['edges']} edges compared)")
    right = {r: sum(c["right"] == r for c in f) for r in ("continuation", "scans")}
    return (f"contradictions between the continuation and the scans: {len(f)} (settled by shooting: continuation right "
            f"in {right['continuation']}, scans right in {right['scans']}; report.md, top)")
