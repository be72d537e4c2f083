"""Graze curves of a periodic orbit in the plane of sigma and a second parameter.

A graze (a free passage of the orbit reaching the wall) is not a smooth event of the FMU's flow:
a passage that penetrates the wall by d changes the orbit by ~sqrt(d), so it is not continued on an
extended system (:mod:`.event_curves` says why).  It is followed in the plane Y = (s, q),
s = ln sigma (sigma itself on a range reaching sigma <= 0: :mod:`.sigma_axis`), q = p2 (ln p2 on
a log axis), by steps along the curve's secant and a location across it: from the
last graze point, a step of length h along the secant T of the last two points, then a bisection
along the normal N on "Newton converges to an orbit with the same contact pattern", to a width
``locate_tol``.  The gap of the last orbit with the pattern (:meth:`PeriodMap.gap`, which vanishes
at a graze) must be below ``GAP_TOL``: a point where Newton merely failed is not a graze.  Being
a step along the curve, not in p2, this passes turning points in p2 and follows a curve that runs
off to large sigma.

Along the curve the grazing orbit's multipliers are kept: where it loses stability, the graze
curve crosses a flip or fold curve of the orbit; a window bounded by that edge and the graze closes
there (located by bisection along the curve).  Turning points in p2 are recorded like those of
:func:`harness.dynamics.curves.event_curves.continue_event`.
"""
from __future__ import annotations

import math
from typing import Any, Callable, Mapping

import numpy as np

from .curve import EventCurve, significant_turns
from ..maps.periodic_map import MapEvaluation, PeriodMap, refine_orbit
from ..continuation.step_control import StepControl
from .sigma_axis import LOG, SigmaAxis, sigma_axis
from ...fmu.simulator import Simulator

__all__ = ["continue_graze", "GAP_TOL"]

#: Largest gap (relative to 1 + sigma) of a located graze (after the secant steps on the gap, a
#: graze has ~1e-12; Newton failing before it leaves ~1e-6, measured on period 2 at Gamma = 73).
GAP_TOL = 1e-8

#: Distances along the normal tried for a point with (inside) and without (outside) the pattern.
_PROBES = (1e-5, 1e-4, 1e-3, 1e-2, 4e-2)


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return any(np.array_equal(np.roll(a, k), b) for k in range(len(a)))


class _Plane:
    """The orbit with a fixed contact pattern at points Y = (s, q) of the plane (s: ``axis``)."""

    def __init__(self, pmap: PeriodMap, param2: str, of_q: Callable[[float], float], M: int,
                 pattern: np.ndarray, axis: SigmaAxis = LOG) -> None:
        self.pmap, self.param2, self.of_q, self.M, self.pattern = pmap, param2, of_q, M, pattern
        self.axis = axis
        self.base = dict(pmap.params)

    def orbit(self, Y: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, MapEvaluation] | None:
        self.pmap.params = {**self.base, self.param2: self.of_q(float(Y[1]))}
        w1, ev, ok, _ = refine_orbit(self.pmap, w, self.axis.of(float(Y[0])), self.M)
        return (w1, ev) if ok and _same(ev.contacts, self.pattern) else None

    def gap(self, Y: np.ndarray, ev: MapEvaluation) -> float:
        self.pmap.params = {**self.base, self.param2: self.of_q(float(Y[1]))}
        return self.pmap.gap(ev.points, ev.contacts, self.axis.of(float(Y[0])))

    def locate(self, P: np.ndarray, N: np.ndarray, w_guess: np.ndarray,
               tol: float) -> tuple[np.ndarray, np.ndarray, MapEvaluation] | None:
        """The graze on the line P + t N (N points inside): an inside and an outside point, then
        bisection in t; None if either is missing or the end is not a graze."""
        inside = None
        for d in _PROBES:
            found = self.orbit(P + d * N, w_guess)
            if found is not None:
                inside = (d, found)
                break
        if inside is None:
            return None
        t_in, (w, ev) = inside
        t_out = None
        for d in _PROBES:
            if self.orbit(P - d * N, w) is None:
                t_out = -d
                break
        if t_out is None:
            return None
        return self.bisect(P, N, t_in, t_out, w, ev, tol)

    def bisect(self, P: np.ndarray, N: np.ndarray, t_in: float, t_out: float, w: np.ndarray, ev: MapEvaluation,
               tol: float) -> tuple[np.ndarray, np.ndarray, MapEvaluation] | None:
        """Bisection in t on P + t N between ``t_in`` (the orbit with the pattern exists: w, ev)
        and ``t_out`` (it does not), then :meth:`polish`."""
        while abs(t_in - t_out) > tol:
            mid = 0.5 * (t_in + t_out)
            found = self.orbit(P + mid * N, w)
            if found is not None:
                t_in, (w, ev) = mid, found
            else:
                t_out = mid
        return self.polish(P, N, t_in, w, ev, tol)

    def polish(self, P: np.ndarray, N: np.ndarray, t_in: float, w: np.ndarray, ev: MapEvaluation,
               tol: float) -> tuple[np.ndarray, np.ndarray, MapEvaluation] | None:
        """Secant steps on the gap along P + t N from the bisection's inside end: the bisection
        stops where Newton first fails, which near a graze can be a little before it (the map is
        nonsmooth there); the gap, smooth on the inside, goes to 0 at the graze itself."""
        g = self.gap(P + t_in * N, ev)
        t_prev, g_prev = t_in + max(100.0 * tol, 1e-7), None
        found = self.orbit(P + t_prev * N, w)
        if found is not None:
            g_prev = self.gap(P + t_prev * N, found[1])
        for _ in range(8):
            if g_prev is None or g <= 1e-12 * (1.0 + self.axis.of(float(P[0]))) or g_prev == g:
                break
            t_new = t_in - g * (t_in - t_prev) / (g - g_prev)
            found = self.orbit(P + t_new * N, w)
            if found is None:  # past the graze: stay inside
                t_new = 0.5 * (t_in + t_new)
                found = self.orbit(P + t_new * N, w)
                if found is None:
                    break
            t_prev, g_prev = t_in, g
            t_in, (w, ev) = t_new, found
            g = self.gap(P + t_in * N, ev)
        Y = P + t_in * N
        if self.gap(Y, ev) > GAP_TOL * (1.0 + self.axis.of(float(Y[0]))):
            return None  # Newton failed for another reason than a graze
        return Y, w, ev


def continue_graze(sim: Simulator, params: Mapping[str, Any], M: int, sigma_in: float, z_in: Any, sigma_out: float,
                   param2: str, p2_range: tuple[float, float], log2: bool = True, direction: float = 1.0,
                   h: float = 0.05, h_min: float = 1e-4, h_max: float = 0.3, max_points: int = 200,
                   locate_tol: float = 1e-9, sigma_range: tuple[float, float] = (1e-3, 1e4),
                   theta: float = 0.5) -> EventCurve:
    """The graze curve of a period-M orbit in (sigma, ``param2``).

    Parameters
    ----------
    sim, params
        The FMU and its parameters (including the starting value of ``param2``).
    M : int
    sigma_in, z_in
        A sigma where the orbit exists with its contact pattern, and a point of it (e.g. the last
        point of a branch before its graze event, ``Event.value`` and ``Event.point``).
    sigma_out : float
        A sigma beyond the graze (the pattern lost), e.g. ``Event.value + Event.bracket``.
    param2, p2_range, log2, direction
        As in :func:`harness.dynamics.curves.event_curves.continue_event`.
    h, h_min, h_max : float
        Steps along the curve in Y = (s, q): s = ln sigma where ``sigma_range`` is positive,
        else sigma (:func:`.sigma_axis.sigma_axis`).
    locate_tol : float
        Width of each location across the curve, in Y.

    Returns
    -------
    EventCurve
        kind "graze"; ``turns`` holds the turning points in p2 ("max"/"min") and where the grazing
        orbit loses or gains stability ("loses"/"gains"); ``end`` why the curve stopped.
    """
    pmap = PeriodMap(sim, params, "sigma", theta)
    of_q = math.exp if log2 else float
    q0 = (math.log if log2 else float)(float(params[param2]))
    axis = sigma_axis(sigma_range)
    walk = _first_graze(pmap, M, sigma_in, z_in, sigma_out, param2, of_q, q0, locate_tol, axis)
    walk.T = np.array([0.0, 1.0 if direction > 0 else -1.0])  # first step along p2
    lo2, hi2 = min(p2_range), max(p2_range)
    control = StepControl(h, h_min, h_max, max_points)
    while control.budget_left:
        res = walk.next_point(control.size)
        if res is None:
            if not control.shrink():
                control.stop("lost", f"no graze found across the curve (step down to {h_min:g}): the "
                             "orbit with this contact pattern ends")
                break
            continue
        walk.add(res, control.size)
        control.accept()
        p2, sg = of_q(float(res[0][1])), axis.of(float(res[0][0]))
        tol2 = 1e-9 * max(abs(lo2), abs(hi2), 1.0)
        if not (lo2 - tol2 <= p2 <= hi2 + tol2 and sigma_range[0] <= sg <= sigma_range[1]):
            control.stop("range", f"left {param2} in [{lo2:g}, {hi2:g}] or sigma in "
                         f"[{sigma_range[0]:g}, {sigma_range[1]:g}]")
            break
    return walk.curve(control, of_q(q0))


def _first_graze(pmap: PeriodMap, M: int, sigma_in: float, z_in: Any, sigma_out: float, param2: str,
                 of_q: Callable[[float], float], q0: float, locate_tol: float, axis: SigmaAxis = LOG) -> _GrazeWalk:
    """The walk started at the first point of the curve: the graze located by bisection across
    the curve along s (``axis``: ln sigma or sigma), between ``sigma_in`` (the orbit with its
    pattern) and ``sigma_out``."""
    w0, ev0, ok = np.zeros(2), None, False
    for k in (0.0, 1.0, 4.0, 16.0):
        # a graze event's value is the zero of its defining quantity, where the orbit with the
        # pattern may already be lost: step inward (away from sigma_out) when it is
        sigma_in_k = sigma_in + k * (sigma_in - sigma_out)
        w_in = np.asarray(z_in, dtype=float) - pmap.offset(sigma_in_k)
        w0, ev0, ok, _ = refine_orbit(pmap, w_in, sigma_in_k, M)
        if ok:
            sigma_in = sigma_in_k
            break
    if not ok:
        raise ValueError(f"no period-{M} orbit at sigma = {sigma_in:g} near the given point")
    plane = _Plane(pmap, param2, of_q, M, ev0.contacts.copy(), axis)
    N = np.array([1.0 if sigma_in > sigma_out else -1.0, 0.0])
    s_in, s_out = axis.to(sigma_in), axis.to(sigma_out)
    mid = np.array([0.5 * (s_in + s_out), q0])
    # the log axis keeps its one-division half-width, so positive ranges locate as they always did
    half = abs(math.log(sigma_in / sigma_out)) / 2 if axis.log else abs(s_in - s_out) / 2
    first = plane.bisect(mid, N, half, -half, w0, ev0, locate_tol)
    if first is None:
        raise ValueError(f"the period-{M} orbit's change between sigma = {sigma_in:.10g} and {sigma_out:.10g} "
                         "is not a graze (the gap does not vanish at its last orbit)")
    return _GrazeWalk(plane, first, N, locate_tol)


def _stable(ev: MapEvaluation) -> bool:
    return bool(np.all(np.abs(np.linalg.eigvals(ev.J)) < 1.0))


class _GrazeWalk:
    """The graze curve walked so far: its points Y with their orbits, the secant T of the last
    two points (the direction of the next step) and the normal N across the curve (pointing to
    the side where the orbit has its pattern), and the turns met.

    Parameters
    ----------
    plane : _Plane
    first : (Y, w, ev)
        The first graze point.
    N : ndarray
        The first normal.
    locate_tol : float
    """

    def __init__(self, plane: _Plane, first: tuple[np.ndarray, np.ndarray, MapEvaluation], N: np.ndarray,
                 locate_tol: float) -> None:
        self.plane, self.N, self.locate_tol = plane, N, locate_tol
        self.Ys, self.ws, self.evs = [first[0]], [first[1]], [first[2]]
        #: the direction of the next step (the caller sets the first one)
        self.T = np.array([0.0, 1.0])
        self.turns: list[dict[str, Any]] = []

    def normal(self, T: np.ndarray) -> np.ndarray:
        """The normal to ``T`` on the side of the current normal."""
        n = np.array([-T[1], T[0]])
        return n if n @ self.N >= 0 else -n

    def next_point(self, s: float) -> tuple[np.ndarray, np.ndarray, MapEvaluation] | None:
        """The graze located across the curve at a step ``s`` along T from the last point, from
        the orbit extrapolated along the last two."""
        Ys, ws = self.Ys, self.ws
        f = s / max(float(np.linalg.norm(Ys[-1] - Ys[-2])), 1e-300) if len(Ys) >= 2 else 0.0
        w_guess = ws[-1] + f * (ws[-1] - ws[-2]) if len(Ys) >= 2 else ws[-1]
        return self.plane.locate(Ys[-1] + s * self.T, self.normal(self.T), w_guess, self.locate_tol)

    def add(self, res: tuple[np.ndarray, np.ndarray, MapEvaluation], step: float) -> None:
        """Accept the point ``res`` found at ``step``, recording a change of stability or a
        turning point in p2 between it and the last point."""
        Y, w, ev = res
        of_q = self.plane.of_q
        if _stable(ev) != _stable(self.evs[-1]):
            self.turns.append(_stability_change(self.next_point, step, _stable(self.evs[-1]), of_q,
                                                self.locate_tol, _stable, self.plane.axis))
        T_new = (Y - self.Ys[-1]) / np.linalg.norm(Y - self.Ys[-1])
        if T_new[1] * self.T[1] < 0 and len(self.Ys) >= 2:
            self.turns.append({"sigma": float(self.plane.axis.of(self.Ys[-1][0])), "p2": float(of_q(self.Ys[-1][1])),
                               "side": "max" if self.T[1] > 0 else "min", "multipliers": _mults(self.evs[-1])})
        self.N = self.normal(T_new)
        self.T = T_new
        self.Ys.append(Y)
        self.ws.append(w)
        self.evs.append(ev)

    def curve(self, control: StepControl, p2_0: float) -> EventCurve:
        """The curve walked, why it ended, and the map's p2 put back to ``p2_0``."""
        plane, of_q = self.plane, self.plane.of_q
        plane.pmap.params = {**plane.base, plane.param2: p2_0}
        sig = plane.axis.of_array(np.array([Y[0] for Y in self.Ys]))
        p2s = np.array([of_q(float(Y[1])) for Y in self.Ys])
        end: dict[str, Any] = {"reason": control.reason, "note": control.note,
                               "sigma": float(sig[-1]), "p2": float(p2s[-1])}
        turns = significant_turns(self.turns, float(p2s[-1]))
        mult = np.array([np.linalg.eigvals(e.J).astype(complex) for e in self.evs])
        gaps = np.array([plane.gap(Y, e) for Y, e in zip(self.Ys, self.evs)])
        plane.pmap.params = {**plane.base, plane.param2: p2_0}
        return EventCurve("graze", plane.M, int(plane.pattern.sum()), plane.param2, sig, p2s,
                          np.array([e.points[0] for e in self.evs]), mult, gaps, turns, end, plane.pmap.evaluations)


def _mults(ev: MapEvaluation) -> list[list[float]]:
    return [[float(m.real), float(m.imag)] for m in np.linalg.eigvals(ev.J)]


def _stability_change(next_point: Callable[[float], Any], step: float, stable_a: bool, of_q: Callable[[float], float],
                      tol: float, stable: Callable[[MapEvaluation], bool], axis: SigmaAxis = LOG) -> dict[str, Any]:
    """Bisection along the curve (the step from the last point) for where the grazing orbit's
    stability changes."""
    lo, hi = 0.0, step
    best = None
    for _ in range(50):
        if hi - lo < max(tol, 1e-10):
            break
        mid = 0.5 * (lo + hi)
        res = next_point(mid)
        if res is None:
            break
        if stable(res[2]) == stable_a:
            lo = mid
        else:
            hi = mid
        best = res
    if best is None:
        return {"sigma": math.nan, "p2": math.nan, "side": "loses" if stable_a else "gains", "multipliers": []}
    Y, _, ev = best
    return {"sigma": float(axis.of(Y[0])), "p2": float(of_q(float(Y[1]))), "side": "loses" if stable_a else "gains",
            "multipliers": _mults(ev)}
