"""Two-parameter continuation of the bifurcations of a periodic orbit: flip, fold and
Neimark-Sacker curves in the plane of sigma and a second FMU parameter, graze curves beside them.

A located event of a branch (:func:`harness.dynamics.continuation.continue_orbit.continue_orbit`) is a point of a
curve in the plane (sigma, p2).  Smooth events (flip, fold, NS) are continued on the extended
system in the unknowns X = (w1, w2, s, q) / (1 + sigma, 1 + sigma, 1, 1), with s = ln sigma
(sigma itself on a range reaching sigma <= 0: :mod:`.sigma_axis`) and q = p2 (ln p2 on a log axis):

    F^M(w; sigma, p2) - w = 0            the period-M orbit (w: coordinates of .periodic_map)
    phi(w; sigma, p2)     = 0            its test function: det(D + I) (flip), det(D - I) (fold),
                                         det D - 1 with a complex pair (NS: |mu|^2 = det D)

(the minimally augmented system of MatCont and BifurcationKit.jl, with the determinants as test
functions since D(F^M) is 2 x 2), by pseudo-arclength: the tangent is the null vector of the
3 x 4 Jacobian (SVD), the corrector Newton's method on the system bordered by the tangent.  The
orbit's block of the Jacobian is exact (the FMU's variational equations: D(F^M), d/dsigma); the
columns in p2 and the gradient of phi are central differences.

Along a smooth-event curve, between accepted points:

* a **turning point** in p2 (the tangent's p2 component changes sign) is located; when both edges
  of a window lie on the curve, the window closes there (its two edges meet);
* a change of the orbit's **contact pattern** ends the curve: a free passage of the orbit on the
  curve reaches the wall, the event meets the orbit's graze curve (a codimension-two point);
  beyond it the orbit with this pattern is virtual.  Located by bisection on the arclength, with
  the gap (:meth:`PeriodMap.gap`) at the last good point as the check that it is a graze.

A graze is not a smooth event of the FMU's flow: a free passage that penetrates the wall by d
changes the orbit by ~sqrt(d) (the square-root singularity this project is about), so an
extended system through the graze would be solved on a nonsmooth function.  Graze curves are
followed by :func:`harness.dynamics.curves.graze_curves.continue_graze` instead: a step along the curve,
then the graze located across it on the smooth side (bisection on the contact pattern, then secant
steps on the gap).
"""
from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from ..continuation.arclength import illinois_update
from .curve import CurvePoint, EventCurve, significant_turns
from ..maps.periodic_map import MapEvaluation, PeriodMap, failed_evaluation
from .sigma_axis import LOG, SigmaAxis, sigma_axis
from ..continuation.step_control import StepControl
from ...errors import FmuRejectedInput, HarnessInputError
from ...fmu.simulator import Simulator

__all__ = ["CurvePoint", "EventCurve", "PlaneMap", "continue_event", "significant_turns", "SMOOTH_KINDS"]

SMOOTH_KINDS = ("flip", "fold", "ns")

#: Residual of the corrector on the orbit (max |F^M(w) - w|) and on the test function.
ORBIT_TOL = 1e-10
TEST_TOL = 1e-9

#: A gap (relative to 1 + sigma) below this where the corrector fails: the event meets a graze.
GRAZE_GAP = 1e-5


class PlaneMap:
    """F^M of the FMU over X = (w, s, q), with the test functions and their derivatives.

    Parameters
    ----------
    pmap : PeriodMap
        The period map in sigma (its ``params`` are updated with p2 at each evaluation).
    param2 : str
        The second parameter.
    log2 : bool
        q = ln p2 (True) or p2.
    M : int
    axis : SigmaAxis
        s = ln sigma (the default) or sigma (a range reaching sigma <= 0).
    """

    def __init__(self, pmap: PeriodMap, param2: str, log2: bool, M: int, axis: SigmaAxis = LOG) -> None:
        if pmap.param != "sigma":
            raise HarnessInputError("pmap", "event curves are continued in sigma and a second parameter")
        if param2 in ("sigma", "u0", "v0", "wall", "solver", "contact", "sensitivities"):
            raise HarnessInputError("param2", f"{param2!r} cannot be the second parameter")
        self.pmap, self.param2, self.log2, self.M, self.axis = pmap, param2, log2, M, axis
        self.base = dict(pmap.params)

    def p2(self, q: float) -> float:
        return math.exp(q) if self.log2 else float(q)

    def q(self, p2: float) -> float:
        return math.log(p2) if self.log2 else float(p2)

    def scale(self, X: np.ndarray) -> float:
        """c = 1 + sigma (> 0): the orbit's w is stored as w / c, since the orbit grows like the
        forcing (so that steps in ln sigma are not throttled by the orbit's size at large sigma)."""
        return 1.0 + self.axis.of(float(X[2]))

    def w(self, X: np.ndarray) -> np.ndarray:
        return np.asarray(X[:2]) * self.scale(X)

    def evaluate(self, X: np.ndarray, derivatives: bool = True) -> MapEvaluation:
        """F^M at X (in w coordinates), with D(F^M) and d/dsigma when ``derivatives``."""
        self.pmap.params = {**self.base, self.param2: self.p2(float(X[3]))}
        try:
            return self.pmap.evaluate(self.w(X), self.axis.of(float(X[2])), self.M, derivatives)
        except FmuRejectedInput:
            # a corrector step beyond the FMU's domain of the second parameter (r > 1 near the end of
            # a range reaching 0.95): a failed step (shorter, or the curve's end), not the chart's end
            return failed_evaluation(self.M, derivatives)

    def test(self, kind: str, ev: MapEvaluation, X: np.ndarray) -> float:
        """The event's test function at an evaluation."""
        J = ev.J
        if kind == "flip":
            return float(np.linalg.det(J + np.eye(2)))
        if kind == "fold":
            return float(np.linalg.det(J - np.eye(2)))
        if kind == "ns":
            return float(np.linalg.det(J)) - 1.0
        raise HarnessInputError("kind", f"unknown event {kind!r} (flip, fold, ns)")

    def residual(self, kind: str, X: np.ndarray) -> tuple[np.ndarray, MapEvaluation]:
        ev = self.evaluate(X)
        return np.append((ev.image - self.w(X)) / self.scale(X), self.test(kind, ev, X)), ev

    def jacobian(self, kind: str, X: np.ndarray, ev: MapEvaluation) -> np.ndarray:
        """3 x 4: the orbit's rows (exact in w and sigma, a central difference in q) and the test
        function's gradient (central differences).  With c = 1 + sigma and w = c X[:2], the orbit's
        residual (F^M(w) - w) / c has d/dX[:2] = D - I and d/ds = (dsigma/ds / c) ((D - I) X[:2] +
        dF^M/dsigma - residual), dsigma/ds = sigma on the log axis."""
        c = 1.0 + self.axis.of(float(X[2]))
        A = np.zeros((3, 4))
        A[:2, :2] = ev.J - np.eye(2)
        res = (ev.image - self.w(X)) / c
        A[:2, 2] = (self.axis.dsigma_ds(float(X[2])) / c) * ((ev.J - np.eye(2)) @ X[:2] + ev.dp - res)
        hq = 1e-6 * max(1.0, abs(float(X[3])))
        e = np.zeros(4)
        e[3] = hq
        A[:2, 3] = (self.evaluate(X + e, False).image - self.evaluate(X - e, False).image) / (2.0 * hq * c)
        for j, h in enumerate((1e-7, 1e-7, 1e-7, hq)):
            e = np.zeros(4)
            e[j] = h
            fp = self.test(kind, self.evaluate(X + e), X + e)
            fm = self.test(kind, self.evaluate(X - e), X - e)
            A[2, j] = (fp - fm) / (2.0 * h)
        return A


def _tangent(A: np.ndarray, prev: np.ndarray | None) -> np.ndarray:
    t = np.linalg.svd(A)[2][-1]
    if prev is not None and t @ prev < 0:
        t = -t
    return t


def _same_pattern(a: np.ndarray, b: np.ndarray) -> bool:
    return any(np.array_equal(np.roll(a, k), b) for k in range(len(a)))


class _Corrector:
    def __init__(self, plane: PlaneMap, kind: str) -> None:
        self.plane, self.kind = plane, kind

    def correct(self, X_pred: np.ndarray, t: np.ndarray, max_iter: int = 10) -> CurvePoint | None:
        """Newton on the extended system bordered by the tangent; None when it fails."""
        X = X_pred.copy()
        for _ in range(max_iter):
            H, ev = self.plane.residual(self.kind, X)
            if not np.all(np.isfinite(H)) or ev.J is None:
                return None
            A = self.plane.jacobian(self.kind, X, ev)
            B = np.vstack([A, t])
            rhs = -np.append(H, t @ (X - X_pred))
            try:
                dX = np.linalg.solve(B, rhs)
            except np.linalg.LinAlgError:
                return None
            if not np.all(np.isfinite(dX)):
                return None
            big = float(np.max(np.abs(dX)))
            if big > 0.2:
                dX *= 0.2 / big
            X = X + dX
            if (float(np.max(np.abs(H[:2]))) < ORBIT_TOL and abs(H[2]) < TEST_TOL and big < 1e-9):
                ev = self.plane.evaluate(X)
                return CurvePoint(X, self.plane.axis.of(float(X[2])), self.plane.p2(float(X[3])), ev,
                                  _tangent(self.plane.jacobian(self.kind, X, ev), t))
        return None

    def along(self, a: CurvePoint, ds: float) -> CurvePoint | None:
        return self.correct(a.X + ds * a.tangent, a.tangent)


def _start(corr: _Corrector, w0: np.ndarray, sigma0: float, p2_0: float, direction: float) -> CurvePoint:
    plane = corr.plane
    X0 = np.array([w0[0] / (1.0 + sigma0), w0[1] / (1.0 + sigma0), plane.axis.to(sigma0), plane.q(p2_0)])
    H, ev = plane.residual(corr.kind, X0)
    if not np.all(np.isfinite(H)):
        raise HarnessInputError("sigma0", f"the FMU's map is not finite at sigma = {sigma0:g}")
    t = _tangent(plane.jacobian(corr.kind, X0, ev), None)
    if t[3] * direction < 0:
        t = -t
    pt = corr.correct(X0, t)
    if pt is None:
        raise HarnessInputError("z0", f"no {corr.kind} point of a period-{plane.M} orbit near sigma = "
                                f"{sigma0:.10g}, {plane.param2} = {p2_0:g} (Newton on the extended system failed)")
    if pt.tangent[3] * direction < 0:
        pt.tangent = -pt.tangent
    return pt


def continue_event(sim: Simulator, params: Mapping[str, Any], kind: str, M: int, sigma0: float, z0: Any,
                   param2: str, p2_range: tuple[float, float], log2: bool = True, direction: float = 1.0,
                   sigma_range: tuple[float, float] = (1e-3, 1e4), ds: float = 0.02, ds_min: float = 1e-7,
                   ds_max: float = 0.25, max_points: int = 200, locate_tol: float = 1e-8, theta: float = 0.5,
                   pmap: PeriodMap | None = None) -> EventCurve:
    """Continue a flip, fold or NS point of a period-M orbit in (sigma, ``param2``).

    Parameters
    ----------
    sim : Simulator
        The FMU (``solver`` = 1 in ``params``: the closed form).
    params : mapping
        FMU parameters including the starting value of ``param2``.
    kind : {"flip", "fold", "ns"}
    M : int
    sigma0 : float
        The event's sigma (e.g. ``Event.value`` of a branch).
    z0 : (u, v)
        A stroboscopic point of the orbit there (``Event.point``).
    param2 : str
        The second parameter; ``p2_range`` its interval (the curve stops when it leaves it).
    log2 : bool
        Continue in ln p2 (the natural scale of Gamma).
    direction : float
        Sign of the first step in p2.
    sigma_range : (float, float)
        The curve stops when sigma leaves it.  Positive: sigma is continued as ln sigma; reaching
        sigma <= 0: as sigma itself (:func:`.sigma_axis.sigma_axis`).
    ds, ds_min, ds_max : float
        Arclength steps in X = (w / (1 + sigma), s, q), s = ln sigma or sigma.
    max_points : int
    locate_tol : float
        Turning points and the end at a graze are located to this width in the arclength.
    """
    if kind not in SMOOTH_KINDS:
        raise HarnessInputError("kind", f"{kind!r} is not continued on the extended system (flip, fold, ns)")
    p2_0 = float(params[param2])
    lo2, hi2 = min(p2_range), max(p2_range)
    if not lo2 <= p2_0 <= hi2:
        raise HarnessInputError("p2_range", f"{param2} = {p2_0:g} lies outside [{lo2:g}, {hi2:g}]")
    tol2 = 1e-9 * max(abs(lo2), abs(hi2), 1.0)  # the start may sit on the range's end up to rounding
    pmap = pmap or PeriodMap(sim, params, "sigma", theta)
    plane = PlaneMap(pmap, param2, log2, M, sigma_axis(sigma_range))
    corr = _Corrector(plane, kind)
    w0 = np.asarray(z0, dtype=float) - pmap.offset(sigma0)
    a = _start(corr, w0, sigma0, p2_0, direction)
    pattern = a.ev.contacts.copy()
    pts = [a]
    turns: list[dict[str, Any]] = []
    control = StepControl(abs(ds), ds_min, ds_max, max_points)
    while control.budget_left:
        # the start counts as inside: its corrector, orthogonal to the tangent, moves p2 too, and where
        # the curve is steep in sigma that can be off the range's end by far more than rounding
        if not ((a is pts[0] or lo2 - tol2 <= a.p2 <= hi2 + tol2) and sigma_range[0] <= a.sigma <= sigma_range[1]):
            control.stop("range", f"left {param2} in [{lo2:g}, {hi2:g}] or sigma in "
                         f"[{sigma_range[0]:g}, {sigma_range[1]:g}]")
            break
        b = corr.along(a, control.size)
        if b is not None and not _same_pattern(b.ev.contacts, pattern):
            good, bad = _bisect_pattern(corr, a, control.size, pattern, locate_tol)
            pts.append(good)
            control.stop("graze", _pattern_change_note(plane, kind, good, bad, pattern))
            break
        if b is None or float(b.tangent @ a.tangent) < 0.9:
            if not control.shrink():
                control.stop(*_failure_end(plane, kind, a, ds_min))
                break
            continue
        if a.tangent[3] * b.tangent[3] < 0:
            turns.append(_locate_turn(corr, a, control.size, locate_tol))
        pts.append(b)
        a = b
        control.accept()
    return _event_curve(plane, kind, pattern, pts, turns, control)


def _gap_at(plane: PlaneMap, pt: CurvePoint) -> float:
    """The gap of the orbit at a curve point, with the point's own p2 (the free flow depends on
    nu and Omega).  Leaves the period map at that p2."""
    plane.pmap.params = {**plane.base, plane.param2: pt.p2}
    return plane.pmap.gap(pt.ev.points, pt.ev.contacts, pt.sigma)


def _pattern_change_note(plane: PlaneMap, kind: str, good: CurvePoint, bad: CurvePoint | None,
                         pattern: np.ndarray) -> str:
    """Why a curve ends where the orbit's contact pattern changes (located at ``good``)."""
    gap = _gap_at(plane, good)
    return (f"the orbit's contacts per period change ({int(pattern.sum())} -> "
            f"{'?' if bad is None else int(bad.ev.contacts.sum())}): the {kind} meets the orbit's graze; "
            f"gap at the last point {gap:.2e}")


def _failure_end(plane: PlaneMap, kind: str, a: CurvePoint, ds_min: float) -> tuple[str, str]:
    """(reason, note) of a curve whose corrector failed from ``a`` down to the smallest step."""
    gap = _gap_at(plane, a)
    if gap < GRAZE_GAP * (1.0 + a.sigma):
        # the corrector fails at the corner where the event meets the graze (the map is
        # nonsmooth there): the last point's free passage touches the wall
        return "graze", (f"the {kind} meets the orbit's graze (the corrector stops at the corner; gap at the "
                         f"last point {gap:.2e})")
    return "lost", f"corrector failed down to the step {ds_min:g} (gap at the last point {gap:.2e}: not a graze)"


def _event_curve(plane: PlaneMap, kind: str, pattern: np.ndarray, pts: list[CurvePoint],
                 turns: list[dict[str, Any]], control: StepControl) -> EventCurve:
    """The curve walked, with each point's gap and why it ended."""
    gaps = [_gap_at(plane, p) for p in pts]
    plane.pmap.params = dict(plane.base)  # a caller's map is left as it was given
    last = pts[-1]
    end: dict[str, Any] = {"reason": control.reason, "note": control.note, "sigma": last.sigma, "p2": last.p2}
    return EventCurve(kind, plane.M, int(pattern.sum()), plane.param2, np.array([p.sigma for p in pts]),
                      np.array([p.p2 for p in pts]), np.array([p.ev.points[0] for p in pts]),
                      np.array([p.multipliers for p in pts]), np.array(gaps),
                      significant_turns(turns, last.p2), end, plane.pmap.evaluations)


def _bisect_pattern(corr: _Corrector, a: CurvePoint, step: float, pattern: np.ndarray,
                    tol: float) -> tuple[CurvePoint, CurvePoint | None]:
    """The last point with ``pattern`` before arclength ``step`` from ``a`` (bisection)."""
    lo, hi, good, bad = 0.0, step, a, None
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        pt = corr.along(a, mid)
        if pt is not None and _same_pattern(pt.ev.contacts, pattern):
            lo, good = mid, pt
        else:
            hi, bad = mid, pt
    return good, bad


def _locate_turn(corr: _Corrector, a: CurvePoint, step: float, tol: float) -> dict[str, Any]:
    """The turning point in p2 between ``a`` and arclength ``step``: the root of the tangent's
    p2 component (Illinois method), oriented like ``a``'s tangent."""
    def f(pt: CurvePoint) -> float:
        t = pt.tangent if pt.tangent @ a.tangent >= 0 else -pt.tangent
        return float(t[3])

    lo, hi, flo = 0.0, step, float(a.tangent[3])
    b = corr.along(a, step)
    fhi = f(b) if b is not None else -flo
    best, side = a, 0
    for _ in range(60):
        s = (lo * fhi - hi * flo) / (fhi - flo)
        if not lo < s < hi:
            s = 0.5 * (lo + hi)
        pt = corr.along(a, s)
        if pt is None:
            break
        fs = f(pt)
        best = pt
        lo, hi, flo, fhi, side = illinois_update(lo, hi, flo, fhi, s, fs, side)
        if hi - lo < tol or abs(fs) < 1e-12:
            break
    return {"sigma": best.sigma, "p2": best.p2, "side": "max" if a.tangent[3] > 0 else "min",
            "multipliers": [[float(m.real), float(m.imag)] for m in best.multipliers]}
