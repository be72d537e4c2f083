"""Whether one period on an attractor is enough to label a start: its tolerance balls, run.

The batch kernel can stop a start as soon as its stroboscopic state lands within the matching
tolerance ``tol`` (max norm, with the same wall entries) of a point of a known attractor
(:mod:`harness.fmu.batch_kernel`).  The label is then the fate of a state in the ball of
radius ``tol`` around that point, so that stop is honest when those balls lie inside the
attractor's basin.  This module checks it for each new attractor: a ``(2m + 1) x (2m + 1)``
grid over each of its balls (edges and corners included) runs through the kernel with the
strict rule (the orbit followed for two rounds, against every attractor known), the samples
that it does not recognise are classified in full, as the scan does.  The attractor passes
when every sample reaches it; one that fails (a basin boundary within ``tol`` of its orbit, as
Figure 7's two-impact orbit at sigma = 0.01 has) keeps the strict rule
(:meth:`harness.runs.basins.registry.Registry.known`).  The check is as fine as its grid: it
makes the one-period stop as good as the scan's own resolution, not a proof.
"""
from __future__ import annotations

from typing import Any, Callable, Mapping

import numpy as np

from ...config import SamplingSpec
from ...fmu import batch_kernel as bk
from .tiles import classify_start, match_known

#: Samples per side of each ball's grid: (2 BALL_HALF + 1)^2 per attractor point.
BALL_HALF = 3


def ball_starts(points: np.ndarray, tol: float, half: int = BALL_HALF) -> tuple[np.ndarray, np.ndarray]:
    """The grid over the max-norm ball of radius ``tol`` around each point (k, 2): (u, v)."""
    offs = np.linspace(-tol, tol, 2 * half + 1)
    du, dv = np.meshgrid(offs, offs, indexing="ij")
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    return (pts[:, 0, None] + du.ravel()).ravel(), (pts[:, 1, None] + dv.ravel()).ravel()


def check_balls(params: Mapping[str, Any], s: SamplingSpec, threads: int, known: bk.KnownAttractors, a: int,
                half: int = BALL_HALF) -> dict[str, Any]:
    """Run the balls of attractor ``a`` of ``known`` (whose ``confirm`` is the strict rule's).

    Returns
    -------
    dict
        ``samples`` (run), ``reached`` (how many reached attractor ``a``), ``inside`` (all did),
        ``first_other`` (the first sample that did not, as [u, v], or None).
    """
    p = int(known.period[a])
    us, vs = ball_starts(known.points[a, :p], known.tol, half)
    res = bk.run_batch(params, us, vs, s.theta, s.n_transient, s.n_samples, known, threads)
    ok = (res.status == bk.MATCHED) & (res.label == a)
    for i in np.flatnonzero(res.status == bk.RAN):
        _, cand = classify_start(res, int(i), s)
        ok[i] = cand is not None and match_known(cand, known) == a
    bad = np.flatnonzero(~ok)
    return {"samples": int(us.size), "reached": int(ok.sum()), "inside": bool(bad.size == 0),
            "first_other": None if bad.size == 0 else [float(us[bad[0]]), float(vs[bad[0]])]}


def ball_checker(params: Mapping[str, Any], s: SamplingSpec, threads: int) -> Callable[..., dict[str, Any]]:
    """``check(known, a) -> dict`` (:func:`check_balls`) for a registry."""
    def check(known: bk.KnownAttractors, a: int) -> dict[str, Any]:
        return check_balls(params, s, threads, known, a)

    return check
