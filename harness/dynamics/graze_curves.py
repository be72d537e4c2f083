"""Graze curves of a periodic orbit in the plane of sigma and a second parameter.

A graze (a free passage of the orbit reaching the wall) is not a smooth event of the FMU's flow:
a passage that penetrates the wall by d changes the orbit by ~sqrt(d), so it is not continued on an
extended system (:mod:`.event_curves` says why).  It is continued in p2 by natural continuation:
at each value of p2 the orbit is followed in sigma towards the graze and the graze is located by
bisection on "Newton converges to an orbit with the same contact pattern", to a relative width
``locate_tol`` in sigma; the gap of the last orbit with the pattern (:meth:`PeriodMap.gap`, which
vanishes at a graze) is kept as the check.  The step in ln p2 adapts to the change of ln sigma.

Along the curve the grazing orbit's multipliers are kept: where it loses stability, the graze
curve crosses a flip or fold curve of the orbit; a window bounded by that edge and the graze closes
there (located by bisection in p2).  A turning point of the graze curve in p2 cannot be passed by
natural continuation: the curve then ends with the reason.
"""
from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from .event_curves import EventCurve
from .periodic_map import MapEvaluation, PeriodMap, refine_orbit
from ..fmu.simulator import Simulator

__all__ = ["continue_graze", "locate_graze"]

#: Relative offsets of sigma tried, from the predicted graze, for a point with the pattern.
_PROBES = (1e-5, 1e-4, 1e-3, 1e-2, 4e-2)


#: Largest gap (relative to 1 + sigma) of a located graze: the bisection's end must be one.
GAP_TOL = 1e-6


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return any(np.array_equal(np.roll(a, k), b) for k in range(len(a)))


def _orbit(pmap: PeriodMap, w: np.ndarray, sigma: float, M: int,
           pattern: np.ndarray) -> tuple[np.ndarray, MapEvaluation] | None:
    """The orbit with ``pattern`` at sigma by Newton from ``w``, or None."""
    w1, ev, ok, _ = refine_orbit(pmap, w, sigma, M)
    if ok and _same(ev.contacts, pattern):
        return w1, ev
    return None


def locate_graze(pmap: PeriodMap, M: int, w_in: np.ndarray, s_in: float, s_out: float, pattern: np.ndarray,
                 locate_tol: float = 1e-9) -> tuple[float, np.ndarray, MapEvaluation, float]:
    """Bisection in ln sigma between ``s_in`` (the orbit with ``pattern`` exists, at ``w_in``) and
    ``s_out`` (it does not); returns (sigma, w, evaluation, bracket) at the last orbit with it."""
    found = _orbit(pmap, w_in, s_in, M, pattern)
    if found is None:
        raise ValueError(f"no orbit with the contact pattern at sigma = {s_in:g}")
    w, ev = found
    lo, hi = math.log(s_in), math.log(s_out)
    while abs(hi - lo) > locate_tol:
        mid = 0.5 * (lo + hi)
        found = _orbit(pmap, w, math.exp(mid), M, pattern)
        if found is not None:
            lo, (w, ev) = mid, found
        else:
            hi = mid
    return math.exp(lo), w, ev, abs(math.exp(hi) - math.exp(lo))


def continue_graze(sim: Simulator, params: Mapping[str, Any], M: int, sigma_in: float, z_in: Any, sigma_out: float,
                   param2: str, p2_range: tuple[float, float], log2: bool = True, direction: float = 1.0,
                   dq: float = 0.05, dq_min: float = 1e-4, dq_max: float = 0.3, max_points: int = 200,
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
        As in :func:`harness.dynamics.event_curves.continue_event`.
    dq, dq_min, dq_max : float
        Steps in q (ln p2 on a log axis).
    locate_tol : float
        Relative width in sigma of each located graze.

    Returns
    -------
    EventCurve
        kind "graze"; ``turns`` holds where the grazing orbit loses (or gains) stability, located
        in p2 (``side``: "loses" / "gains"), ``end`` why the curve stopped.
    """
    pmap = PeriodMap(sim, params, "sigma", theta)
    base = dict(pmap.params)
    p2_0 = float(params[param2])
    to_q = (lambda p: math.log(p)) if log2 else float
    of_q = math.exp if log2 else float

    def at(q: float) -> None:
        pmap.params = {**base, param2: of_q(q)}

    w_in = np.asarray(z_in, dtype=float) - pmap.offset(sigma_in)
    w0, ev0, ok, _ = refine_orbit(pmap, w_in, sigma_in, M)
    if not ok:
        raise ValueError(f"no period-{M} orbit at sigma = {sigma_in:g} near the given point")
    pattern = ev0.contacts.copy()
    side = 1.0 if sigma_in > sigma_out else -1.0  # ln sigma increases into the orbit's region
    s, w, ev, _ = locate_graze(pmap, M, w0, sigma_in, sigma_out, pattern, locate_tol)
    if pmap.gap(ev.points, ev.contacts, s) > GAP_TOL * (1.0 + s):
        raise ValueError(f"the period-{M} orbit's change at sigma = {s:.10g} is not a graze (gap "
                         f"{pmap.gap(ev.points, ev.contacts, s):.3g})")
    qs, ss, ws, evs = [to_q(p2_0)], [s], [w], [ev]
    turns: list[dict[str, Any]] = []
    end: dict[str, Any] = {"reason": "steps", "note": f"{max_points} steps done"}
    lo2, hi2 = min(p2_range), max(p2_range)
    step = dq * (1.0 if direction > 0 else -1.0)

    def stable(e: MapEvaluation) -> bool:
        return bool(np.all(np.abs(np.linalg.eigvals(e.J)) < 1.0))

    def graze_at(q: float) -> tuple[float, np.ndarray, MapEvaluation] | None:
        at(q)
        # predict ln sigma and w by the secant through the last two points
        if len(qs) >= 2 and qs[-1] != qs[-2]:
            f = (q - qs[-1]) / (qs[-1] - qs[-2])
            ls = math.log(ss[-1]) + f * (math.log(ss[-1]) - math.log(ss[-2]))
            wp = ws[-1] + f * (ws[-1] - ws[-2])
        else:
            ls, wp = math.log(ss[-1]), ws[-1]
        for d in _PROBES:
            s_try = math.exp(ls + side * d)
            found = _orbit(pmap, wp, s_try, M, pattern) or _orbit(pmap, ws[-1], s_try, M, pattern)
            if found is None:
                continue
            w_try = found[0]
            for d_out in _PROBES:  # a point beyond, without the pattern
                s_out = math.exp(ls - side * d_out)
                if _orbit(pmap, w_try, s_out, M, pattern) is None:
                    sg, wg, eg, _ = locate_graze(pmap, M, w_try, s_try, s_out, pattern, locate_tol)
                    # Newton can fail beyond for other reasons than a graze: only a vanishing gap is one
                    if pmap.gap(eg.points, eg.contacts, sg) > GAP_TOL * (1.0 + sg):
                        return None
                    return sg, wg, eg
            return None
        return None

    n = 0
    while n < max_points:
        q = qs[-1] + step
        if not lo2 <= of_q(q) <= hi2:
            end = {"reason": "range", "note": f"left {param2} in [{lo2:g}, {hi2:g}]"}
            break
        res = graze_at(q)
        if res is not None and abs(math.log(res[0] / ss[-1])) > 0.3 and abs(step) > dq_min:
            res = None  # too large a jump for one step: retry shorter
        if res is None:
            step *= 0.5
            if abs(step) < dq_min:
                end = {"reason": "lost", "note": "no orbit with the contact pattern next to the predicted graze "
                       f"(step in ln {param2} down to {dq_min:g}): a turning point of the graze curve or the end "
                       "of the orbit"}
                break
            continue
        sg, wg, eg = res
        if stable(eg) != stable(evs[-1]):
            turns.append(_stability_change(graze_at, qs[-1], q, stable(evs[-1]), of_q, locate_tol, stable))
        qs.append(q)
        ss.append(sg)
        ws.append(wg)
        evs.append(eg)
        n += 1
        if not sigma_range[0] <= sg <= sigma_range[1]:
            end = {"reason": "range", "note": f"left sigma in [{sigma_range[0]:g}, {sigma_range[1]:g}]"}
            break
        step = math.copysign(min(abs(step) * 1.5, dq_max), step)
    at(qs[0])
    end.update({"sigma": ss[-1], "p2": of_q(qs[-1])})
    mult = np.array([np.linalg.eigvals(e.J).astype(complex) for e in evs])
    gaps = np.array([pmap.gap(e.points, e.contacts, s_) for e, s_ in zip(evs, ss)])
    return EventCurve("graze", M, int(pattern.sum()), param2, np.array(ss), np.array([of_q(x) for x in qs]),
                      np.array([e.points[0] for e in evs]), mult, gaps, turns, end, pmap.evaluations)


def _stability_change(graze_at: Any, qa: float, qb: float, stable_a: bool, of_q: Any, tol: float,
                      stable: Any) -> dict[str, Any]:
    """Bisection in q for where the grazing orbit's stability changes."""
    lo, hi = qa, qb
    best = None
    for _ in range(40):
        if abs(hi - lo) < max(tol, 1e-10):
            break
        mid = 0.5 * (lo + hi)
        res = graze_at(mid)
        if res is None:
            break
        if stable(res[2]) == stable_a:
            lo = mid
        else:
            hi = mid
        best = res
    sg = best[0] if best is not None else float("nan")
    mult = np.linalg.eigvals(best[2].J) if best is not None else []
    return {"sigma": sg, "p2": of_q(0.5 * (lo + hi)), "side": "loses" if stable_a else "gains",
            "multipliers": [[float(m.real), float(m.imag)] for m in mult]}
