"""The wall-free orbit as a window of ``chart``, and the attractors that coexist at each value.

Below sigma = 0 the wall-free orbit (4), u = (1 + sigma) cos(2 pi t) - 1, misses the wall by
-sigma: a stable orbit with no impact (period 1, 0 impacts; |multipliers| = exp(-nu/2)) that grazes
at sigma = 0 (docs/theory.md section 10, "Below grazing").  ``windows`` lists it as a window like
any other; here the chart does too, for a ``--sigma-range`` reaching below 0:

* :func:`wall_free_window`: at each value of the second parameter the orbit is found by Newton
  on the FMU's period map (from the wall-free point itself) at two sigma below 0, and its graze is
  located on its defining equation: the largest u of its free passage (:meth:`PeriodMap.gap`)
  reaches the wall.  That largest u is linear in sigma, so the zero of the line through the two
  orbits' gaps is the graze, with the two orbits' difference from that line as its error.  The
  window's lower edge is the range's end (stable at every sigma below 0 where nu > 0: its
  multipliers are measured at each value).
* :func:`wall_free_scans`: the per-value scans' wall-free windows, in the rows of ``scans``.
* :func:`coexistence_by_value`: per value of the second parameter, the sigma intervals where two
  or more attractors coexist, from the scans' windows and from the continued edges
  (:func:`harness.analysis.windows.summary.coexistence` on each).

Its key in ``closes`` and ``scans`` is ``"1/0"`` (period 1, 0 impacts): never ``"1"``, the period-1
window with one impact.
"""
from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

__all__ = ["WALL_FREE", "WALL_FREE_LABEL", "window_key_label", "row_label", "coexistence_lines", "draw_wall_free", "wall_free_window", "wall_free_scans",
           "closing_of", "continued_intervals", "why_not_continued", "coexistence_by_value"]

#: key of the wall-free window in chart.json's ``closes``, ``scans``, ``contradictions``
WALL_FREE = "1/0"
WALL_FREE_LABEL = "wall-free (period 1, no impact)"


def window_key_label(key: str) -> str:
    """'1/0' -> the wall-free label; '2' or '2/1' -> 'period 2, 1 impact'."""
    if key == WALL_FREE:
        return WALL_FREE_LABEL
    M = key.split("/")[0]
    return f"period {M}, 1 impact"


def _wall_free_orbit(pmap: Any, sigma: float, tol: float) -> dict[str, Any]:
    """Newton on the period-1 map from the wall-free point itself (w = 0) at ``sigma`` < 0."""
    from ...dynamics.maps.periodic_map import refine_orbit

    w, ev, ok, res = refine_orbit(pmap, np.zeros(2), sigma, 1, tol=tol)
    ok = bool(ok and int(ev.contacts.sum()) == 0)
    mult = np.linalg.eigvals(ev.J) if ok else np.array([np.nan, np.nan])
    gap = pmap.gap(ev.points, ev.contacts, sigma) if ok else float("nan")
    return {"ok": ok, "sigma": sigma, "point": (w + pmap.offset(sigma)).tolist(), "residual": res, "gap": gap,
            "multipliers": [[float(m.real), float(m.imag)] for m in mult],
            "stable": bool(ok and np.all(np.abs(mult) < 1.0))}


def wall_free_window(source: Any, params: Mapping[str, Any], param2: str, values: Sequence[float],
                     grid: np.ndarray, theta: float = 0.5) -> dict[str, Any] | None:
    """The wall-free window over the second parameter (None when the grid stays above grazing).

    Returns a window like :func:`harness.analysis.chart.edge_curves.windows_at`'s, ``impacts`` 0, its
    upper edge a "graze" curve over ``values`` (``sigma``: where the largest u of the orbit's
    passage reaches the wall; ``error``: the two orbits' gaps from the line through them) and its
    lower edge None (the range), with ``present`` per value (the orbit found and stable)."""
    from ...dynamics.maps.periodic_map import PeriodMap
    from ...fmu.simulator import FmuSimulator

    g0 = float(grid[0])
    if g0 >= 0:
        return None
    sim = FmuSimulator(source, instance_name="chart-wall-free")
    s1, s2 = 0.5 * g0, 0.25 * g0  # two sigma below grazing, inside the scanned grid
    rows: dict[str, list] = {"p2": [], "sigma": [], "points": [], "multipliers": [], "error": [], "residual": []}
    present = []
    for v in values:
        pmap = PeriodMap(sim, {**params, param2: float(v)}, "sigma", theta)
        a, b = (_wall_free_orbit(pmap, s, 1e-11) for s in (s1, s2))
        ok = a["stable"] and b["stable"] and np.isfinite(a["gap"]) and np.isfinite(b["gap"]) and a["gap"] != b["gap"]
        present.append(bool(ok))
        if not ok:
            continue
        # the gap (wall minus largest u) is linear in sigma on the wall-free orbit: its zero
        sg = s2 - b["gap"] * (s2 - s1) / (b["gap"] - a["gap"])
        rows["p2"].append(float(v))
        rows["sigma"].append(float(sg))
        rows["points"].append(b["point"])
        rows["multipliers"].append(b["multipliers"])
        rows["error"].append(float(abs(a["gap"] + s1) + abs(b["gap"] + s2)))  # exact theory: gap = -sigma
        rows["residual"].append(max(a["residual"], b["residual"]))
    if not present or not present[0]:
        return None
    absent = [float(v) for v, p in zip(values, present) if not p]
    end_note = ("the wall-free orbit is stable with no impact at every value (its graze located at each)" if not absent
                else f"no stable wall-free orbit at {param2} = {absent[0]:g}")
    upper = {"kind": "graze", "impacts": 0, **rows, "turns": [],
             "end": {"reason": "range" if not absent else "lost", "p2": rows["p2"][-1], "sigma": rows["sigma"][-1],
                     "note": end_note},
             "method": f"Newton on the period-1 map from the wall-free point at sigma = {s1:.4g} and {s2:.4g}; the "
                       "graze where the largest u of the orbit's passage reaches the wall (line through the two gaps)"}
    i_abs = next((i for i, p in enumerate(present) if not p), None)
    closing = {"closes": None if i_abs is None else float(values[i_abs]), "sigma": None if i_abs is None else 0.0,
               "how": None if i_abs is None else f"no stable wall-free orbit found at {param2} = {values[i_abs]:g} "
               f"(Newton from the wall-free point at sigma = {s1:.4g}, {s2:.4g})",
               "searched": [float(values[0]), float(values[-1])]}
    if i_abs is None:
        closing["note"] = ("the wall-free orbit exists at every sigma < 0 and grazes at sigma = 0 (located at each value "
                           f"of {param2}: at most {max(abs(x) for x in rows['sigma']):.2g} from 0); stable at every value "
                           f"(largest multiplier modulus {max(abs(complex(*m)) for ms in rows['multipliers'] for m in ms):.4g})")
    first = {"kind": "graze", "sigma": rows["sigma"][0], "point": rows["points"][0], "bracket": rows["error"][0],
             "multipliers": rows["multipliers"][0], "note": "the wall-free orbit's graze"}
    return {"M": 1, "impacts": 0, "label": WALL_FREE_LABEL, "seed_sigma": s2, "seed": rows["points"][0],
            "lower": None, "upper": first, "found_by": ["wall-free point (4)"],
            "curves": {"lower": None, "upper": upper}, "closing": closing, "present": present}


def wall_free_scans(values: Sequence[float], per_value: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """The scans' wall-free windows (period 1, 0 impacts) per value, in ``scans``' row format."""
    rows: dict[str, list] = {"value": [], "lower": [], "upper": [], "kind_lower": [], "kind_upper": [], "beta": [],
                             "v_c": [], "multipliers_inside": []}
    present = []
    for res in per_value:
        cands = [e for e in res["all"] if e["M"] == 1 and e["impacts"] == 0 and e["resolved"]]
        present.append(bool(cands))
        if cands:
            e = cands[0]
            rows["value"].append(res["value"])
            for key, val in (("lower", e["lo"]), ("upper", e["hi"]), ("kind_lower", e["kinds"][0]),
                             ("kind_upper", e["kinds"][1]), ("beta", None), ("v_c", None),
                             ("multipliers_inside", e.get("multipliers_inside"))):
                rows[key].append(val)
    v = [float(x) for x in values]
    # where the window is first lost after the first value: bracketed by the last value with it
    i = next((i for i, p in enumerate(present) if not p), None) if present and present[0] else None
    return {**rows, "impacts": 0, "label": WALL_FREE_LABEL, "searched": [v[0], v[-1]],
            "present_at": [x for x, p in zip(v, present) if p],
            "closes": None if i is None else v[i], "bracket": None if i is None else [v[i - 1], v[i]]}


def closing_of(w: Mapping[str, Any], windows: Sequence[Mapping[str, Any]],
               closes: Mapping[str, Any] | None) -> float | None:
    """Where the window closes: chart.json's ``closes[M]`` for the window it reports (the first of its
    M, with one impact), else the window's own ``closing``."""
    first = next((x for x in windows if x["M"] == w["M"] and x.get("impacts", 1) == 1), None)
    if closes is not None and w is first and str(w["M"]) in closes:
        return closes[str(w["M"])].get("closes")
    return w["closing"]["closes"]


def continued_intervals(windows: Sequence[Mapping[str, Any]], v: float,
                        closes: Mapping[str, Any] | None = None,
                        sigma_top: float | None = None, sigma_bottom: float | None = None) -> list[dict[str, Any]]:
    """The continued windows at ``v``: ``{"M", "impacts", "lo", "hi", "window"}`` (an edge None: open,
    the branch left the range stable) for each window whose edges exist there, before its closing
    (:func:`closing_of`).  A window whose edge curve does not reach ``v`` (failed, ended, turned) is
    not there by this route, except an upper edge whose curve left the range upward, above
    ``sigma_top``, before ``v``: the window is open above there (Figure 9's period 2 past
    Gamma = 1102, where its graze edge runs off to large sigma); likewise a lower edge whose curve
    left the range downward, below ``sigma_bottom``: open below (a fold below grazing reaching
    further down than the chart's sigma range as Omega grows, at a resonant grazing)."""
    out = []
    for w in windows:
        closes_at = closing_of(w, windows, closes)
        if closes_at is not None and v >= closes_at:
            continue
        edges, curves = _stretch_at(w, v)
        ends = []
        for side in ("lower", "upper"):
            if edges[side] is None:
                ends.append(None)  # open: no edge in the range at the start, none later
                continue
            s = _edge_at_end(curves.get(side), v)
            if s is None and _left_range(curves.get(side), v, sigma_top if side == "upper" else sigma_bottom,
                                         side == "upper"):
                ends.append(None)
                continue
            ends.append(s if s is not None else "missing")
        if "missing" in ends:
            continue
        out.append({"M": w["M"], "impacts": w.get("impacts", 1), "lo": ends[0], "hi": ends[1], "window": w})
    return out


def _left_range(curve: Mapping[str, Any] | None, v: float, bound: float | None, upward: bool) -> bool:
    """The curve ran monotonically (no turning point) out of the sigma range, above ``bound``
    (``upward``) or below it, before reaching ``v``."""
    if bound is None or not curve or "failed" in curve or len(curve.get("p2", ())) < 2:
        return False
    end, p2 = curve["end"], curve["p2"]
    if end.get("reason") != "range" or (float(end["sigma"]) <= bound if upward else float(end["sigma"]) >= bound):
        return False
    if any(t.get("side") in ("max", "min") for t in curve.get("turns", [])):
        return False
    rising = p2[-1] > p2[0]
    return v > p2[-1] if rising else v < p2[-1]


def _stretch_at(w: Mapping[str, Any], v: float) -> tuple[Mapping[str, Any], Mapping[str, Any]]:
    """The window's edges and their continued curves that bound it at ``v``: those from the start,
    or, past a hand-over of its boundary (:mod:`.window_region`), the ones continued from there."""
    edges, curves = w, w.get("curves") or {}
    for h in w.get("handovers") or []:
        if v >= float(h["p2"]):
            edges, curves = h["window"], h["curves"]
    return edges, curves


def _edge_at_end(curve: Mapping[str, Any] | None, v: float) -> float | None:
    """:func:`harness.analysis.chart.edge_curves._edge_at`, and at the curve's first point where ``v``
    is its p2 to round-off (a curve starts at the start value of p2 to ~1e-12 relative, not exactly)."""
    from .edge_curves import _edge_at

    s = _edge_at(curve, v)
    if s is None and curve and "failed" not in curve and curve.get("p2"):
        if abs(curve["p2"][0] - v) <= 1e-9 * max(abs(v), 1e-300):
            return float(curve["sigma"][0])
    return s


def why_not_continued(windows: Sequence[Mapping[str, Any]], M: int, impacts: int, v: float,
                      closes: Mapping[str, Any] | None = None) -> str:
    """Why the continuation has no window (M, impacts) at ``v``, in words."""
    mine = [w for w in windows if w["M"] == M and w.get("impacts", 1) == impacts]
    if not mine:
        return "no such window at the start of the range"
    out = []
    for w in mine:
        at = closing_of(w, windows, closes)
        if at is not None and v >= at:
            out.append(f"beyond its closing at {at:.6g}")
            continue
        for side in ("lower", "upper"):
            c = w["curves"].get(side)
            if w[side] is None or _edge_at_end(c, v) is not None:
                continue
            if not c or "failed" in c:
                out.append(f"its {side} edge was not continued")
            elif c["turns"] and any(t["side"] == "max" for t in c["turns"]):
                t = next(t for t in c["turns"] if t["side"] == "max")
                out.append(f"its {side} {c['kind']} edge turns back at {t['p2']:.6g} (the boundary then hands over "
                           "to another curve)")
            else:
                out.append(f"its {side} {c['kind']} edge curve ends at {c['end']['p2']:.6g} ({c['end'].get('note')})")
    return "; ".join(out) or "its window lies outside the scanned sigma grid"


def coexistence_by_value(values: Sequence[float], per_value: Sequence[Mapping[str, Any]],
                         windows: Sequence[Mapping[str, Any]], search: tuple[float, float],
                         closes: Mapping[str, Any] | None = None) -> list[dict[str, Any]]:
    """Per value: the sigma intervals where two or more stable attractors coexist, from the scans'
    windows (every attractor they saw, shot to its edges) and from the continued edges; each row
    says which route saw it (``routes``) and the other route's interval with the same attractors."""
    from ..windows.summary import coexistence

    out = []
    for v, res in zip(values, per_value):
        scans = coexistence([e for e in res["all"] if e.get("resolved")], search)
        cont = coexistence([{**c, "resolved": True}
                            for c in continued_intervals(windows, float(v), closes, search[1], search[0])], search)
        for c in scans:
            twin = next((d for d in cont if d["keys"] == c["keys"] and _overlap(c, d)), None)
            out.append({"p2": float(v), **c, "routes": ["scans"] + (["continuation"] if twin else []),
                        "continued": None if twin is None else [twin["lo"], twin["hi"]]})
        for d in cont:
            if not any(c["keys"] == d["keys"] and _overlap(c, d) for c in scans):
                out.append({"p2": float(v), **d, "routes": ["continuation"], "continued": [d["lo"], d["hi"]]})
    return out


def _overlap(a: Mapping[str, Any], b: Mapping[str, Any]) -> bool:
    lo = max(-np.inf if a["lo"] is None else a["lo"], -np.inf if b["lo"] is None else b["lo"])
    hi = min(np.inf if a["hi"] is None else a["hi"], np.inf if b["hi"] is None else b["hi"])
    return bool(lo < hi)


def row_label(key: str) -> str:
    """A key of ``closes``/``scans`` as the first cell of a report row: '2', or '1, no impact (wall-free)'."""
    return "1, no impact (wall-free)" if key == WALL_FREE else key


def coexistence_lines(rows: Sequence[Mapping[str, Any]] | None, param2: str) -> list[str]:
    """report.md's coexistence table: per value, which attractors coexist over which sigma."""
    from ..windows.summary import fmt_sigma

    if rows is None:
        return []
    lines = ["", "## Coexisting attractors per value (bistability)", ""]
    if not rows:
        return lines + [f"At no value of {param2} do two stable attractors coexist in the searched sigma range (as "
                        "far as the scans and the continued edges saw)."]
    lines += [f"| {param2} | sigma from | to | attractors | seen by |", "|---|---|---|---|---|"]
    for c in rows:
        by = " and ".join(c["routes"])
        if c["routes"] == ["scans", "continuation"] and c["continued"] is not None:
            by += f" (continued: {fmt_sigma(c['continued'][0], 'below')} .. {fmt_sigma(c['continued'][1], 'above')})"
        lines.append(f"| {c['p2']:.6g} | {fmt_sigma(c['lo'], 'below')} | {fmt_sigma(c['hi'], 'above')} | "
                     f"{'; '.join(c['attractors'])} | {by} |")
    return lines + ["", "Overlaps of the windows (the scans': every attractor they saw, shot to its edges; the "
                    "continuation's: the continued edges at that value); which attractor a run reaches there depends on "
                    "where it starts (`impact-harness basins`)."]


def draw_wall_free(ax: Any, wf: Mapping[str, Any] | None) -> None:
    """chart.png: the wall-free orbit's graze located at each value (grey, its own legend entry)."""
    c = None if wf is None else wf["curves"]["upper"]
    if c and c["p2"]:
        ax.plot(c["p2"], c["sigma"], "--", marker="o", ms=3, color="0.3", lw=1.6,
                label=f"graze of the {WALL_FREE_LABEL} orbit (located per value)")
