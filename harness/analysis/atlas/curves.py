"""The chart's continued edge curves (``chart.json``) beside the atlas: read, and checked pixel by
pixel.

An edge curve of the window of period M bounds the region where the window's orbit (M, one
impact per period; the wall-free orbit: period 1, no impact) is stable. Along each curve, at steps
of one pixel, the atlas is probed on both sides, ``offset`` pixels away along the curve's normal
(in pixel coordinates): the curve agrees with the atlas there when the class is stable on exactly
one side. Past the chart's closing of its window (a curve continued beyond it, e.g. the graze of
the orbit after it lost stability) a curve is no edge and is not probed (``past_closing`` counts
those pixels). A disagreement is kept with what the atlas has on both sides and why it may be so:

- ``narrow``: another edge of the same window passes within the probe's reach (the window is
  narrower than 2 x offset pixels there, or the curve runs into a corner or a turning point);
- ``both sides``: the class is stable on both sides: the edge lies elsewhere by more than
  ``offset`` pixels, or the class is also reached beyond the edge as another of its orbits;
- ``neither side``: stable on neither side: the pixels' starts all went to other attractors
  (the window's basin missed; ``multistable`` says whether the pixel had more than one), or the
  orbit is stable only in a band thinner than the probe.
"""
from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import HarnessInputError
from .classes import ClassMaps, window_class

#: Pixels from the curve at which the atlas is probed on either side.
PROBE_OFFSET = 2


def read_curves(path: str | Path, param2: str) -> list[dict[str, Any]]:
    """Every continued edge curve of a chart.json: dicts with ``M``, ``impacts``, ``side``,
    ``kind``, ``p2``, ``sigma`` (arrays); the wall-free orbit's graze as (1, 0)."""
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise HarnessInputError("curves", f"cannot read {path}: {exc}") from None
    if not isinstance(data, dict) or "windows" not in data:
        raise HarnessInputError("curves", f"{path} is not a chart.json (no 'windows')")
    got = data.get("problem", {}).get("param2") or data.get("param2")
    if got is not None and got != param2:
        raise HarnessInputError("curves", f"{path} charts {got}, not {param2}")
    out = []
    for w in data["windows"]:
        sets = [w.get("curves") or {}, *((h.get("curves") or {}) for h in w.get("handovers", []))]
        closes = (w.get("closing") or {}).get("closes")
        for cs in sets:
            for side in ("lower", "upper"):
                for c in _curve(cs.get(side), int(w["M"]), 1, side):
                    out.append({**c, "closes": closes})
    wf = data.get("wall_free") or {}
    out += _curve((wf.get("curves") or {}).get("upper"), 1, 0, "upper", "graze")
    return out


def _curve(c: Any, M: int, impacts: int, side: str, kind: str | None = None) -> list[dict[str, Any]]:
    if not c or "failed" in c or len(c.get("p2") or []) < 2:
        return []
    p2 = np.array([np.nan if x is None else x for x in c["p2"]], float)
    sg = np.array([np.nan if x is None else x for x in c["sigma"]], float)
    return [{"M": M, "impacts": impacts, "side": side, "kind": kind or c.get("kind", "?"), "p2": p2, "sigma": sg}]


def _index(axis: np.ndarray, x: np.ndarray, log: bool) -> np.ndarray:
    """Fractional pixel index of the values x on an increasing axis (NaN outside)."""
    a = np.log(axis) if log else axis
    with np.errstate(invalid="ignore", divide="ignore"):
        xx = np.log(x) if log else x
    i = np.interp(xx, a, np.arange(axis.size), left=np.nan, right=np.nan)
    return i


def _probes(curve: dict[str, Any], p2: np.ndarray, sigma: np.ndarray, log_p2: bool, log_sigma: bool):
    """(point in pixel coordinates, unit normal) every pixel along the curve."""
    ip, js = _index(p2, curve["p2"], log_p2), _index(sigma, curve["sigma"], log_sigma)
    for a in range(len(ip) - 1):
        x0, y0, x1, y1 = ip[a], js[a], ip[a + 1], js[a + 1]
        if not np.all(np.isfinite([x0, y0, x1, y1])):
            continue
        length = math.hypot(x1 - x0, y1 - y0)
        if length == 0:
            continue
        n = (-(y1 - y0) / length, (x1 - x0) / length)
        for t in np.arange(0.0, length, 1.0) / length:
            yield (x0 + t * (x1 - x0), y0 + t * (y1 - y0)), n


def compare_curves(maps: ClassMaps, curves: list[dict[str, Any]], p2: np.ndarray, sigma: np.ndarray,
                   log_p2: bool, log_sigma: bool, offset: int = PROBE_OFFSET) -> dict[str, Any]:
    """The curves checked against the atlas (module comment): counts and every disagreement."""
    shape = maps.dominant.shape
    checked, past, seen, found = 0, 0, set(), []
    for c in curves:
        k = window_class(maps, c["M"], c["impacts"])
        others = [o for o in curves if o is not c and o["M"] == c["M"] and o["impacts"] == c["impacts"]]
        for (x, y), n in _probes(c, p2, sigma, log_p2, log_sigma):
            a = (int(round(x + offset * n[0])), int(round(y + offset * n[1])))
            b = (int(round(x - offset * n[0])), int(round(y - offset * n[1])))
            key = (int(round(x)), int(round(y)), c["M"], c["impacts"], c["side"])
            if not all(0 <= q[0] < shape[0] and 0 <= q[1] < shape[1] for q in (a, b)) or key in seen:
                continue
            seen.add(key)
            if c.get("closes") is not None and p2[key[0]] > c["closes"]:
                past += 1  # the curve beyond the window's closing bounds no stable orbit: no edge there
                continue
            checked += 1
            pa, pb = (bool(maps.present[k][q]) if k >= 0 else False for q in (a, b))
            if pa != pb:
                continue
            found.append(_disagreement(maps, c, others, (x, y), a, b, pa, p2, sigma, log_p2, log_sigma, offset))
    reasons: dict[str, int] = {}
    for d in found:
        reasons[d["why"]] = reasons.get(d["why"], 0) + 1
    return {"probe_offset_pixels": offset, "checked": checked, "past_closing": past, "disagree": len(found),
            "by_reason": reasons,
            "disagreements": found}


def _disagreement(maps: ClassMaps, c: dict[str, Any], others: list[dict[str, Any]], at: tuple[float, float],
                  a: tuple[int, int], b: tuple[int, int], present: bool, p2: np.ndarray, sigma: np.ndarray,
                  log_p2: bool, log_sigma: bool, offset: int) -> dict[str, Any]:
    near_other = False
    for o in others:
        ip, js = _index(p2, o["p2"], log_p2), _index(sigma, o["sigma"], log_sigma)
        ok = np.isfinite(ip) & np.isfinite(js)
        if ok.any() and np.min(np.hypot(ip[ok] - at[0], js[ok] - at[1])) <= 2 * offset + 1:
            near_other = True
            break
    why = "narrow" if near_other else ("both sides" if present else "neither side")
    name = lambda q: [maps.classes[i].name for i in np.flatnonzero(maps.present[:, q[0], q[1]])]  # noqa: E731
    i, j = int(round(at[0])), int(round(at[1]))
    return {"M": c["M"], "impacts": c["impacts"], "side": c["side"], "kind": c["kind"], "why": why,
            "p2": float(p2[min(max(i, 0), p2.size - 1)]), "sigma": float(sigma[min(max(j, 0), sigma.size - 1)]),
            "classes_one_side": name(a), "classes_other_side": name(b),
            "multistable": bool(maps.n_attractors[a] >= 2 or maps.n_attractors[b] >= 2)}
