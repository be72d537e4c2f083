"""One tile of a batch-kernel basin scan, run on a worker: the starts through the kernel
(:mod:`harness.fmu.batch_kernel`), early-stopped on the attractors known when the tile was
sent, and the starts that ran in full classified here from their samples.

Kept free of xarray and Dask so that a worker imports only numpy and the kernel's loader.
A tile's result names known attractors by their index; a periodic orbit that matches none is
returned as a *candidate* (period, wall entries, points in orbit order), which the scan merges
into its list (:mod:`harness.runs.basins.kernel_scan`), so two tiles that find the same new
attractor at the same time agree on it.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...config import SamplingSpec
from ...dynamics.attractors.identity import (
    CHATTER_ENTRIES,
    ESCAPED,
    INVALID,
    NOT_PERIODIC,
    STICKING,
    hausdorff,
)
from ...dynamics.maps.classify import classify_orbit
from ...fmu import batch_kernel as bk

#: Labels of a tile below this are candidates: CANDIDATE - k is the tile's k-th candidate.
CANDIDATE = -100


@dataclass(frozen=True)
class Candidate:
    """A periodic orbit a tile found that matched no known attractor."""

    period: int
    impacts: int
    points: np.ndarray   # (period, 2), consecutive in time, the last sample last
    entries: np.ndarray  # (period,), wall entries of the period ending on each point
    stuck: bool


@dataclass(frozen=True)
class BasinTile:
    """The starts of one tile and what they run with."""

    index: int
    u0: np.ndarray
    v0: np.ndarray
    params: dict[str, Any] = field(hash=False)
    sampling: SamplingSpec
    known: bk.KnownAttractors
    threads: int = 1


def candidate_of(u: np.ndarray, v: np.ndarray, impacts: np.ndarray, stuck: np.ndarray, period: int,
                 orbit_impacts: int) -> Candidate:
    """The last ``period`` samples of a periodic start, in time order."""
    return Candidate(period, orbit_impacts, np.column_stack([u[-period:], v[-period:]]),
                     np.asarray(impacts[-period:], dtype=np.int32), bool(np.any(stuck[-period:])))


def match_known(c: Candidate, known: bk.KnownAttractors) -> int:
    """The known attractor with ``c``'s period and wall entries within the known tolerance of it
    (Hausdorff distance of the point sets, as :func:`harness.dynamics.attractors.identity.identify_attractors`),
    or -1."""
    for a in range(known.period.size):
        p = int(known.period[a])
        if p == c.period and int(known.entries[a, :p].sum()) == c.impacts \
                and hausdorff(c.points, known.points[a, :p]) <= known.tol:
            return a
    return -1


def classify_start(res: bk.BatchResult, i: int, s: SamplingSpec) -> tuple[int, Candidate | None]:
    """Label of start ``i`` that ran in full: a negative code, or -1 with its candidate."""
    u, v, imp, stuck = res.u[i], res.v[i], res.impacts[i], res.stuck[i].astype(bool)
    orbit = classify_orbit(u, v, imp, s.tol, s.max_period)
    if orbit.periodic:
        return -1, candidate_of(u, v, imp, stuck, orbit.period, orbit.impacts)
    # the slow regions of the flow get a label of their own, never an attractor's
    if np.any(stuck) or int(np.max(imp)) >= CHATTER_ENTRIES:
        return STICKING, None
    return NOT_PERIODIC, None


def orbit_periods(u: np.ndarray, v: np.ndarray, impacts: np.ndarray, s: SamplingSpec) -> tuple[np.ndarray, np.ndarray]:
    """Per row of samples (starts, samples): :func:`harness.dynamics.maps.classify.classify_orbit`'s
    period (0: not periodic) and wall entries per period, for all rows at once -- the same test
    on the same numbers (the smallest shift m <= the largest period whose residual, the largest
    |difference| of u and v m samples apart, is within tol (1 + the largest peak-to-peak range)
    and whose wall entries repeat; a row with a NaN is not periodic), so the same verdicts."""
    rows, n = u.shape if u.ndim == 2 else (u.shape[0], 0)
    period = np.zeros(rows, dtype=np.int64)
    entries = np.full(rows, -1, dtype=np.int64)
    if n < 2 or rows == 0:
        return period, entries
    finite = np.all(np.isfinite(u), axis=1) & np.all(np.isfinite(v), axis=1)
    mp = max(1, min(s.max_period if s.max_period is not None else n // 2, n - 1))
    with np.errstate(invalid="ignore"):
        thr = s.tol * (1.0 + np.maximum(np.ptp(u, axis=1), np.ptp(v, axis=1)))
        open_ = finite.copy()
        for m in range(1, mp + 1):
            r = np.maximum(np.max(np.abs(u[:, m:] - u[:, :-m]), axis=1), np.max(np.abs(v[:, m:] - v[:, :-m]), axis=1))
            hit = open_ & (r <= thr) & np.all(impacts[:, m:] == impacts[:, :-m], axis=1)
            period[hit] = m
            entries[hit] = impacts[hit, n - m:].sum(axis=1)
            open_ &= ~hit
    return period, entries


def run_tile(tile: BasinTile, source: Any = None, progress: Any = None) -> dict[str, Any]:
    """Run a tile (on any worker: ``source`` and ``progress`` are the backends' arguments, unused).

    Returns
    -------
    dict
        As :func:`label_result`, with ``index``.
    """
    s = tile.sampling
    res = bk.run_batch(tile.params, tile.u0, tile.v0, s.theta, s.n_transient, s.n_samples, tile.known,
                       threads=tile.threads)
    return {"index": tile.index, **label_result(res, s, tile.known)}


def label_result(res: bk.BatchResult, s: SamplingSpec, known: bk.KnownAttractors) -> dict[str, Any]:
    """Labels of the kernel's starts.

    Returns
    -------
    dict
        ``label`` (int32, per start): a known attractor, a negative code of
        :mod:`harness.dynamics.attractors.identity`, or ``CANDIDATE - k``; ``periods`` (forcing periods each
        start ran); ``candidates`` (list of :class:`Candidate`); ``error`` (the first failure).
    """
    label = res.label.astype(np.int32).copy()
    label[res.status == bk.INVALID] = INVALID
    label[(res.status == bk.FAILED) | (res.status == bk.ESCAPED)] = ESCAPED
    candidates: list[Candidate] = []
    ran = np.flatnonzero(res.status == bk.RAN)
    period, entries = orbit_periods(res.u[ran], res.v[ran], res.impacts[ran], s)
    # classify_start's verdict on a start that reached no period, and on one stopped as soon as its
    # samples ruled a period out (its samples so far say whether it stuck or chattered)
    never = np.concatenate([ran[period == 0], np.flatnonzero(res.status == bk.APERIODIC)])
    slow = np.any(res.stuck[never], axis=1) | (np.max(res.impacts[never], axis=1, initial=-1) >= CHATTER_ENTRIES)
    label[never] = np.where(slow, STICKING, NOT_PERIODIC)
    for i, p, e in zip(ran[period > 0], period[period > 0], entries[period > 0]):
        cand = candidate_of(res.u[i], res.v[i], res.impacts[i], res.stuck[i].astype(bool), int(p), int(e))
        a = match_known(cand, known)
        if a < 0:
            for k, other in enumerate(candidates):
                if other.period == cand.period and other.impacts == cand.impacts \
                        and hausdorff(other.points, cand.points) <= known.tol:
                    a = CANDIDATE - k
                    break
            else:
                a = CANDIDATE - len(candidates)
                candidates.append(cand)
        label[i] = a
    return {"label": label, "periods": res.periods.astype(np.int32), "candidates": candidates, "error": res.error}
