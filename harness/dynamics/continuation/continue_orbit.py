"""Pseudo-arclength continuation of periodic orbits of the FMU's M-period stroboscopic map.

The unknowns are x = (w, p): the orbit's stroboscopic point in coordinates w = z - p(theta)
(:mod:`.periodic_map`) and the parameter p (any FMU parameter).  Each step predicts along the
tangent t (the null vector of [D(F^M) - I | dF^M/dp], the cross product of its two rows) and
corrects by Newton on

    F^M(w; p) - w = 0,      t . (x - x_pred) = 0,

with D(F^M) and d/d sigma exact from the FMU's sensitivity outputs (a central difference for
any other parameter).  Stable and unstable orbits are followed alike.  The step adapts to the
corrector's iterations.

Events, between two accepted points (:mod:`.branch`):

* flip / fold / ns: a sign change of det(D + I), det(D - I), or det(D) - 1 with a complex pair
  (for 2x2, |mu|^2 = det); located by the Illinois (regula falsi) method on the arclength
  from the previous point, each trial corrected onto the branch, to ``locate_tol`` in p;
* graze / stick: the corrected orbit's contacts per period differ from the previous point's;
  located by bisection on the arclength on "same contacts as before", to ``locate_tol`` in p.
  The orbit with the new contact count is then sought beyond the graze (persistence) and on
  the same side (the nonsmooth fold of the square-root map); continuation goes on with it if it
  exists, and the event's note says which.

Period doubling: :func:`switch_at_flip` starts the period-2M branch at a located flip.

The steps and the events between them are taken by :class:`.orbit_walk.OrbitWalk`, the step
size by :class:`.step_control.StepControl` (shared with the curves in two parameters).
"""
from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from .arclength import ArclengthCorrector, BranchPoint
from .branch import Branch, Event
from .orbit_walk import STICK_IMPACTS, OrbitWalk
from ..maps.periodic_map import PeriodMap, refine_orbit
from .step_control import StepControl
from ...errors import HarnessInputError
from ...fmu.simulator import Simulator

__all__ = ["continue_orbit", "doubled_orbit", "switch_at_flip", "STICK_IMPACTS"]


def _start_point(pmap: PeriodMap, p0: float, z0: Any, M: int) -> BranchPoint:
    w0 = np.asarray(z0, dtype=float) - pmap.offset(p0)
    w, ev, ok, res = refine_orbit(pmap, w0, p0, M)
    if not ok:
        raise HarnessInputError("z0", f"no period-{M} orbit found near ({z0[0]:g}, {z0[1]:g}) at "
                                f"{pmap.param} = {p0:g} (Newton residual {res:.3g})")
    return BranchPoint(w, p0, ev)


def _check_inputs(M: int, p_range: tuple[float, float], p0: float, param: str) -> tuple[float, float]:
    """The range (lo, hi) of the continuation, after checking the period, the range and the start."""
    if M < 1:
        raise HarnessInputError("M", f"the period must be >= 1, got {M}")
    lo, hi = min(p_range), max(p_range)
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise HarnessInputError("p_range", f"needs two different finite values, got {p_range}")
    if not lo <= p0 <= hi:
        raise HarnessInputError("p0", f"{param} = {p0:g} lies outside the range [{lo:g}, {hi:g}]")
    return lo, hi


def continue_orbit(sim: Simulator, params: Mapping[str, Any], M: int, p0: float, z0: Any,
                   param: str = "sigma", p_range: tuple[float, float] = (0.0, 2.0), direction: float = 1.0,
                   ds: float = 1e-2, ds_min: float = 1e-9, ds_max: float = 0.05, max_points: int = 200,
                   theta: float = 0.5, derivatives: str = "auto", locate_tol: float = 1e-8,
                   follow_grazing: bool = True, pmap: PeriodMap | None = None, progress: Any = None) -> Branch:
    """Continue a period-M orbit of the stroboscopic map in ``param``.

    Parameters
    ----------
    sim : Simulator
        The FMU (``solver`` = 1 in ``params``: the closed form, ~30x faster than CVODE).
    params : mapping
        FMU parameters.
    M : int
        Period of the orbit in forcing periods.
    p0 : float
        Starting parameter value.
    z0 : (u, v)
        A guess of one stroboscopic point of the orbit at t = theta, e.g. ``Attractor.points[0]``
        from :func:`harness.dynamics.attractors.scans.find_attractors` (Newton refines it first).
    param : str
        Any settable Real FMU parameter (sigma, Gamma, r, nu, Omega, ...).
    p_range : (float, float)
        The branch stops when it leaves this interval.
    direction : float
        Sign of the first step in p (+1 increasing).
    ds, ds_min, ds_max : float
        First, smallest and largest arclength step (in the norm of (w, p)).
    max_points : int
        Continuation steps at most (located event points come on top).
    theta : float
        Section phase.
    derivatives : {"auto", "exact", "fd"}
    locate_tol : float
        Events are located to this width in p (where the corrector allows).
    follow_grazing : bool
        At a graze, continue with the orbit with the new contact count when it exists.
    pmap : PeriodMap, optional
        Reuse an existing map (overrides sim/params/param/theta/derivatives).
    progress : tqdm-like, optional
        Updated once per accepted step.

    Returns
    -------
    Branch
        Its last event is always an ``end`` event saying why the continuation stopped.
    """
    lo, hi = _check_inputs(M, p_range, p0, param)
    pmap = pmap or PeriodMap(sim, params, param, theta, derivatives)
    cont = ArclengthCorrector(pmap, M, locate_tol)
    a = _start_point(pmap, p0, z0, M)
    if a.tangent[2] * direction < 0:
        a.tangent = -a.tangent
    walk = OrbitWalk(cont, a, StepControl(ds, ds_min, ds_max, max_points), follow_grazing, progress)
    while walk.control.budget_left:
        if not lo <= walk.a.p <= hi:
            walk.control.stop("range", f"left the range [{lo:g}, {hi:g}]")
            break
        if not walk.step():
            break
    return walk.branch()


def switch_at_flip(sim: Simulator, params: Mapping[str, Any], branch: Branch, event: Event,
                   delta: float = 1e-4, **kwargs: Any) -> Branch | None:
    """Start the period-2M branch at a located flip of ``branch`` and continue it.

    The period-2M orbit bifurcates from the flip point (w_f, p_f) along the eigenvector e of
    mu = -1: w = w_f + s e + O(s^2), p = p_f + O(s^2).  It is solved with its amplitude s fixed
    (branch switching): Newton on F^{2M}(w; p) - w = 0, e . (w - w_f) = s in (w, p), from
    (w_f + s e, p_f), for a few amplitudes s; the period-M orbit, whose component along e is
    not s at any p near the flip, is not a solution of that system.  The first solution that is
    not the period-M orbit (|F^M(w) - w| above the solver's accuracy) and has twice its contacts
    starts :func:`continue_orbit` with period 2M, directed away from the flip.  Where none
    converges, Newton at fixed p_f +- ``delta`` from w_f +- sqrt(delta) e is tried as well.
    ``kwargs`` go to :func:`continue_orbit` (p_range, max_points, ...).

    Returns
    -------
    Branch or None
        None when no period-2M orbit was found on either side (the report should say so).
    """
    if event.kind != "flip":
        raise HarnessInputError("event", f"branch switching needs a flip, not {event.kind!r}")
    pmap = PeriodMap(sim, params, branch.param, branch.theta, kwargs.pop("derivatives", branch.derivatives))
    M = branch.M
    w_f = np.asarray(event.point) - pmap.offset(event.value)
    ev = pmap.evaluate(w_f, event.value, M)
    vals, vecs = np.linalg.eig(ev.J)
    e = np.real(vecs[:, int(np.argmin(np.abs(vals + 1.0)))])
    e = e / np.linalg.norm(e)
    impacts = 2 * int(np.asarray(branch.contacts[event.index]).sum())
    found = doubled_orbit(pmap, w_f, float(event.value), e, M, impacts)
    if found is None:
        found = _doubled_at_fixed_p(pmap, w_f, float(event.value), e, M, impacts, delta)
    if found is None:
        return None
    w, p = found
    side = math.copysign(1.0, p - float(event.value)) if p != event.value else 1.0
    return continue_orbit(sim, params, 2 * M, p, w + pmap.offset(p), direction=side, pmap=pmap, **kwargs)


def _is_doubled(pmap: PeriodMap, w: np.ndarray, p: float, ev: Any, M: int, impacts: int) -> bool:
    """A period-2M orbit with ``impacts`` contacts that is not the period-M orbit run twice."""
    if int(np.asarray(ev.contacts).sum()) != impacts:
        return False
    half = pmap.evaluate(w, p, M, derivatives=False).image
    return float(np.max(np.abs(half - w))) > max(1e-7, 100.0 * pmap.tol(M, 0.0))


def doubled_orbit(pmap: PeriodMap, w_f: np.ndarray, p_f: float, e: np.ndarray, M: int,
                  impacts: int) -> tuple[np.ndarray, float] | None:
    """The period-2M orbit next to the flip at (w_f, p_f) with eigenvector ``e``: (w, p) solved
    with its amplitude along e fixed (Newton in (w, p) on F^{2M}(w; p) = w, e . (w - w_f) = s),
    for amplitudes s from 1e-3 to 3e-2 and 1e-4; None when none converges onto such an orbit."""
    tol = pmap.tol(2 * M, 1e-10)
    for amp in (1e-3, 1e-2, 1e-4, 3e-2):
        for sgn in (1.0, -1.0):
            s = sgn * amp
            x = np.append(w_f + s * e, p_f)
            for _ in range(25):
                ev = pmap.evaluate(x[:2], x[2], 2 * M)
                g = np.append(ev.image - x[:2], e @ (x[:2] - w_f) - s)
                if not np.all(np.isfinite(g)):
                    break
                if float(np.max(np.abs(g[:2]))) < tol and abs(g[2]) < 1e-12:
                    if _is_doubled(pmap, x[:2], float(x[2]), ev, M, impacts):
                        return x[:2].copy(), float(x[2])
                    break
                A = np.vstack([np.hstack([ev.J - np.eye(2), ev.dp[:, None]]), np.append(e, 0.0)])
                try:
                    dx = np.linalg.solve(A, -g)
                except np.linalg.LinAlgError:
                    break
                big = float(np.max(np.abs(dx)))  # damped like the corrector (the map is nonsmooth)
                x = x + (dx * (0.1 * (1.0 + abs(p_f)) / big) if big > 0.1 * (1.0 + abs(p_f)) else dx)
    return None


def _doubled_at_fixed_p(pmap: PeriodMap, w_f: np.ndarray, p_f: float, e: np.ndarray, M: int, impacts: int,
                        delta: float) -> tuple[np.ndarray, float] | None:
    """Newton at fixed p_f +- d from w_f +- sqrt(d) e (d = ``delta``, then delta / 100)."""
    for d in (delta, 1e-2 * delta):
        for side in (+1.0, -1.0):
            p = p_f + side * d
            for amp in (+1.0, -1.0):
                w, ev2, ok, _ = refine_orbit(pmap, w_f + amp * math.sqrt(d) * e, p, 2 * M)
                if ok and _is_doubled(pmap, w, p, ev2, M, impacts):
                    return w, p
    return None
