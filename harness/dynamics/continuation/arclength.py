"""The pseudo-arclength machinery of :mod:`.continuation`: a branch point with its tangent and
test functions, the predictor-corrector, and the location of events along the arclength.

The unknowns are x = (w, p).  The tangent is the null vector of [D(F^M) - I | dF^M/dp], the cross
product of its two rows.  Located events: the Illinois method (regula falsi) on a test function of
the arclength from the previous point, every trial corrected onto the branch; a change of the
contact pattern by bisection on the arclength, each trial predicted from the last good point.
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

from ..maps.periodic_map import MapEvaluation, PeriodMap

__all__ = ["BranchPoint", "ArclengthCorrector", "CORRECTOR_TOL"]

#: Residual of the corrector: max |F^M(w) - w| (with CVODE, its accuracy where larger:
#: :func:`harness.dynamics.maps.periodic_map.map_accuracy`).
CORRECTOR_TOL = 1e-10


def illinois_update(lo: float, hi: float, flo: float, fhi: float, s: float, f: float,
                    side: int) -> tuple[float, float, float, float, int]:
    """One bracket update of the Illinois method (regula falsi that halves the value kept at the
    end retained twice in a row, so the bracket shrinks from both sides)."""
    if (f > 0) == (flo > 0):
        if side == -1:
            fhi *= 0.5
        return s, hi, f, fhi, -1
    if side == +1:
        flo *= 0.5
    return lo, s, flo, f, +1


class BranchPoint:
    """A point of a branch: x = (w, p), the map's evaluation there (orbit, contacts, D(F^M),
    d/dp), the multipliers and the unit tangent (its orientation is set by the caller)."""

    def __init__(self, w: np.ndarray, p: float, ev: MapEvaluation) -> None:
        self.w, self.p, self.ev = np.asarray(w, dtype=float), float(p), ev
        self.x = np.append(self.w, self.p)
        self.mult = np.linalg.eigvals(ev.J).astype(complex)
        row = np.hstack([ev.J - np.eye(2), ev.dp[:, None]])
        t = np.cross(row[0], row[1])
        self.tangent = t / np.linalg.norm(t)

    def tests(self) -> dict[str, float]:
        J = self.ev.J
        det = float(np.linalg.det(J))
        complex_pair = bool(abs(self.mult[0].imag) > 1e-12)
        return {"fold": float(np.linalg.det(J - np.eye(2))), "flip": float(np.linalg.det(J + np.eye(2))),
                "ns": det - 1.0 if complex_pair else math.nan}


class ArclengthCorrector:
    """Predictor-corrector steps and event location for period-M orbits of ``pmap``."""

    def __init__(self, pmap: PeriodMap, M: int, locate_tol: float) -> None:
        self.pmap, self.M, self.locate_tol = pmap, M, locate_tol
        #: the corrector's residual: CORRECTOR_TOL, or the solver's accuracy over M periods
        self.tol = pmap.tol(M, CORRECTOR_TOL) if hasattr(pmap, "tol") else CORRECTOR_TOL

    def correct(self, x_pred: np.ndarray, t: np.ndarray, max_iter: int = 8,
                lenient: bool = False) -> tuple[BranchPoint | None, int]:
        """Newton on the extended system from ``x_pred``; (point or None, iterations).  With
        ``lenient`` (a step of the walk), an orbit that does not reach :data:`CORRECTOR_TOL` counts
        where the solver cannot tell it from one (``self.tol``: CVODE's accuracy over M periods);
        the location of events keeps the strict residual (a graze's samples and the last orbit
        with the old contacts are fitted and compared to ~1e-10)."""
        x = x_pred.copy()
        best: tuple[float, np.ndarray, MapEvaluation] | None = None
        for it in range(1, max_iter + 1):
            ev = self.pmap.evaluate(x[:2], x[2], self.M)
            g = ev.image - x[:2]
            if not np.all(np.isfinite(g)):
                return None, it
            res = float(np.max(np.abs(g)))
            if abs(t @ (x - x_pred)) < 1e-12:
                if res < CORRECTOR_TOL:
                    return BranchPoint(x[:2], x[2], ev), it
                if best is None or res < best[0]:
                    best = (res, x.copy(), ev)
            A = np.vstack([np.hstack([ev.J - np.eye(2), ev.dp[:, None]]), t])
            rhs = -np.append(g, t @ (x - x_pred))
            try:
                dx = np.linalg.solve(A, rhs)
            except np.linalg.LinAlgError:
                return None, it
            big = float(np.max(np.abs(dx)))
            if big > 0.2:
                dx *= 0.2 / big
            x = x + dx
        # CORRECTOR_TOL out of reach: the best orbit counts where the solver cannot tell it from
        # one (CVODE's accuracy over M periods, ``self.tol``)
        if lenient and best is not None and best[0] < self.tol:
            return BranchPoint(best[1][:2], best[1][2], best[2]), max_iter
        return None, max_iter

    def along(self, a: BranchPoint, ds: float) -> BranchPoint | None:
        """The branch point at arclength ``ds`` from ``a`` (along a's tangent), or None."""
        pt, _ = self.correct(a.x + ds * a.tangent, a.tangent)
        return pt

    def locate_root(self, a: BranchPoint, ds_b: float, fn: Callable[[BranchPoint], float], fa: float,
                    fb: float, valid: Callable[[BranchPoint], bool] | None = None) -> tuple[BranchPoint, float]:
        """Illinois method on s in [0, ds_b] for the test function ``fn``; (point, bracket in p).
        A corrected point that is not ``valid`` (on another branch) counts as a failed correction."""
        lo, hi, flo, fhi = 0.0, ds_b, fa, fb
        best, best_f, side = a, abs(fa), 0
        p_at = {0.0: a.p}
        for _ in range(60):
            s = (lo * fhi - hi * flo) / (fhi - flo)
            pt = self.along(a, s)
            if pt is None or (valid is not None and not valid(pt)):
                s = 0.5 * (lo + hi)
                pt = self.along(a, s)
                if pt is None or (valid is not None and not valid(pt)):
                    break
            f = fn(pt)
            p_at[s] = pt.p
            if abs(f) < best_f or best is a:
                best, best_f = pt, abs(f)
            if not math.isfinite(f) or f == 0.0 or abs(f) < 1e-14:
                return pt, 0.0
            lo, hi, flo, fhi, side = illinois_update(lo, hi, flo, fhi, s, f, side)
            # the bracket in arclength (the parameter may be at a turning point, where its own
            # bracket says nothing), with the parameter's rate along the tangent
            if (hi - lo) * max(abs(a.tangent[2]), 1e-3) < self.locate_tol:
                break
        bracket = abs(p_at.get(hi, best.p) - p_at.get(lo, a.p)) if hi in p_at and lo in p_at else (hi - lo)
        return best, bracket

    def locate_contact_change(self, a: BranchPoint, ds_b: float) -> tuple[BranchPoint, float, BranchPoint | None]:
        """Bisection on s in [0, ds_b] on 'same contacts as a'; (last good, bracket in p, first
        bad point if it converged there)."""
        lo, hi = 0.0, ds_b
        good, bad = a, None
        rate = max(abs(a.tangent[2]), 1e-300)  # dp/ds along the tangent: the bracket in p
        for _ in range(80):
            if (hi - lo) * rate < self.locate_tol or hi - lo < 1e-15:
                break
            # predict from the last good point (not from a): a short step the corrector can make
            # even next to the corner of a nonsmooth fold
            pt = self.along(good, 0.5 * (hi - lo))
            if pt is not None and np.array_equal(pt.ev.contacts, a.ev.contacts):
                if pt.tangent @ good.tangent < 0:
                    pt.tangent = -pt.tangent
                lo, good = lo + 0.5 * (hi - lo), pt
                rate = max(abs(good.tangent[2]), 1e-300)
            else:
                hi, bad = lo + 0.5 * (hi - lo), pt
        return good, (hi - lo) * rate, bad
