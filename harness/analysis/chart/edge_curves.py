"""The windows' edges continued in two parameters, and where each window closes.

At the first value of the second parameter, the stable maximal period-M orbits (one impact per
period) are found by the ODE alone (:func:`harness.dynamics.attractors.scans.find_attractors` over the
sigma grid), each is continued in sigma both ways (:func:`harness.dynamics.continuation.continue_orbit.continue_orbit`)
and its first event on each side is the window's edge (flip, fold, NS, graze or stick; none when
the branch leaves the range stable).  Each edge is then continued in (sigma, p2): flip, fold and NS
on their extended system (:func:`harness.dynamics.curves.event_curves.continue_event`), grazes stepped along
the curve and located across it (:func:`harness.dynamics.curves.graze_curves.continue_graze`).

Where a window closes: the candidates (:func:`window_closing`), in p2:

* a turning point (maximum in p2) of an edge curve: the lower and upper edges are one curve that
  turns back (e.g. two flips joining: the smallest |multiplier| along sigma reaches 1 there);
* the grazing orbit on a graze edge losing its stability (the graze edge meets a flip or fold, a
  codimension-two point), or a smooth edge curve ending on the orbit's graze (the same point seen
  from the flip's side, located less exactly: the first is preferred when both are found);
* the lower edge leaving the charted sigma range upward (the window runs to sigma -> infinity; the
  report says so: it is an asymptote, not a meeting of two edges).

These are only candidates: :func:`harness.analysis.chart.window_region.chart_regions` confirms each by
direct shooting on both sides, and follows the window past a candidate where its boundary hands
over to another curve (the window's closing is the first confirmed one).
"""
from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np

from ...dynamics.continuation.window_branch import EDGE_KINDS, first_edge  # noqa: F401  (EDGE_KINDS: one list, there)
from ...errors import FmuError

__all__ = ["windows_at", "widened", "continue_window", "window_closing", "smooth_top", "chart_curves", "scan_check", "edge_check"]


def _edge(branch: Any) -> dict[str, Any] | None:
    """The first event of a branch that ends the stable one-impact window, as a dict."""
    e = first_edge(branch)
    if e is None:
        return None
    return {"kind": e.kind, "sigma": float(e.value), "point": [float(x) for x in e.point],
            "bracket": float(e.bracket), "multipliers": [[float(m.real), float(m.imag)] for m in e.multipliers],
            "note": e.note}


def windows_at(sim: Any, params: Mapping[str, Any], grid: np.ndarray, M_max: int, theta: float = 0.5,
               transient: int = 200, refine: int = 16) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """The stable maximal windows (M <= M_max, one impact per period) at one parameter set.

    The grid is scanned (up, down, fresh starts); between two neighbouring values whose attractors
    differ or where either has no periodic attractor (period <= M_max), ``refine`` more values are
    scanned: a window narrower than the grid's step, such as Figure 9's period 4, lies there.

    Returns (windows, search): each window ``{"M", "seed_sigma", "seed", "lower", "upper"}`` with
    the edges as dicts (None: the branch left the range stable); ``search`` what was scanned.
    """
    from ...dynamics.attractors.scans import families, find_attractors
    from ...dynamics.continuation.window_branch import continue_side

    scan = find_attractors(sim, params, grid, "sigma", M_max=M_max, theta=theta, transient=transient)
    labels = [frozenset(a.label for a in scan.at(float(v))) for v in grid]
    changes = [i for i in range(len(grid) - 1) if labels[i] != labels[i + 1] or not labels[i] or not labels[i + 1]]
    found = list(scan.attractors)
    between = np.geomspace if grid[0] > 0 else np.linspace  # an even grid where it reaches sigma <= 0
    extra = np.concatenate([between(grid[i], grid[i + 1], refine + 2)[1:-1] for i in changes]) if changes \
        else np.zeros(0)
    if refine > 0 and extra.size:
        fine = find_attractors(sim, params, extra, "sigma", M_max=M_max, theta=theta, transient=transient)
        found += fine.attractors
    lo, hi = float(grid[0]), float(grid[-1])
    windows: list[dict[str, Any]] = []
    # stable maximal orbits only (a period-2M sample near a flip can be refined onto the unstable M orbit)
    for fam in families([a for a in found if a.impacts == 1 and a.stable]):
        a = fam[len(fam) // 2]
        if any(w["M"] == a.period and _inside(a.value, w) for w in windows):
            continue  # the same window, reached again from another run of the grid
        edges = [_edge(continue_side(sim, params, a.period, a.value, a.points[0], (lo, hi), d, theta))
                 for d in (-1.0, 1.0)]
        windows.append({"M": a.period, "seed_sigma": a.value, "seed": a.points[0].tolist(),
                        "lower": edges[0], "upper": edges[1], "found_by": a.found_by})
    search = {"sigma": [lo, hi], "values": len(grid), "refined_intervals": len(changes), "refined_values": int(extra.size),
              "scans": scan.scans, "transient": scan.transient, "M_max": M_max}
    return sorted(windows, key=lambda w: (w["M"], w["seed_sigma"])), search


def widened(grid: Sequence[float]) -> tuple[float, float]:
    """The sigma interval the edges are followed over, for an even grid reaching sigma <= 0: a
    half-width beyond each end, never down to sigma = -1 (where the forcing vanishes)."""
    lo, hi = float(grid[0]), float(grid[-1])
    return max(lo - 0.5 * (hi - lo), -0.99), hi + 0.5 * (hi - lo)


def _inside(sigma: float, w: Mapping[str, Any]) -> bool:
    lo = w["lower"]["sigma"] if w["lower"] else -math.inf
    hi = w["upper"]["sigma"] if w["upper"] else math.inf
    return lo <= sigma <= hi


def continue_window(sim: Any, params: Mapping[str, Any], window: Mapping[str, Any], param2: str,
                    p2_range: tuple[float, float], log2: bool, sigma_range: tuple[float, float],
                    theta: float = 0.5, max_points: int = 300) -> dict[str, Any]:
    """Both edges of a window continued in (sigma, p2) from ``params[param2]`` upward."""
    from ...dynamics.curves.event_curves import continue_event
    from ...dynamics.curves.graze_curves import continue_graze

    out: dict[str, Any] = {}
    for side, sign in (("lower", -1.0), ("upper", 1.0)):
        e = window[side]
        if e is None:
            out[side] = None
            continue
        if e["kind"] == "stick":
            out[side] = {"kind": "stick", "failed": "a sticking onset is not continued in two parameters"}
            continue
        try:
            if e["kind"] == "graze":
                s_out = e["sigma"] + sign * max(2.0 * e["bracket"], 1e-9 * e["sigma"])
                curve = continue_graze(sim, params, window["M"], e["sigma"], e["point"], s_out, param2, p2_range,
                                       log2, 1.0, max_points=max_points, sigma_range=sigma_range, theta=theta)
            else:
                curve = continue_event(sim, params, e["kind"], window["M"], e["sigma"], e["point"], param2,
                                       p2_range, log2, 1.0, sigma_range=sigma_range, max_points=max_points,
                                       theta=theta)
            out[side] = curve.as_dict()
        except (ValueError, ArithmeticError, FmuError) as exc:
            # no start on the extended system (HarnessInputError is a ValueError), no graze where
            # the branch said one, or the FMU failing on the way: the edge is reported, not charted
            out[side] = {"kind": e["kind"], "failed": f"{type(exc).__name__}: {exc}"}
    return out


def window_closing(curves: Mapping[str, Any], p2_range: Sequence[float], sigma_range: Sequence[float]) -> dict[str, Any]:
    """Where (in p2) and how a window with the continued edge ``curves`` closes."""
    cands: list[tuple[float, float, str]] = []
    for side in ("lower", "upper"):
        c = curves.get(side)
        if not c or "failed" in c:
            continue
        for t in c["turns"]:
            if t["side"] == "max":
                why = ("smallest |multiplier| along sigma reaches 1" if c["kind"] != "graze" else
                       "the orbit's free passage no longer reaches the wall at any sigma")
                cands.append((t["p2"], t["sigma"], f"the {side} {c['kind']} edge turns back in p2 at its maximum: "
                              f"the window's two {c['kind']} edges meet ({why})"))
            elif t["side"] == "loses":
                cands.append((t["p2"], t["sigma"], f"the grazing orbit on the {side} graze edge loses stability "
                              "(multipliers in `multipliers`): the graze edge meets a flip/fold edge"))
        end = c["end"]
        if end.get("reason") == "graze":
            cands.append((end["p2"], end["sigma"], f"the {side} {c['kind']} edge ends on the orbit's graze curve "
                          f"(approximate: {end['note']})"))
        if side == "lower" and _heads_up(c) and end.get("reason") == "range" and end["sigma"] >= 0.99 * sigma_range[1]:
            g_inf = _asymptote(c["sigma"], c["p2"])
            cands.append((g_inf, end["sigma"], f"the lower {c['kind']} edge runs off to large sigma: it leaves the "
                          f"charted sigma range at p2 = {end['p2']:.8g} (sigma = {end['sigma']:.4g}); the value given is "
                          "its asymptote, p2 = p* - c / sigma through the last two points (not two edges meeting)"))
    top = smooth_top(curves)
    if top is not None and top["interior"] and not any(x[0] >= top["p2"] for x in cands):
        cands.append((top["p2"], top["sigma"], f"the {top['side']} {top['kind']} edge reaches its largest p2 between "
                      "two of its points (a turn its continuation did not locate): the window's edges meet there"))
    if not cands:
        reasons = {s: (curves[s] or {}).get("end", {}).get("note", "no edge") if curves.get(s) and "failed" not in curves[s]
                   else (curves[s] or {}).get("failed", "no edge (unbounded in the sigma range)") for s in ("lower", "upper")}
        return {"closes": None, "sigma": None, "how": None, "searched": list(p2_range), "edges_end": reasons}
    cands.sort()
    # Where a flip/fold curve runs into the graze, its corrector stops once its difference steps
    # straddle the graze (a gap ~1e-7 before the meeting point), which near a thin window's tip can
    # be 0.3 % early in p2; the grazing orbit's loss of stability, located on the graze curve,
    # is the same point located exactly.  Prefer it when the two are that close.
    exact = [x for x in cands if "loses stability" in x[2] and x[0] <= cands[0][0] * 1.01]
    if exact and "approximate" in cands[0][2]:
        cands.remove(exact[0])
        cands.insert(0, exact[0])
    p2, sigma, how = cands[0]
    return {"closes": p2, "sigma": sigma, "how": how, "searched": list(p2_range),
            "other_candidates": [{"p2": a, "sigma": b, "how": c} for a, b, c in cands[1:]]}


def _heads_up(c: Mapping[str, Any]) -> bool:
    """Whether a lower edge curve runs off to large sigma with p2 growing: its last located turn, if
    any, is a minimum (after a maximum alone it returns to large sigma as p2 falls: the window's upper
    edge, bounding it from above, whose asymptote closes nothing)."""
    ext = [t["side"] for t in c["turns"] if t["side"] in ("max", "min")]
    # and its end is its largest p2 (to the noise that significant_turns filters: a turn it dropped
    # leaves a curve returning with p2 falling)
    return (not ext or ext[-1] == "min") and c["p2"][-1] >= max(c["p2"]) * (1.0 - 1e-3)


def smooth_top(curves: Mapping[str, Any]) -> dict[str, Any] | None:
    """The largest p2 reached by a point of a smooth (flip, fold, NS) edge curve: ``{"p2", "sigma",
    "side", "kind", "interior"}`` (``interior``: neither end of its curve).  Every such point has
    stable orbits of the window next to it on one side (the other multiplier of a dissipative map is
    inside the unit circle; the edge check confirms it point by point), so no closing lies below it."""
    best = None
    for side, c in curves.items():
        if not c or "failed" in c or c.get("kind") not in ("flip", "fold", "ns") or not c.get("p2"):
            continue
        i = int(np.argmax(c["p2"]))
        if best is None or c["p2"][i] > best["p2"]:
            best = {"p2": float(c["p2"][i]), "sigma": float(c["sigma"][i]), "side": side, "kind": c["kind"],
                    "interior": 0 < i < len(c["p2"]) - 1}
    return best


def _asymptote(sigma: Sequence[float], p2: Sequence[float]) -> float:
    """p* of p2 = p* - c / sigma through the last two points of a curve running off to large sigma
    (the oscillator becomes scale-invariant as sigma -> infinity: the wall's offset 1 is negligible
    beside the forcing amplitude 1 + sigma, so the edge tends to a fixed p2)."""
    (s1, s2), (a, b) = sigma[-2:], p2[-2:]
    if s1 == s2:
        return float(b)
    c = (b - a) / (1.0 / s1 - 1.0 / s2)
    return float(b + c / s2)


def chart_curves(source: Any, params: Mapping[str, Any], param2: str, p2_range: tuple[float, float], log2: bool,
                 grid: np.ndarray, M_max: int, theta: float = 0.5) -> dict[str, Any]:
    """Windows at the start of the range, their edges continued, and where each closes."""
    from ...fmu.simulator import FmuSimulator

    sim = FmuSimulator(source, instance_name="chart-curves")
    p0 = {**params, param2: float(p2_range[0])}
    windows, search = windows_at(sim, p0, grid, M_max, theta)
    if grid[0] > 0:
        sigma_range = (float(grid[0]) * 0.1, float(grid[-1]) * 10.0)
    else:
        sigma_range = widened(grid)
    for w in windows:
        w["curves"] = continue_window(sim, p0, w, param2, p2_range, log2, sigma_range, theta)
        w["closing"] = window_closing(w["curves"], p2_range, sigma_range)
    closes: dict[str, Any] = {}
    for M in range(1, M_max + 1):
        mine = [w for w in windows if w["M"] == M]
        if mine:  # the window nearest grazing (lowest), the near-grazing maps' subject
            closes[str(M)] = {**mine[0]["closing"], "window_at_start": [_sig(mine[0]["lower"]), _sig(mine[0]["upper"])]}
        else:
            closes[str(M)] = {"closes": None, "sigma": None, "how": None, "searched": list(p2_range),
                              "note": f"no stable period-{M} orbit with one impact per period found at {param2} = "
                              f"{p2_range[0]:g} by the scans over sigma in [{grid[0]:g}, {grid[-1]:g}] "
                              f"({len(grid)} values and {search['refined_values']} more where the attractors change or none is periodic, "
                              "up/down/fresh)"}
    return {"windows": windows, "closes": closes, "search": search, "sigma_range": list(sigma_range),
            "start": float(p2_range[0])}


def _sig(edge: Mapping[str, Any] | None) -> Any:
    return None if edge is None else {"kind": edge["kind"], "sigma": edge["sigma"]}


def _edge_at(curve: Mapping[str, Any] | None, p2: float) -> float | None:
    """The edge's sigma at ``p2`` on the curve's first monotone stretch in p2 (None outside it)."""
    if not curve or "failed" in curve or len(curve["p2"]) < 2:
        return None
    x, y = np.asarray(curve["p2"], float), np.asarray(curve["sigma"], float)
    d = np.sign(np.diff(x))
    n = int(np.argmax(d != d[0])) + 1 if np.any(d != d[0]) else len(x)
    x, y = x[:n], y[:n]
    if d[0] < 0:
        x, y = x[::-1], y[::-1]
    if not x[0] <= p2 <= x[-1]:
        return None
    if np.any(y <= 0):  # below grazing: sigma interpolated as itself
        return float(np.interp(np.log(p2), np.log(x), y))
    return float(np.exp(np.interp(np.log(p2), np.log(x), np.log(y))))


def scan_check(windows: Sequence[Mapping[str, Any]], scans: Mapping[str, Any], rel: float = 1e-2) -> dict[str, Any]:
    """Compare the per-value scans' window edges with the continued edges at the same p2.

    Per M: the values compared, the largest relative difference, and every value where an edge
    differs by more than ``rel`` (with the scan's edge kind: "lost" marks a march that failed)."""
    out: dict[str, Any] = {}
    for M, sc in scans.items():
        mine = [w for w in windows if str(w["M"]) == M]
        if not mine:
            continue
        cur = mine[0]["curves"]
        rows, worst = [], 0.0
        for i, v in enumerate(sc["value"]):
            for side, key in (("lower", "lower"), ("upper", "upper")):
                s_scan, s_cont = sc[key][i], _edge_at(cur.get(side), float(v))
                if s_scan is None or s_cont is None:
                    continue
                d = abs(s_scan - s_cont) / max(abs(s_cont), 1e-12)
                worst = max(worst, d)
                if d > rel:
                    rows.append({"p2": float(v), "side": side, "scan": s_scan, "continued": s_cont,
                                 "scan_kind": sc[f"kind_{key}"][i]})
        out[M] = {"compared": len(sc["value"]), "max_rel_diff": worst, "disagree": rows}
    return out


def _stretches(w: Mapping[str, Any]) -> list[tuple[Mapping[str, Any], float | None, float | None]]:
    """The window's edge curves with the stretch of p2 over which each bounds it: those continued from
    the start up to the first hand-over of its boundary (:mod:`.window_region`), then those continued
    after each hand-over up to the next one, the last up to the closing."""
    cl = w["closing"]
    first = cl.get("edges_bound_until", cl["closes"])
    hs = sorted(w.get("handovers", []), key=lambda h: float(h["p2"]))
    ends = [float(h["p2"]) for h in hs[1:]] + [cl["closes"]]
    return [(w["curves"], None, first)] + [(h["curves"], float(h["p2"]), e) for h, e in zip(hs, ends)]


#: Across a fold, an orbit Newton finds from the fold's own orbit farther than this (relative to
#: 1 + sigma) is another orbit (a coexisting stable one between two turns of the fold curve), not
#: the fold's branch: the branch moves ~sqrt(d) from its fold point.
FOLD_BRANCH = 0.05


def _orbit_across(sim: Any, params: Mapping[str, Any], param2: str, theta: float, M: int, impacts: int, z: Any,
                  s: float, v: float, near: float | None = None) -> tuple[bool, bool]:
    """(an orbit with the contacts found by Newton from ``z`` at (sigma, p2) = (s, v), and stable); with
    ``near``, only an orbit within ``near`` (1 + sigma) of ``z`` counts."""
    from ...dynamics.maps.periodic_map import PeriodMap, refine_orbit

    s, v = float(s), float(v)
    pmap = PeriodMap(sim, {**params, param2: v}, "sigma", theta)
    # the residual relative to the orbit's size (1 + sigma), as on the curve itself: an absolute
    # 1e-10 is below CVODE's accuracy on an orbit of size 1e3
    _, ev, ok, _ = refine_orbit(pmap, np.asarray(z, float) - pmap.offset(s), s, M, tol=1e-10 * (1.0 + s))
    same = ok and int(ev.contacts.sum()) == impacts
    if same and near is not None:
        same = float(np.max(np.abs(ev.points[0] - np.asarray(z, float)))) <= near * (1.0 + abs(s))
    return same, same and bool(np.all(np.abs(np.linalg.eigvals(ev.J)) < 1.0))


def edge_check(source: Any, params: Mapping[str, Any], param2: str, windows: Sequence[Mapping[str, Any]],
               log2: bool = True, theta: float = 0.5, d: float = 1e-5, sigma_log: bool = True) -> dict[str, Any]:
    """Check the continued edges across themselves, at every point of every edge curve.

    At a point of a curve, the orbit is solved by Newton (from the curve's own point) at the two
    points d away across the curve (along its normal in the plane (s, q), s = ln sigma (sigma itself
    with ``sigma_log`` False, a chart reaching sigma <= 0), q = ln p2 on a
    log axis; the tangent from the neighbouring points): a flip/NS point must have a stable
    orbit on one side and an unstable one with the same contacts on the other; a fold or graze point a
    stable orbit on one side and no orbit with its contacts on the other.  Each curve is checked
    over the stretch of p2 where it bounds the window (:func:`_stretches`: up to the first hand-over
    of the boundary, the edges continued after a hand-over from there, none beyond the closing).
    Returns per M: ``{"checked", "confirmed", "failed": [...]}``.
    """
    from ...fmu.simulator import FmuSimulator

    sim = FmuSimulator(source, instance_name="chart-edge-check")
    to_q, of_q = (np.log, np.exp) if log2 else (np.asarray, np.asarray)
    to_s, of_s = (np.log, np.exp) if sigma_log else (np.asarray, np.asarray)
    out: dict[str, Any] = {}
    for w in windows:
        rep = out.setdefault(str(w["M"]), {"checked": 0, "confirmed": 0, "failed": []})
        try:
            _check_window(sim, params, param2, theta, d, w, rep, (to_q, of_q, to_s, of_s))
        except Exception as exc:  # noqa: BLE001  (one window's failure is a line of the report; the rest goes on)
            rep["error"] = f"{type(exc).__name__}: {exc}"
    return out


def _check_window(sim: Any, params: Mapping[str, Any], param2: str, theta: float, d: float, w: Mapping[str, Any],
                  rep: dict[str, Any], axes: tuple) -> None:
    """:func:`edge_check` of one window into ``rep``."""
    to_q, of_q, to_s, of_s = axes
    for curves, p_lo, p_hi in _stretches(w):
        for side in ("lower", "upper"):
            c = curves.get(side)
            if not c or "failed" in c or len(c["sigma"]) < 2:
                continue
            Y = np.column_stack([to_s(np.asarray(c["sigma"], float)), to_q(np.asarray(c["p2"], float))])
            for i, z in enumerate(c["points"]):
                if (p_hi is not None and c["p2"][i] > p_hi * (1.0 - 1e-3)) or (p_lo is not None and c["p2"][i] < p_lo):
                    continue
                t = Y[min(i + 1, len(Y) - 1)] - Y[max(i - 1, 0)]
                n = np.array([-t[1], t[0]]) / np.linalg.norm(t)
                near = FOLD_BRANCH if c["kind"] == "fold" else None
                sides = [_orbit_across(sim, params, param2, theta, w["M"], c["impacts"], z, of_s(ls), of_q(q), near)
                         for ls, q in (Y[i] + d * n, Y[i] - d * n)]
                (a_same, a_stable), (b_same, b_stable) = sides
                if c["kind"] in ("graze", "stick", "fold"):
                    # a fold: the stable orbit meets its unstable partner and both end there, so
                    # across it there is no orbit at all (not an unstable one, as across a flip)
                    good = (a_stable and not b_same) or (b_stable and not a_same)
                else:
                    good = a_same and b_same and a_stable != b_stable
                rep["checked"] += 1
                rep["confirmed"] += int(good)
                if not good:
                    rep["failed"].append({"p2": float(c["p2"][i]), "side": side, "kind": c["kind"],
                                          "sigma": float(c["sigma"][i]), "one_side": {"orbit": a_same, "stable": a_stable},
                                          "other_side": {"orbit": b_same, "stable": b_stable}})
