"""An event curve in the plane of sigma and a second parameter, as the continuations of
:mod:`.event_curves` and :mod:`.graze_curves` return it, and the filter of their turning points."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..maps.periodic_map import MapEvaluation

__all__ = ["CurvePoint", "EventCurve", "significant_turns"]


@dataclass
class CurvePoint:
    """A point of an event curve: X = (w / (1 + sigma), ln sigma, q), sigma, p2, the map's
    evaluation there and the unit tangent in X."""

    X: np.ndarray
    sigma: float
    p2: float
    ev: MapEvaluation
    tangent: np.ndarray

    @property
    def multipliers(self) -> np.ndarray:
        return np.linalg.eigvals(self.ev.J).astype(complex)


@dataclass
class EventCurve:
    """An event of a period-M orbit continued in (sigma, p2).

    Attributes
    ----------
    kind : str
        flip, fold, ns or graze.
    M, impacts : int
        Period and wall entries per period of the orbit.
    param2 : str
    sigma, p2 : ndarray
        The curve, in continuation order.
    points : ndarray (N, 2)
        A stroboscopic point (u, v) at t = theta of the orbit at each point of the curve.
    multipliers : ndarray complex (N, 2)
    gaps : ndarray (N,)
        Smallest distance to the wall of the orbit's free passages (inf: none).
    turns : list of dict
        Located turning points in p2: ``{"sigma", "p2", "side"}`` (side: "max" or "min").
    end : dict
        Why the curve stopped: ``{"reason", "sigma", "p2", "note"}``; reason "graze" (the orbit's
        contact pattern changes: the event meets its graze curve), "range", "steps", "lost".
    periods_run : int
        FMU periods integrated.
    """

    kind: str
    M: int
    impacts: int
    param2: str
    sigma: np.ndarray
    p2: np.ndarray
    points: np.ndarray
    multipliers: np.ndarray
    gaps: np.ndarray
    turns: list[dict[str, Any]] = field(default_factory=list)
    end: dict[str, Any] = field(default_factory=dict)
    periods_run: int = 0

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return {"kind": self.kind, "M": self.M, "impacts": self.impacts, "param2": self.param2,
                "sigma": self.sigma.tolist(), "p2": self.p2.tolist(), "points": self.points.tolist(),
                "multipliers": [[[float(m.real), float(m.imag)] for m in row] for row in self.multipliers],
                "gaps": [None if not math.isfinite(g) else float(g) for g in self.gaps],
                "turns": self.turns, "end": self.end, "periods_run": self.periods_run}


def significant_turns(turns: list[dict[str, Any]], p2_end: float, rel: float = 1e-3) -> list[dict[str, Any]]:
    """Drop turning points in p2 that are noise: a max and a min closer than ``rel`` (relative in
    p2) to each other, or a last turn within ``rel`` of the curve's end.  Where a curve runs nearly
    parallel to the sigma axis, the solver's tolerance (CVODE: ~1e-4 of p2 on a graze near an
    asymptote) makes p2 wiggle; a real turn, where a window closes, moves p2 by far more."""
    ext = [t for t in turns if t["side"] in ("max", "min")]
    close = lambda a, b: abs(a - b) < rel * max(abs(a), 1e-300)  # noqa: E731
    k = 0
    while k < len(ext) - 1:
        if close(ext[k]["p2"], ext[k + 1]["p2"]):
            del ext[k:k + 2]
            k = max(k - 1, 0)
        else:
            k += 1
    if ext and close(ext[-1]["p2"], p2_end):
        ext.pop()
    keep = {id(t) for t in ext}
    return [t for t in turns if t["side"] not in ("max", "min") or id(t) in keep]
