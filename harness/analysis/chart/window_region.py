"""A window as a region of (sigma, p2), and its closing confirmed by direct shooting.

At each value of the second parameter p2 a window is the set of sigma where its period-M orbit
exists with its contacts and is stable.  Its boundary can hand over from one curve to another: a
graze curve that turns back in p2 bounds only the region where the orbit's free passage reaches
the wall; past its turn the window is bounded by the other edges (a flip curve taking over, a fold
appearing) and closes later.  So the candidates of :func:`.chart_curves.window_closing` (turning
points, a grazing orbit losing stability, an edge ending on the graze, the lower edge running off
to sigma -> infinity) are only candidates.  Each is tested in turn by direct Newton shooting on the
FMU (:func:`harness.dynamics.maps.periodic_map.refine_orbit`, no continuation):

* **below**, at p2* (1 - 1e-3): a stable period-M orbit with the window's contacts must be found
  on a sigma grid across the window there (between the continued edges' crossings of that p2);
* **above**, at p2* (1 + 1e-3): none on a sigma grid across the same interval widened (started
  from the orbits found below, from the edge curves' own orbits, and from orbits iterated from a
  few starts, :data:`ITERATED`).

Both found: the candidate is confirmed, the window closes there.  A stable orbit above: the
boundary hands over there (a codimension-two point of the kind the candidate names); the orbit
found is continued in sigma to its new edges (:func:`orbit_edges`), those are continued in
(sigma, p2) from there (:func:`.chart_curves.continue_window`), and their candidates are tested
in turn, at most :data:`MAX_HANDOVERS` times.  No orbit below: the candidate is not this window's
closing (recorded, the next candidate is tested).  An unconfirmed candidate is never the answer.
"""
from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np

from ...dynamics.maps.sigma_search import norm_seed, shoot_across, sigma_grid, with_near_edges
from ...errors import FmuError

__all__ = ["chart_regions", "closing_evidence_lines", "STEP", "MAX_HANDOVERS", "GRID", "ITERATED", "closing_kind", "edge_crossings",
           "bracketing",
           "confirm_candidate", "orbit_edges", "follow_window"]

#: Relative distance in p2 from a candidate closing at which the window is tested on each side.
STEP = 1e-3
#: Hand-overs followed per window before the search gives up (and says so).
MAX_HANDOVERS = 6
#: Values of sigma in each search grid.
GRID = 25
#: Orbits iterated from a few starts (periods of transient) at this many sigma of the grid above.
ITERATED = (5, 300)


def closing_kind(how: str) -> str:
    """The codimension-two point a candidate's description (:func:`.chart_curves.window_closing`) names."""
    if "bisection" in how:
        return "window lost between two values of p2 (shooting bisection)"
    if "continuation is lost" in how:
        return "edge curve lost at its end (the window may end there)"
    if "runs off" in how:
        return "edge runs off to sigma -> infinity (an asymptote)"
    if "loses stability" in how:
        return "graze meets flip/fold (the grazing orbit loses stability)"
    if "ends on the orbit's graze" in how:
        return "smooth edge meets graze (flip/fold curve ends on the graze)"
    for kind in ("graze", "flip", "fold", "ns"):
        if f"{kind} edge turns back" in how or f"{kind} edge reaches its largest" in how:
            return f"{kind} curve turns (maximum in p2)"
    return "other"


def edge_crossings(curves: Mapping[str, Any], p2: float) -> list[float]:
    """Every sigma at which a continued edge curve crosses ``p2`` (linear interpolation between
    neighbouring points, in ln sigma where both are positive)."""
    out: list[float] = []
    for c in curves.values():
        if not c or "failed" in c or len(c["p2"]) < 2:
            continue
        x, y = np.asarray(c["p2"], float), np.asarray(c["sigma"], float)
        for i in range(len(x) - 1):
            a, b = x[i], x[i + 1]
            if (a - p2) * (b - p2) > 0 or a == b:
                continue
            t = (p2 - a) / (b - a)
            if y[i] > 0 and y[i + 1] > 0:
                out.append(float(math.exp((1 - t) * math.log(y[i]) + t * math.log(y[i + 1]))))
            else:
                out.append(float((1 - t) * y[i] + t * y[i + 1]))
    return sorted(out)


def _curve_seeds(curves: Mapping[str, Any], p2: float, theta: float) -> list[np.ndarray]:
    """The orbit of each continued edge curve at its point nearest ``p2`` (as shapes)."""
    out = []
    for c in curves.values():
        if c and "failed" not in c and len(c["p2"]) > 0:
            i = int(np.argmin(np.abs(np.asarray(c["p2"], float) - p2)))
            out.append(norm_seed(c["points"][i], float(c["sigma"][i]), theta))
    return out


def _below(curves: Mapping[str, Any], cand: Mapping[str, Any]) -> tuple[float, float, float, list[float]]:
    """Where the window is tested just below the candidate: (p2, sigma from, sigma to, the edge
    curves' crossings of that p2).  At p2* (1 - 1e-3), between the edges' crossings there (and the
    candidate's own sigma).  For a lower edge running off to sigma -> infinity, on the asymptote
    p2 = p* - c / sigma through its last two points, at the p2 where the edge is at sigma_e = at
    most twice its last charted sigma (nearer p* the edge lies beyond any sigma Newton can follow
    accurately), over [1.2, 4] x sigma_e."""
    pb = float(cand["p2"]) * (1.0 - STEP)
    if "runs off" in cand["how"]:
        lower = curves["lower"]
        (s1, s2), (a, b) = lower["sigma"][-2:], lower["p2"][-2:]
        c = (b - a) / (1.0 / s1 - 1.0 / s2) if s1 != s2 else 0.0
        if c > 0:
            pb = min(pb, float(cand["p2"]) - c / (2.0 * s2))
        s_e = c / max(cand["p2"] - pb, 1e-300) if c > 0 else 2.0 * float(s2)
        return pb, 1.2 * s_e, 4.0 * s_e, edge_crossings(curves, pb)
    edges = bracketing(edge_crossings(curves, pb), float(cand["sigma"]))
    pts = edges + [float(cand["sigma"])] + [float(x) for x in cand.get("sigmas", [])]
    return pb, min(pts), max(pts), edges


def bracketing(edges: Sequence[float], sigma: float) -> list[float]:
    """The edge crossings that bound the window around ``sigma``: the nearest at or below it and the
    nearest at or above it (the two nearest where it lies beyond all of them).  The shots sample the
    window there, at a density set by its width, never a range widened to every curve's crossing (a
    graze curve running off to large sigma crosses the same p2 far away)."""
    if len(edges) <= 2:
        return sorted(edges)
    below = [e for e in edges if e <= sigma]
    above = [e for e in edges if e >= sigma]
    if below and above:
        return sorted({max(below), min(above)})
    return sorted(sorted(edges, key=lambda e: abs(e - sigma))[:2])


def confirm_candidate(sim: Any, params: Mapping[str, Any], param2: str, M: int, impacts: int,
                      curves: Mapping[str, Any], cand: Mapping[str, Any], theta: float = 0.5) -> dict[str, Any]:
    """Test a candidate closing ``{"p2", "sigma", "how"}`` by Newton shooting on either side.

    Returns ``{"verdict", "below", "above"}``; verdict "confirmed" (a stable orbit below between
    the edges, none above), "hand-over" (one above: the window goes on) or "no orbit below" (the
    window is not there just below the candidate: not its closing)."""
    from ...dynamics.maps.periodic_map import PeriodMap

    p2c = float(cand["p2"])
    pb, lo, hi, edges = _below(curves, cand)
    pa = p2c * (1.0 + STEP)
    seeds = _curve_seeds(curves, p2c, theta)
    g_below = with_near_edges(sigma_grid(lo, hi, 0.25, GRID), edges)
    below = shoot_across(PeriodMap(sim, {**params, param2: pb}, "sigma", theta), M, impacts, g_below, seeds)
    between = None if len(edges) < 2 else any(edges[0] <= o["sigma"] <= edges[-1] for o in below)
    more = [norm_seed(o["point"], o["sigma"], theta) for o in below[:: max(1, len(below) // 3)]]
    g_above = with_near_edges(sigma_grid(lo, hi, 0.5, GRID + 6), edges)
    above = shoot_across(PeriodMap(sim, {**params, param2: pa}, "sigma", theta), M, impacts, g_above,
                         more + seeds, ITERATED)
    verdict = ("hand-over" if above else "confirmed" if below and between is not False else "no orbit below")
    search = {"grid": "geometric" if lo > 0 else "even", "newton_tol": "1e-10 x (1 + |sigma|)",
              "stable": "all |multipliers| < 1, contacts per period as the window's"}
    return {"verdict": verdict,
            "below": {"p2": pb, "sigma_range": [float(g_below[0]), float(g_below[-1])], "values": len(g_below),
                      "edges_there": edges, "found": len(below), "between_edges": between,
                      "sigma": [o["sigma"] for o in below],
                      "orbit": _middle([o for o in below if not edges or edges[0] <= o["sigma"] <= edges[-1]] or below)},
            "above": {"p2": pa, "sigma_range": [float(g_above[0]), float(g_above[-1])], "values": len(g_above),
                      "starts": f"{len(more) + len(seeds)} seeds + the previous sigma's orbit at each value; the "
                      f"wall-free orbit and the seeds iterated {ITERATED[1]} periods at {ITERATED[0]} values",
                      "found": bool(above), "sigma": [o["sigma"] for o in above], "orbit": _middle(above)},
            "search": search}


def _middle(found: Sequence[Mapping[str, Any]]) -> dict[str, Any] | None:
    """The middle one of the orbits found (as evidence), or None."""
    return dict(found[len(found) // 2]) if found else None


def orbit_edges(sim: Any, params: Mapping[str, Any], M: int, sigma: float, z: Sequence[float],
                sigma_range: tuple[float, float], theta: float = 0.5) -> dict[str, Any]:
    """A stable period-M orbit continued in sigma both ways to its first events: the window it
    lies in, as :func:`.chart_curves.windows_at` builds one (same continuation settings)."""
    from ...dynamics.continuation.continue_orbit import continue_orbit
    from .edge_curves import _edge

    # not down to sigma = -1 (no forcing; the FMU refuses sigma <= -1, and a corrector step can
    # overshoot the range's end)
    rng = (max(float(sigma_range[0]), -0.8), float(sigma_range[1]))
    edges: list[dict[str, Any] | None] = []
    for d in (-1.0, 1.0):
        try:
            br = continue_orbit(sim, params, M, sigma, z, "sigma", rng, d,
                                ds_max=max(0.05, 0.1 * abs(sigma)), max_points=600, theta=theta)
            edges.append(_edge(br))
        except (ValueError, ArithmeticError, FmuError) as exc:  # reported with the edge, not raised
            edges.append({"kind": "failed", "sigma": math.nan, "note": f"{type(exc).__name__}: {exc}"})
    return {"M": M, "seed_sigma": float(sigma), "seed": [float(x) for x in z], "lower": edges[0], "upper": edges[1]}


def _candidates(curves: Mapping[str, Any], p2_range: Sequence[float], sigma_range: Sequence[float]) -> tuple[list, dict]:
    """window_closing's candidates in its order (the preferred one first), above the range's start."""
    from .edge_curves import window_closing

    cl = window_closing(curves, p2_range, sigma_range)
    cands = [] if cl["closes"] is None else \
        [{"p2": cl["closes"], "sigma": cl["sigma"], "how": cl["how"]}, *cl.get("other_candidates", [])]
    for side in ("lower", "upper"):
        # an edge whose continuation was lost inside the range may end where the window does (a
        # graze curve running into a fold: its grazing orbit ends there); shooting decides
        c = curves.get(side)
        if c and "failed" not in c and c["end"].get("reason") in ("lost", "steps"):
            e = {"p2": float(c["end"]["p2"]), "sigma": float(c["end"]["sigma"]),
                 "how": f"the {side} {c['kind']} edge's continuation is lost at its end (approximate: "
                 f"{c['end'].get('note', '')})"}
            k = next((i for i, x in enumerate(cands) if x["p2"] > e["p2"]), len(cands))
            cands.insert(k, e)
    # an asymptote extrapolated beyond the range's end is not a closing in the range
    return [c for c in cands if p2_range[0] * (1.0 + STEP) < c["p2"] <= p2_range[1]], cl


def _impacts(curves: Mapping[str, Any]) -> int:
    for c in curves.values():
        if c and "impacts" in c:
            return int(c["impacts"])
    return 1


def follow_window(sim: Any, params: Mapping[str, Any], window: dict[str, Any], param2: str,
                  p2_range: tuple[float, float], log2: bool, sigma_range: tuple[float, float],
                  theta: float = 0.5) -> dict[str, Any]:
    """Where the window (with its continued edges ``window["curves"]``, ``params`` at the range's
    start) closes: the first candidate confirmed by :func:`confirm_candidate`, following every
    hand-over of its boundary.  The new edges after each hand-over are kept in
    ``window["handovers"]`` (``{"p2", "window", "curves"}``).  Returns the closing dict of
    :func:`.chart_curves.window_closing` with ``confirmation``, ``codim2`` (every codimension-two
    point met, with its kind) and ``tested`` (every candidate tested, with its verdict)."""
    M, curves, start = window["M"], window["curves"], float(p2_range[0])
    codim2: list[dict[str, Any]] = []
    tested: list[dict[str, Any]] = []
    window["handovers"] = []
    seen: dict[str, Any] | None = None  # the last hand-over's shooting above it: the window seen there
    before: Mapping[str, Any] | None = None  # the edges before the last hand-over
    while True:
        cands, first = _candidates(curves, (start, p2_range[1]), sigma_range)
        if not cands and before is not None:
            # the new edges propose nothing (not continued, or no event in the range): the edges
            # before the hand-over still bound the window on their other side, and their later
            # candidates are tested like any (shooting decides, not the curve)
            curves, before = before, None
            cands, first = _candidates(curves, (start, p2_range[1]), sigma_range)
        handed = None
        for cand in cands:
            conf = confirm_candidate(sim, params, param2, M, _impacts(curves), curves, cand, theta)
            if conf["verdict"] == "no orbit below" and seen is not None:
                # seen above the hand-over, gone below this candidate: it closes in between
                tested.append({**cand, "kind": closing_kind(cand["how"]), "verdict": conf["verdict"]})
                cand = _bisect_closing(sim, params, param2, M, _impacts(curves), seen, conf["below"], curves, theta)
                conf = confirm_candidate(sim, params, param2, M, _impacts(curves), curves, cand, theta)
            kind = closing_kind(cand["how"])
            top = _above_candidate(curves, cand) if conf["verdict"] == "confirmed" else None
            tested.append({**cand, "kind": kind, "verdict": conf["verdict"] if top is None else top})
            if conf["verdict"] == "confirmed" and top is None:
                if "asymptote" not in kind and "bisection" not in kind:  # neither is a codimension-two point
                    codim2.append({"kind": kind, "p2": cand["p2"], "sigma": cand["sigma"], "closes_window": True})
                return {"closes": cand["p2"], "sigma": cand["sigma"], "how": cand["how"], "kind": kind,
                        "searched": list(p2_range), "confirmation": conf, "codim2": codim2, "tested": tested}
            if conf["verdict"] == "hand-over" and "bisection" not in cand["how"]:  # a bisection's estimate is no point
                codim2.append({"kind": f"boundary hand-over: {kind}", "p2": cand["p2"], "sigma": cand["sigma"],
                               "closes_window": False, "orbit_above": conf["above"]["orbit"]})
            if conf["verdict"] == "hand-over":
                handed = conf
                break
        if handed is None:
            # no candidate at all: the edges' ends (``edges_end``) say why
            note = ("no candidate confirmed: " + "; ".join(f"{t['kind']} at {t['p2']:.6g}: {t['verdict']}" for t in tested)
                    if tested else None)
            return {"closes": None, "sigma": None, "how": None, "searched": list(p2_range), "note": note,
                    "edges_end": first.get("edges_end"), "codim2": codim2, "tested": tested}
        if len(window["handovers"]) >= MAX_HANDOVERS:
            return {"closes": None, "sigma": None, "how": None, "searched": list(p2_range), "codim2": codim2,
                    "tested": tested, "note": f"not decided: the boundary handed over {MAX_HANDOVERS} times "
                    f"(the bound of hand-overs followed); the last at {param2} = {handed['above']['p2']:.8g}"}
        start, seen, before = handed["above"]["p2"], handed["above"], curves
        new, failed = _new_edges(sim, params, param2, window, handed["above"], p2_range, log2, sigma_range, theta)
        if failed:
            tested.append({"p2": start, "sigma": None, "how": failed, "kind": "new edges not found",
                           "verdict": "the edges before the hand-over are followed on"})
        curves = before if failed else new


def _above_candidate(curves: Mapping[str, Any], cand: Mapping[str, Any]) -> str | None:
    """Why a candidate confirmed by the shots around it is still not the closing: a smooth edge curve
    of the window reaches a larger p2 (a flip curve that turns back and, past a minimum, runs off to
    large sigma beyond its first turn: the window goes on there, outside the shots' interval)."""
    from .edge_curves import smooth_top

    top = smooth_top(curves)
    if top is None or top["p2"] <= float(cand["p2"]) * (1.0 + 1e-9):
        return None
    return (f"confirmed by the shots around it, but the {top['side']} {top['kind']} edge reaches "
            f"{top['p2']:.8g} (sigma = {top['sigma']:.5g}), stable orbits of the window beside it: not the closing")


def _bisect_closing(sim: Any, params: Mapping[str, Any], param2: str, M: int, impacts: int, seen: Mapping[str, Any],
                    gone: Mapping[str, Any], curves: Mapping[str, Any], theta: float) -> dict[str, Any]:
    """Where the window, ``seen`` (shooting evidence with orbits) at one p2 and ``gone`` (none) at a
    larger one, ends: bisection in ln p2, shooting on a sigma grid that narrows to the orbits found
    (two grid steps beyond them) and the edge curves' crossings, until the bracket is within 1e-3.  A candidate for
    :func:`confirm_candidate` (it decides, as for any other)."""
    from ...dynamics.maps.periodic_map import PeriodMap

    lo_p, hi_p = float(seen["p2"]), float(gone["p2"])
    # the window where it was seen: its orbits and the edges bounding them there (not the range the
    # shots above a candidate were spread over)
    sig = [float(o) for o in seen["sigma"]]
    sig += bracketing(edge_crossings(curves, lo_p), float(seen["orbit"]["sigma"]))
    lo_s, hi_s = min(sig), max(sig)
    seeds = [norm_seed(seen["orbit"]["point"], seen["orbit"]["sigma"], theta)]
    last = seen["orbit"]
    while hi_p / lo_p > 1.0 + STEP:
        mid = math.sqrt(lo_p * hi_p)
        # the window moves with p2: the edges' crossings of mid are in the interval too
        e = bracketing(edge_crossings(curves, mid), float(last["sigma"]))
        grid = sigma_grid(min([lo_s, *e]), max([hi_s, *e]), 0.25, GRID)
        found = shoot_across(PeriodMap(sim, {**params, param2: mid}, "sigma", theta), M, impacts, grid, seeds, ITERATED)
        if found:
            lo_p, last = mid, found[len(found) // 2]
            dx = 2.0 * float(np.max(np.abs(np.diff(grid))))
            lo_s, hi_s = min(o["sigma"] for o in found) - dx, max(o["sigma"] for o in found) + dx
            seeds = [norm_seed(last["point"], last["sigma"], theta)] + seeds[:2]
        else:
            hi_p = mid
    return {"p2": math.sqrt(lo_p * hi_p), "sigma": float(last["sigma"]), "sigmas": [lo_s, hi_s],
            "how": f"the window, seen by shooting at {param2} = {seen['p2']:.8g} and not below the next candidate, "
            f"ends between {lo_p:.8g} and {hi_p:.8g} (shooting bisection in {param2}; no edge curve located it)"}


def _new_edges(sim: Any, params: Mapping[str, Any], param2: str, window: dict[str, Any], above: Mapping[str, Any],
               p2_range: Sequence[float], log2: bool, sigma_range: tuple[float, float],
               theta: float) -> tuple[dict[str, Any], str | None]:
    """After a hand-over: the window's edges at the p2 above it (the stable orbit found there continued
    in sigma), continued in (sigma, p2) from there; kept in ``window["handovers"]``.  Returns (curves,
    None), or ({}, why) where the new edges were not found."""
    from .edge_curves import continue_window

    start, orbit = float(above["p2"]), above["orbit"]
    p_at = {**params, param2: start}
    try:
        new = orbit_edges(sim, p_at, window["M"], orbit["sigma"], orbit["point"], sigma_range, theta)
    except (ValueError, ArithmeticError, FmuError) as exc:  # the FMU refusing a step of the walk
        return {}, (f"not decided: the boundary hands over at {param2} = {start:.8g} and the window's new "
                    f"edges were not found there ({type(exc).__name__}: {exc})")
    curves = continue_window(sim, p_at, new, param2, (start, float(p2_range[1])), log2, sigma_range, theta)
    window["handovers"].append({"p2": start, "window": new, "curves": curves})
    return curves, None


def chart_regions(source: Any, params: Mapping[str, Any], param2: str, p2_range: tuple[float, float], log2: bool,
                  grid: np.ndarray, M_max: int, theta: float = 0.5) -> dict[str, Any]:
    """:func:`.chart_curves.chart_curves` (the windows at the range's start and their edges
    continued), with each window's closing the first candidate confirmed by :func:`follow_window`."""
    from ...fmu.simulator import FmuSimulator
    from .edge_curves import chart_curves

    cont = chart_curves(source, params, param2, p2_range, log2, grid, M_max, theta)
    sim = FmuSimulator(source, instance_name="chart-closing")
    p0 = {**params, param2: float(p2_range[0])}
    sigma_range = tuple(cont["sigma_range"])
    for w in cont["windows"]:
        try:
            w["closing"] = follow_window(sim, p0, w, param2, p2_range, log2, sigma_range, theta)
        except Exception as exc:  # noqa: BLE001  (one window's failure is a line of the report; the rest goes on)
            w["closing"] = {"closes": None, "sigma": None, "how": None, "searched": list(p2_range), "codim2": [],
                            "tested": [], "note": f"the closing search failed: {type(exc).__name__}: {exc}"}
        hand = [c["p2"] for c in w["closing"]["codim2"] if c["kind"].startswith("boundary hand-over")]
        if hand:  # the edges continued from the start bound the window up to its first hand-over
            w["closing"]["edges_bound_until"] = min(hand)
    for M, cl in cont["closes"].items():
        mine = [w for w in cont["windows"] if str(w["M"]) == M]
        if mine:  # the window nearest grazing, as chart_curves chose it
            cont["closes"][M] = {**mine[0]["closing"], "window_at_start": cl["window_at_start"]}
    return cont


def closing_evidence_lines(closes: Mapping[str, Any], param2: str) -> list[str]:
    """The report's account of each window's closing: the shooting on either side of it, every
    candidate tested with its verdict, every codimension-two point met."""
    lines = ["", f"Each closing confirmed by Newton shooting on the FMU (chart.json `closes[M].confirmation`): at "
             f"{param2} x (1 - {STEP:g}) a stable orbit with the window's contacts between the continued edges, at "
             f"{param2} x (1 + {STEP:g}) none on a sigma grid across the window's interval widened (from the orbits "
             "found below, the edge curves' orbits, and orbits iterated from the wall-free orbit); a stable orbit "
             "above is a hand-over of the window's boundary, whose new edges are then continued:", ""]
    for M, cl in closes.items():
        tested = "; ".join(f"{t['kind']} at {t['p2']:.7g} ({t['verdict']})" for t in cl.get("tested", [])) or "none"
        c2 = "; ".join(f"{c['kind']} at ({param2} = {c['p2']:.7g}, sigma = {c['sigma']:.6g})"
                       for c in cl.get("codim2", [])) or "none"
        cf = cl.get("confirmation")
        if cf is None:
            lines.append(f"- M = {M}: {cl.get('note') or 'no closing in the range'}; candidates tested: {tested}; "
                         f"codimension-two points: {c2}")
            continue
        b, a = cf["below"], cf["above"]
        mu = ", ".join(f"{math.hypot(*m):.6g}" for m in b["orbit"]["multipliers"])
        lines.append(f"- M = {M}: closes at {param2} = {cl['closes']:.7g} ({cl['kind']}). Below ({param2} = "
                     f"{b['p2']:.7g}): {b['found']} stable orbits on {b['values']} sigma in [{b['sigma_range'][0]:.6g}, "
                     f"{b['sigma_range'][1]:.6g}], edges there ({len(b['edges_there'])} crossings of the continued edge curves) {', '.join(f'{x:.8g}' for x in b['edges_there']) or 'none'}, e.g. sigma = "
                     f"{b['orbit']['sigma']:.8g} with |multipliers| {mu}. Above ({param2} = {a['p2']:.7g}): none on "
                     f"{a['values']} sigma in [{a['sigma_range'][0]:.6g}, {a['sigma_range'][1]:.6g}] ({a['starts']}). "
                     f"Candidates tested: {tested}. Codimension-two points: {c2}.")
    return lines
