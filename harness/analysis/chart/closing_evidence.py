"""What a window's closing is held against: the stable orbits every route of a chart run found, and the
located boundary features of its edge curves (:mod:`.closing_routes` uses both).

* :func:`stable_evidence`: every p2 at which a route of the run found a stable orbit of the window --
  the per-value scans (their windows, shot to their edges, with the scans' own states), a
  contradiction settled by shooting, the shots below a candidate closing, the orbit found above a
  hand-over of the boundary;
* :func:`boundary_features`: the edge curves' turning points (maximum in p2), grazing orbits losing
  stability, smooth edges ending on the graze, and corners where two edge curves cross.
"""
from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np

__all__ = ["curve_sets", "boundary_features", "stable_evidence"]


def curve_sets(w: Mapping[str, Any]) -> list[Mapping[str, Any]]:
    return [w.get("curves") or {}, *((h.get("curves") or {}) for h in w.get("handovers") or [])]


def _usable(c: Any) -> bool:
    return bool(c) and "failed" not in c and len(c.get("p2", ())) >= 2


def _corners(a: Mapping[str, Any], b: Mapping[str, Any]) -> list[tuple[float, float]]:
    """Where two edge curves cross in the plane (ln p2, ln sigma) (sigma itself where one is <= 0)."""
    pa, sa, pb, sb = (np.asarray(x, float) for x in (a["p2"], a["sigma"], b["p2"], b["sigma"]))
    if min(pa.min(), pb.min()) <= 0:
        return []
    log_s = bool(min(sa.min(), sb.min()) > 0)
    fa = np.column_stack([np.log(pa), np.log(sa) if log_s else sa])
    fb = np.column_stack([np.log(pb), np.log(sb) if log_s else sb])
    out = []
    p, r = fa[:-1], fa[1:] - fa[:-1]
    for j in range(len(fb) - 1):
        q, s = fb[j], fb[j + 1] - fb[j]
        den = r[:, 0] * s[1] - r[:, 1] * s[0]
        ok = np.abs(den) > 1e-300
        with np.errstate(all="ignore"):
            t = ((q[0] - p[:, 0]) * s[1] - (q[1] - p[:, 1]) * s[0]) / den
            u = ((q[0] - p[:, 0]) * r[:, 1] - (q[1] - p[:, 1]) * r[:, 0]) / den
        for i in np.nonzero(ok & (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1))[0]:
            x = p[i] + t[i] * r[i]
            out.append((float(math.exp(x[0])), float(math.exp(x[1]) if log_s else x[1])))
    return out


def boundary_features(w: Mapping[str, Any]) -> list[dict[str, Any]]:
    """The located boundary features of a window's edge curves (those continued after a hand-over
    included): turning points (maximum in p2), grazing orbits losing stability, a smooth edge
    ending on the graze, and corners where two edge curves meet.  ``{"p2", "sigma", "kind"}``."""
    out: list[dict[str, Any]] = []
    curves = [(side, c) for cs in curve_sets(w) for side, c in cs.items() if _usable(c)]
    for side, c in curves:
        for t in c.get("turns", []):
            if t["side"] == "max":
                out.append({"p2": float(t["p2"]), "sigma": float(t["sigma"]),
                            "kind": f"turning point of the {side} {c['kind']} edge"})
            elif t["side"] == "loses":
                out.append({"p2": float(t["p2"]), "sigma": float(t["sigma"]),
                            "kind": f"the grazing orbit on the {side} graze edge loses stability"})
        i = int(np.argmax(c["p2"]))
        if c["kind"] != "graze" and 0 < i < len(c["p2"]) - 1 and not any(
                t["side"] == "max" and abs(t["p2"] - c["p2"][i]) <= 1e-6 * c["p2"][i] for t in c.get("turns", [])):
            out.append({"p2": float(c["p2"][i]), "sigma": float(c["sigma"][i]),
                        "kind": f"largest p2 of the {side} {c['kind']} edge (a turn between two of its points)"})
        if c["end"].get("reason") == "graze":
            out.append({"p2": float(c["end"]["p2"]), "sigma": float(c["end"]["sigma"]),
                        "kind": f"the {side} {c['kind']} edge ends on the graze"})
    for i in range(len(curves)):
        for j in range(i + 1, len(curves)):
            (s1, a), (s2, b) = curves[i], curves[j]
            if a is b:
                continue
            for p2, s in _corners(a, b):
                # the curves' common start (a window's two edges at the first value) is no corner
                if min(abs(p2 - a["p2"][0]), abs(p2 - b["p2"][0])) <= 1e-9 * p2:
                    continue
                out.append({"p2": p2, "sigma": s, "kind": f"corner: the {s1} {a['kind']} edge meets the {s2} "
                            f"{b['kind']} edge"})
    return sorted(out, key=lambda f: f["p2"])


def stable_evidence(M: int, closing: Mapping[str, Any], per_value: Sequence[Mapping[str, Any]],
                    contradictions: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Every p2 of the run at which a route found a stable orbit of the period-M window (one impact
    per period): ``{"p2", "sigma", "point", "route"}`` (``point`` None where the route kept none)."""
    out: list[dict[str, Any]] = []
    for res in per_value:
        for e in res.get("all", []):
            if e["M"] != M or e["impacts"] != 1 or not e.get("resolved"):
                continue
            lo, hi = e.get("lo"), e.get("hi")
            tr = [t for sd in res.get("seeds", []) if sd["M"] == M and sd["impacts"] == 1 for t in sd["track"]
                  if (lo is None or t[0] >= lo) and (hi is None or t[0] <= hi)]
            t = min(tr, key=lambda t: abs(t[0] - e["seed_sigma"]), default=None)
            out.append({"p2": float(res["value"]), "sigma": float(e["seed_sigma"] if t is None else t[0]),
                        "point": None if t is None else [t[1], t[2]], "route": "per-value scans"})
    for c in contradictions:
        ev = c.get("evidence") or {}
        if c.get("window") == str(M) and ev.get("found"):
            out.append({"p2": float(c["p2"]), "sigma": float(ev["sigma"]), "point": ev.get("point"),
                        "route": f"shooting settling a {c['type']} contradiction ({c['right']} right)"})
    conf = closing.get("confirmation") or {}
    below = conf.get("below") or {}
    if below.get("orbit"):
        o = below["orbit"]
        out.append({"p2": float(below["p2"]), "sigma": float(o["sigma"]), "point": o.get("point"),
                    "route": "shooting below the candidate closing"})
    for c in closing.get("codim2", []) or []:
        o = c.get("orbit_above")
        if o:
            out.append({"p2": float(c["p2"]) * (1.0 + 1e-3), "sigma": float(o["sigma"]), "point": o.get("point"),
                        "route": "shooting above a hand-over of the boundary"})
    return sorted(out, key=lambda e: e["p2"])
