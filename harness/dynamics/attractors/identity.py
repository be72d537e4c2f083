"""Attractors told apart by their stroboscopic orbits, and basins of attraction.

A basin scan starts the oscillator from every (u0, v0) of a grid at the section time theta and
samples where each start ends up (a fresh 2D sweep over the initial state, parallel and
resumable: :func:`harness.runs.basins.scan.run_basins`).  This module turns those end states
into attractors.  Two starts reach the same attractor when their sampled orbits are the same
set of points: the same period, the same wall entries per period, and every point of one orbit
within ``match_tol`` of a point of the other (the Hausdorff distance of the two point sets).
The period alone would merge coexisting orbits of equal period -- the norm near grazing, where a
non-impacting and an impacting period-1 orbit coexist.

Starts whose samples are not periodic (chaotic, quasi-periodic, or not converged in the
transient) cannot be matched point by point; they form one class, ``NOT_PERIODIC``, and the
scan's ``dynamics`` variable says which of the three each one is when Lyapunov exponents were
asked for.  Starts the FMU refused (inside a rigid wall) are ``INVALID``.  The batch kernel's
scans (:mod:`harness.runs.basins.kernel_scan`) add two labels: ``STICKING`` for a start that is
not periodic and sticks on the wall or chatters (many wall entries in one period) at its
samples -- the slow regions of the flow that a recurrence test could take for an attractor --
and ``ESCAPED`` for one that left every bound or that the closed form could not continue.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Label of a start whose samples have no period (see the module docstring).
NOT_PERIODIC = -1
#: Label of a start that was not run: the FMU refused it (a start inside a rigid wall).
INVALID = -2
#: Label of a start that is not periodic and sticks or chatters at its samples (batch kernel).
STICKING = -3
#: Label of a start that escaped (|u| or |v| beyond every bound) or failed (batch kernel).
ESCAPED = -4
#: Wall entries in one forcing period from which a non-periodic start counts as chattering.
CHATTER_ENTRIES = 8
#: What each label below 0 means (the NetCDF flags and the figure's legend).
LABEL_NAMES = {NOT_PERIODIC: "not periodic", INVALID: "invalid start", STICKING: "sticking or chatter",
               ESCAPED: "escaped or failed"}


@dataclass(frozen=True)
class Attractor:
    """One periodic attractor found by a basin scan.

    Attributes
    ----------
    label : int
        Its index in the scan's ``attractor`` variable (0, 1, ...; in order of basin size).
    period : int
        Period of the stroboscopic orbit in forcing periods.
    impacts : int
        Wall entries over one orbit period.
    points : numpy.ndarray
        The ``period`` stroboscopic points (u, v), shape (period, 2), starting with the point of
        smallest u (so that equal orbits read equally).
    starts : int
        Grid points in its basin.
    """

    label: int
    period: int
    impacts: int
    points: np.ndarray
    starts: int

    @property
    def name(self) -> str:
        """E.g. ``"A0: P2, 1 impact"``."""
        s = "" if self.impacts == 1 else "s"
        return f"A{self.label}: P{self.period}, {self.impacts} impact{s}"


def orbit_points(u: np.ndarray, v: np.ndarray, period: int) -> np.ndarray:
    """The last ``period`` samples as points (u, v), rotated to start at the smallest u."""
    pts = np.column_stack([u[-period:], v[-period:]])
    return np.roll(pts, -int(np.argmin(pts[:, 0])), axis=0)


def hausdorff(a: np.ndarray, b: np.ndarray) -> float:
    """Hausdorff distance (max norm) of two point sets of shape (n, 2) and (m, 2)."""
    d = np.max(np.abs(a[:, None, :] - b[None, :, :]), axis=2)
    return float(max(d.min(axis=1).max(), d.min(axis=0).max()))


def identify_attractors(u: np.ndarray, v: np.ndarray, period: np.ndarray, orbit_impacts: np.ndarray,
                        match_tol: float) -> tuple[np.ndarray, list[Attractor]]:
    """Label every start by the attractor its samples reached.

    Parameters
    ----------
    u, v : numpy.ndarray
        Stroboscopic samples, shape (..., samples): any grid of starts, the samples last.
    period, orbit_impacts : numpy.ndarray
        Per start (shape ``u.shape[:-1]``): the orbit period (> 0 periodic, 0 not periodic,
        < 0 not run) and the wall entries per orbit period.
    match_tol : float
        Largest Hausdorff distance (max norm, in the units of u and v) between two orbits of
        one attractor.  It must exceed the sampling tolerance the periods were found with and be
        smaller than the distance between distinct attractors.

    Returns
    -------
    labels : numpy.ndarray of int
        Shape ``period.shape``: the attractor's label, :data:`NOT_PERIODIC` or :data:`INVALID`.
    attractors : list of Attractor
        Labelled 0, 1, ... by decreasing basin size (ties: by period, then smallest u).
    """
    if not (np.isfinite(match_tol) and match_tol > 0):
        raise ValueError(f"match_tol must be a finite number > 0, got {match_tol!r}")
    shape = period.shape
    u2, v2 = u.reshape(-1, u.shape[-1]), v.reshape(-1, v.shape[-1])
    per, imp = period.reshape(-1), orbit_impacts.reshape(-1)
    raw = np.full(per.size, NOT_PERIODIC, dtype=np.int64)
    raw[per < 0] = INVALID
    found: list[tuple[int, int, np.ndarray]] = []  # (period, impacts, points)
    for i in np.flatnonzero(per > 0):
        p, k = int(per[i]), int(imp[i])
        pts = orbit_points(u2[i], v2[i], p)
        for j, (pj, kj, ref) in enumerate(found):
            if pj == p and kj == k and hausdorff(pts, ref) <= match_tol:
                raw[i] = j
                break
        else:
            raw[i] = len(found)
            found.append((p, k, pts))
    counts = np.bincount(raw[raw >= 0], minlength=len(found))
    order = sorted(range(len(found)), key=lambda j: (-counts[j], found[j][0], found[j][2][0, 0]))
    relabel = np.empty(len(found), dtype=np.int64)
    relabel[order] = np.arange(len(found))
    labels = raw.copy()
    labels[raw >= 0] = relabel[raw[raw >= 0]]
    attractors = [Attractor(int(relabel[j]), found[j][0], found[j][1], found[j][2], int(counts[j])) for j in order]
    return labels.reshape(shape), attractors
