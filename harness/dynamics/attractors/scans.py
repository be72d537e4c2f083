"""Periodic attractors of the FMU's stroboscopic map, found from the ODE alone (no map guide).

For every value of a parameter (sigma by default) the FMU is run from several starts:

* ``up`` / ``down``: the final state at the previous value (a hysteresis scan each way, so an
  orbit is followed while it exists and coexisting ones are reached from both sides);
* ``fresh:<name>``: each of :data:`DEFAULT_STARTS` (at rest, near the wall, on the wall-free
  orbit), or states given by the caller.

After the transient the stroboscopic points are searched for the smallest period M <= M_max;
each periodic candidate is refined by Newton on F^M(w) = w with the FMU's exact Jacobian
(:func:`.periodic_map.refine_orbit`), which also gives its multipliers.  Orbits found by several
starts are merged when they are the same orbit (same period, a common point within ``match``);
different orbits at one parameter value (coexisting attractors) are kept apart.  A start whose
samples are not periodic up to M_max contributes nothing (its count is kept in
:attr:`AttractorScan.not_periodic`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from ..maps.periodic_map import PeriodMap, refine_orbit
from ...errors import HarnessInputError
from ...fmu.simulator import Simulator

__all__ = ["Attractor", "AttractorScan", "DEFAULT_STARTS", "find_attractors", "families"]

#: Fresh starts (u, v) at t = theta; None: on the wall-free orbit p(theta) of (4).
DEFAULT_STARTS: dict[str, tuple[float, float] | None] = {
    "rest": (-1.0, 0.0), "near-wall": (-1e-3, 0.0), "wall-free": None}


@dataclass
class Attractor:
    """A stable periodic orbit of the stroboscopic map at one parameter value.

    Attributes
    ----------
    param : str
    value : float
        The parameter value.
    period : int
        M, in forcing periods.
    impacts : int
        Wall entries (impacts) per period M of the orbit.
    points : ndarray (M, 2)
        Stroboscopic points (u, v) at t = theta + k, Newton-refined; ``points[0]`` follows the
        orbit's first impacting period (a canonical rotation, so orbits compare point by point).
    contacts : ndarray of int (M,)
        Contacts in each period, starting at ``points[0]``.
    multipliers : ndarray complex (2,)
        Eigenvalues of D(F^M) (the FMU's exact Jacobian when it reports one).
    residual : float
        max |F^M(z) - z| after Newton.
    found_by : list of str
        Which scans reached it ("up", "down", "fresh:rest", ...).
    theta : float
        Section phase.
    """

    param: str
    value: float
    period: int
    impacts: int
    points: np.ndarray
    contacts: np.ndarray
    multipliers: np.ndarray
    residual: float
    found_by: list[str] = field(default_factory=list)
    theta: float = 0.5

    @property
    def stable(self) -> bool:
        return bool(np.all(np.abs(self.multipliers) < 1.0))

    @property
    def label(self) -> str:
        """E.g. "P2/1" (period 2, one impact per period)."""
        return f"P{self.period}/{self.impacts}"

    def same_orbit(self, other: "Attractor", match: float) -> bool:
        """Same period and a common stroboscopic point within ``match`` (max norm)."""
        if self.period != other.period:
            return False
        d = np.max(np.abs(other.points - self.points[0]), axis=1)
        return bool(d.min() <= match)


@dataclass
class AttractorScan:
    """What :func:`find_attractors` searched and found.

    Attributes
    ----------
    attractors : list of Attractor
        Sorted by (value, period, impacts).
    values : ndarray
        Parameter values scanned.
    scans : list of str
        Scans run at every value.
    M_max, transient : int
    not_periodic : int
        Runs whose samples were not periodic up to M_max (or whose Newton failed).
    periods_run : int
        FMU periods integrated in all.
    """

    attractors: list[Attractor]
    values: np.ndarray
    scans: list[str]
    M_max: int
    transient: int
    not_periodic: int = 0
    periods_run: int = 0

    def at(self, value: float) -> list[Attractor]:
        """The attractors found at one scanned value."""
        return [a for a in self.attractors if a.value == value]


def _detect_period(pts: np.ndarray, M_max: int, tol: float) -> int | None:
    """Smallest M <= M_max with z_{k+M} = z_k (to ``tol``) over the last M_max samples."""
    last = pts[-M_max - 1:]
    for M in range(1, M_max + 1):
        if np.max(np.abs(last[M:] - last[:-M])) <= tol * max(1.0, float(np.max(np.abs(last)))):
            return M
    return None


def _canonical(pts: np.ndarray, cont: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotate the orbit so that it starts right after its first impacting period."""
    if cont.any():
        k = (int(np.argmax(cont > 0)) + 1) % len(cont)
        return np.roll(pts, -k, axis=0), np.roll(cont, -k)
    return pts, cont


def find_attractors(sim: Simulator, params: Mapping[str, Any], values: Sequence[float], param: str = "sigma",
                    M_max: int = 8, theta: float = 0.5, transient: int = 300,
                    starts: Mapping[str, tuple[float, float] | None] | None = None,
                    scans: Sequence[str] = ("up", "down", "fresh"), detect_tol: float = 1e-6,
                    match: float = 1e-5, derivatives: str = "auto", progress: Any = None) -> AttractorScan:
    """Periodic attractors over a range of a parameter, from the ODE alone.

    Parameters
    ----------
    sim : Simulator
        The FMU (``solver`` = 1, the closed form, is ~30x faster than CVODE).
    params : mapping
        FMU parameters (nu, Omega, r, wall, Gamma, ...).
    values : sequence of float
        Parameter values, in the order of the ``up`` scan (``down`` runs them reversed).
    param : str
        The parameter scanned (default sigma).
    M_max : int
        Longest period searched.
    theta : float
        Section phase (1/2: away from the impacts near t = n).
    transient : int
        Periods run before the period is detected (``up``/``down``: after each step of the
        parameter; the state carried over is already near the attractor).
    starts : mapping name -> (u, v) or None, optional
        Fresh starts at t = theta (None: on the wall-free orbit); default :data:`DEFAULT_STARTS`.
    scans : sequence of {"up", "down", "fresh"}
    detect_tol : float
        Relative tolerance of the periodicity test on the samples (Newton then refines).
    match : float
        Two orbits are the same when they share a point within this (max norm).
    derivatives : {"auto", "exact", "fd"}
        Jacobian of the Newton refinement and the multipliers.
    progress : tqdm-like, optional
        Updated once per (value, scan).

    Returns
    -------
    AttractorScan
    """
    values = np.asarray(values, dtype=float)
    if values.size == 0 or not np.all(np.isfinite(values)):
        raise HarnessInputError("values", "needs at least one finite parameter value")
    if M_max < 1:
        raise HarnessInputError("M_max", f"must be >= 1, got {M_max}")
    bad = set(scans) - {"up", "down", "fresh"}
    if bad:
        raise HarnessInputError("scans", f"unknown scan(s) {sorted(bad)}; use up, down, fresh")
    pmap = PeriodMap(sim, params, param, theta, derivatives)
    starts = dict(DEFAULT_STARTS if starts is None else starts)
    search = _Search(pmap, AttractorScan([], values, list(scans), M_max, transient), detect_tol, match, param, theta)
    for direction in [s for s in scans if s in ("up", "down")]:
        order = values if direction == "up" else values[::-1]
        z = np.array(starts.get("rest") or (-1.0, 0.0), dtype=float)
        for p in order:
            z = search.settle(float(p), z, direction)
            if progress is not None:
                progress.update(1)
    if "fresh" in scans:
        for p in values:
            for name, z0 in starts.items():
                z = pmap.offset(float(p)) if z0 is None else np.asarray(z0, dtype=float)
                search.settle(float(p), z, f"fresh:{name}")
            if progress is not None:
                progress.update(1)
    scan = search.scan
    scan.attractors.sort(key=lambda a: (a.value, a.period, a.impacts))
    scan.periods_run = pmap.evaluations
    return scan


class _Search:
    """The attractors found so far by :func:`find_attractors`, and how a run from a state is
    turned into one of them.

    Parameters
    ----------
    pmap : PeriodMap
    scan : AttractorScan
        Filled as runs settle (its ``attractors`` and ``not_periodic``).
    detect_tol, match, param, theta
        As in :func:`find_attractors`.
    """

    def __init__(self, pmap: PeriodMap, scan: AttractorScan, detect_tol: float, match: float, param: str,
                 theta: float) -> None:
        self.pmap, self.scan, self.detect_tol, self.match = pmap, scan, detect_tol, match
        self.param, self.theta = param, theta

    def settle(self, p: float, z0: np.ndarray, name: str) -> np.ndarray:
        """Run from z0, record the orbit reached (if periodic), return the final state."""
        pmap, scan = self.pmap, self.scan
        off = pmap.offset(p)
        pts, _ = pmap.run(p, z0, scan.transient)
        z = pts[-1]
        pts, cont = pmap.run(p, z, 2 * scan.M_max + 1)
        if not np.all(np.isfinite(pts)):
            scan.not_periodic += 1
            return pts[-1]
        w, ev, ok, res, M = self.refine(p, pts, off)
        if not ok:
            scan.not_periodic += 1
            return pts[-1]
        # a slowly converging orbit (a multiplier near -1) passes the sample test at 2M first:
        # the refined orbit has the true (smallest) period
        for d in range(1, M):
            if M % d == 0 and np.max(np.abs(ev.points[d] - ev.points[0])) <= self.match:
                w, ev, ok, res = refine_orbit(pmap, w, p, d)
                if ok:
                    M = d
                    break
        orb_pts, orb_cont = _canonical(ev.points, ev.contacts)
        self.add(Attractor(self.param, float(p), M, int(ev.contacts.sum()), orb_pts, orb_cont,
                           np.linalg.eigvals(ev.J).astype(complex), res, [name], self.theta))
        return w + off

    def refine(self, p: float, pts: np.ndarray, off: np.ndarray) -> tuple[Any, Any, bool, float, int]:
        """Newton on the orbit the samples ``pts`` settled on: (w, ev, ok, residual, period)."""
        pmap, M_max = self.pmap, self.scan.M_max
        M = _detect_period(pts, M_max, self.detect_tol)
        if M is not None:
            w, ev, ok, res = refine_orbit(pmap, pts[-1] - off, p, M)
            return w, ev, ok, res, M
        # not yet periodic to detect_tol: a slow transient (a multiplier near the unit
        # circle, next to a bifurcation) still ends near its orbit; Newton from there, for
        # each period, accepting a stable orbit that the samples are close to
        ok = False
        spread = float(np.max(np.abs(pts[-M_max - 1:] - pts[-1]))) + 1e-12
        for M in range(1, M_max + 1):
            w, ev, ok, res = refine_orbit(pmap, pts[-1] - off, p, M)
            ok = (ok and bool(np.all(np.abs(np.linalg.eigvals(ev.J)) < 1.0))
                  and float(np.max(np.abs(ev.points[0] - pts[-1]))) < 10 * spread)
            if ok:
                break
        return w, ev, ok, res, M

    def add(self, cand: Attractor) -> None:
        """Record ``cand``, or its finder's name on the same orbit found before."""
        name = cand.found_by[0]
        for a in self.scan.attractors:
            if a.value == cand.value and a.same_orbit(cand, self.match):
                if name not in a.found_by:
                    a.found_by.append(name)
                break
        else:
            self.scan.attractors.append(cand)


def families(attractors: Sequence[Attractor], match: float = 1e-2) -> list[list[Attractor]]:
    """Group attractors into families: same (period, impacts) at neighbouring scanned values,
    each point within ``match`` of the family's previous one.  A seed for continuation is any
    member; coexisting families stay apart.
    """
    values = sorted({a.value for a in attractors})
    index = {v: i for i, v in enumerate(values)}
    fams: list[list[Attractor]] = []
    for a in sorted(attractors, key=lambda a: a.value):
        for fam in fams:
            last = fam[-1]
            if (index[a.value] == index[last.value] + 1 and (last.period, last.impacts) == (a.period, a.impacts)
                    and last.same_orbit(a, match)):
                fam.append(a)
                break
        else:
            fams.append([a])
    return fams
