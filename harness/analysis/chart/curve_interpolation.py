"""How far a continued edge, read between two points of its curve, can be from the curve itself.

``chart`` reads a continued edge at a scanned value of p2 by interpolating its curve linearly
(in ln sigma against ln p2 on log axes: :func:`harness.analysis.chart.edge_curves._edge_at`).  Where the
curve is steep and its points far apart the chord lies off the curve; comparing that reading with
an edge the scans located at that p2 to 1e-9 would call the chord's error a contradiction.  The
chord's error is bounded from the curve's own curvature: the parabolas through the bracketing
points and either neighbour, against the chord, the larger difference, doubled (the parabola is
itself off the curve by the next order: on ln sigma = a (e^q - 1 - q) the difference alone
covers 95 % of the chord's error).  On Figure 9's chart the difference alone is 1.2 to 1.5 times
the distance between the chord and the edge located at that p2 (8 edges at Gamma = 530 to 1172,
where the points are 12 % apart in Gamma).
"""
from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

__all__ = ["chord_error"]


def _first_stretch(curve: Mapping[str, Any], log2: bool) -> tuple[np.ndarray, np.ndarray, bool]:
    """The curve's first monotone stretch in p2, increasing, as (q, y, log_sigma): q = ln p2 (p2 on
    an even axis), y = ln sigma where every sigma is positive (else sigma itself)."""
    p2 = np.asarray(curve["p2"], float)
    x = np.log(p2) if log2 else p2
    y = np.asarray(curve["sigma"], float)
    d = np.sign(np.diff(x))
    n = int(np.argmax(d != d[0])) + 1 if np.any(d != d[0]) else len(x)
    x, y = x[:n], y[:n]
    if d[0] < 0:
        x, y = x[::-1], y[::-1]
    log_sigma = bool(np.all(y > 0))
    return x, (np.log(y) if log_sigma else y), log_sigma


def chord_error(curve: Mapping[str, Any] | None, p2: float, log2: bool = True) -> float:
    """Estimated error in sigma of the curve's linear reading at ``p2`` (0 where the curve has
    fewer than three points on its first stretch or ``p2`` lies outside it: nothing to estimate
    from, and the reading there is not used)."""
    if not curve or "failed" in curve or len(curve.get("p2", ())) < 3 or (log2 and p2 <= 0):
        return 0.0
    x, y, log_sigma = _first_stretch(curve, log2)
    q = math.log(p2) if log2 else p2
    if len(x) < 3 or not x[0] <= q <= x[-1]:
        return 0.0
    i = int(np.clip(np.searchsorted(x, q) - 1, 0, len(x) - 2))
    chord = float(np.interp(q, x, y))
    diffs = [abs(float(np.polyval(np.polyfit(x[j:j + 3], y[j:j + 3], 2), q)) - chord)
             for j in (i - 1, i) if j >= 0 and j + 3 <= len(x)]
    err = 2.0 * max(diffs, default=0.0)
    return math.exp(chord) * math.expm1(err) if log_sigma else err
