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
"""
from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from .arclength import ArclengthCorrector, BranchPoint
from .branch import Branch, Event
from .periodic_map import PeriodMap, refine_orbit
from ..errors import HarnessInputError
from ..fmu.simulator import Simulator

__all__ = ["continue_orbit", "switch_at_flip", "STICK_IMPACTS"]

#: Impacts per period from which a new contact pattern on a rigid wall is a chatter ending in
#: sticking (the FMU ends chatter by sticking after ~100 impacts).
STICK_IMPACTS = 20

#: Smallest cosine between the tangents of two accepted points (larger turns: a shorter step).
MAX_TURN = 0.98

#: A gap (distance to the wall of a free passage) below this at a corrector failure is a graze.
GRAZE_GAP = 1e-5

#: A multiplier above this at a corrector failure: a contact of the orbit is grazing.
GRAZE_MULTIPLIER = 1e3


def _start_point(pmap: PeriodMap, p0: float, z0: Any, M: int) -> BranchPoint:
    w0 = np.asarray(z0, dtype=float) - pmap.offset(p0)
    w, ev, ok, res = refine_orbit(pmap, w0, p0, M)
    if not ok:
        raise HarnessInputError("--start", f"no period-{M} orbit found near ({z0[0]:g}, {z0[1]:g}) at "
                                f"{pmap.param} = {p0:g} (Newton residual {res:.3g})")
    return BranchPoint(w, p0, ev)


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
        from :func:`harness.dynamics.attractors.find_attractors` (Newton refines it first).
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
    if M < 1:
        raise HarnessInputError("-M", f"the period must be >= 1, got {M}")
    lo, hi = min(p_range), max(p_range)
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise HarnessInputError("--range", f"needs two different finite values, got {p_range}")
    if not lo <= p0 <= hi:
        raise HarnessInputError("--start", f"{param} = {p0:g} lies outside the range [{lo:g}, {hi:g}]")
    pmap = pmap or PeriodMap(sim, params, param, theta, derivatives)
    cont = ArclengthCorrector(pmap, M, locate_tol)
    a = _start_point(pmap, p0, z0, M)
    if a.tangent[2] * direction < 0:
        a.tangent = -a.tangent
    pts: list[BranchPoint] = [a]
    labels = [""]
    events: list[Event] = []

    def event(kind: str, pt: BranchPoint, bracket: float, note: str = "") -> None:
        pts.append(pt)
        labels.append(kind)
        events.append(Event(kind, pt.p, len(pts) - 1, pt.mult, pt.ev.points[0], bracket, note))

    def _graze(good: BranchPoint, bracket: float, bad: BranchPoint | None, n_beyond: int | None = None) -> bool:
        """Record a graze at ``good``; switch to the orbit with the new contact count if it
        exists (True: the branch ends here)."""
        nonlocal a, end_note, steps
        n_old = int(a.ev.contacts.sum())
        rigid = int(pmap.params.get("wall", 0)) == 2
        nxt = _new_contact_orbit(cont, good, bad) if follow_grazing else None
        if nxt is not None and any(np.array_equal(np.roll(nxt.ev.contacts, k), good.ev.contacts) for k in range(M)):
            nxt = None  # the same contacts shifted: the same orbit again, not a new one
        kind = "graze"
        other = nxt if nxt is not None else bad
        if rigid and other is not None:
            # the sticking onset: on one side the orbit sticks to the wall for part of the period
            # (its D(F^M) is exactly 0: the sticking phase forgets the state), on the other not
            if _sticks(good) != _sticks(other):
                kind = "stick"
        elif rigid and n_beyond is not None and n_beyond >= STICK_IMPACTS:
            kind = "stick"  # nothing to compare: the flow beyond chatters as long as a sticking orbit
        if nxt is None:
            event(kind, good, bracket, f"{n_old} impact(s) per period before; no orbit with another contact "
                  "count found next to it" + ("" if follow_grazing else " (not sought)") + "; branch ends")
            end_note = f"{kind} at {pmap.param} = {good.p:.10g}"
            return True
        n_new = int(nxt.ev.contacts.sum())
        how = "beyond it" if (nxt.p - good.p) * (good.p - a.p) > 0 else "back on the same side (nonsmooth fold)"
        event(kind, good, bracket, f"{n_old} -> {n_new} impacts per period; continued {how}")
        a = nxt
        pts.append(a)
        labels.append("")
        steps += 1
        return False

    end_note = f"{max_points} steps done"
    steps = 0
    failed_here = False
    while steps < max_points:
        if not lo <= a.p <= hi:
            end_note = f"left the range [{lo:g}, {hi:g}]"
            break
        trial, its = cont.correct(a.x + ds * a.tangent, a.tangent)
        if trial is None and not failed_here:
            # the corrector fails where the branch has a corner: a graze that is a nonsmooth fold
            # (the orbit meets its partner with the extra contact on the wall).  Bisect on
            # "converges with the same contacts"; a vanishing gap there is a graze.
            failed_here = True
            good, bracket, bad = cont.locate_contact_change(a, ds)
            # a vanishing gap of a free passage, or a contact becoming grazing (its multipliers
            # diverge like 1/sqrt(depth): the square-root singularity)
            # or a change of the contacts that the gap cannot see, told by the flow just beyond
            # (on a rigid wall an impact added to a chatter, or the chatter completing into
            # sticking: the map is nonsmooth there too)
            n_beyond = _contacts_beyond(pmap, good, bracket, M) if good is not a else None
            changed = n_beyond is not None and n_beyond != int(good.ev.contacts.sum())
            if good is not a and (pmap.gap(good.ev.points, good.ev.contacts, good.p) < GRAZE_GAP
                                  or float(np.abs(good.mult).max()) > GRAZE_MULTIPLIER or changed):
                trial = good
                if trial.tangent @ a.tangent < 0:
                    trial.tangent = -trial.tangent
                stop = _graze(good, bracket, bad, n_beyond)
                if stop:
                    break
                continue
        if trial is None:
            ds *= 0.5
            if abs(ds) < ds_min:
                end_note = f"corrector failed down to the smallest step {ds_min:g} (orbit lost)"
                break
            continue
        turn = float(trial.tangent @ a.tangent)
        if abs(turn) < MAX_TURN and abs(ds) > 4 * ds_min:
            # the tangent turned too much in one step: the corrector may have fallen back onto the
            # branch already followed (a step across a fold); retry shorter
            ds *= 0.5
            continue
        if turn < 0:  # keep the orientation through folds
            trial.tangent = -trial.tangent
        failed_here = False
        if not np.array_equal(trial.ev.contacts, a.ev.contacts):
            good, bracket, bad = cont.locate_contact_change(a, ds)
            if _graze(good, bracket, bad):
                break
            continue
        ta, tb = a.tests(), trial.tests()
        if M % 2 == 0:
            # a period-2m branch that runs into the flip of the period-m orbit it was born from:
            # z_0 - z_m changes sign there (beyond, the branch is the same orbit shifted by m)
            e = a.ev.points[0] - a.ev.points[M // 2]
            e = e / max(float(np.linalg.norm(e)), 1e-300)
            ta["halving"] = float(e @ (a.ev.points[0] - a.ev.points[M // 2]))
            tb["halving"] = float(e @ (trial.ev.points[0] - trial.ev.points[M // 2]))
            if ta["halving"] * tb["halving"] < 0:
                # where the branch meets the period-m orbit: that orbit's flip, located on the
                # period-m orbit itself (the corrector here would fall onto it: it solves F^M = w too)
                pt, bracket = _flip_of_half(cont, a, trial, M // 2)
                event("flip", pt, bracket, f"the period-{M} branch meets the period-{M // 2} orbit at its flip "
                      "(beyond: the same orbit shifted by half its period); branch ends")
                end_note = f"branch point at {pmap.param} = {pt.p:.10g}"
                break
        for kind in ("flip", "fold", "ns"):
            fa, fb = ta[kind], tb[kind]
            if math.isfinite(fa) and math.isfinite(fb) and fa * fb < 0:
                pt, bracket = cont.locate_root(a, ds, lambda q, k=kind: q.tests()[k], fa, fb)
                if kind == "ns" and abs(pt.mult[0].imag) < 1e-12:
                    continue  # a real pair with product 1: a neutral saddle, not a bifurcation
                if pt.tangent @ a.tangent < 0:
                    pt.tangent = -pt.tangent
                event(kind, pt, bracket)
        pts.append(trial)
        labels.append("")
        a = trial
        steps += 1
        if progress is not None:
            progress.update(1)
        ds = math.copysign(min(abs(ds) * (1.5 if its <= 3 else (0.5 if its >= 6 else 1.0)), ds_max), ds)
    # located events were appended out of order: sort points by continuation order
    last = pts[-1]
    events.append(Event("end", last.p, len(pts) - 1, last.mult, last.ev.points[0], 0.0, end_note))
    return _branch(pmap, M, pts, labels, events)


def _sticks(pt: BranchPoint) -> bool:
    """The orbit sticks to a rigid wall for part of its period: its Jacobian is exactly 0."""
    return bool(np.max(np.abs(pt.mult)) == 0.0)


def _contacts_beyond(pmap: PeriodMap, good: BranchPoint, bracket: float, M: int) -> int | None:
    """Contacts per M periods of the flow started on the last good orbit just beyond it (in the
    direction of continuation), after one M-period transient.  Where the corrector fails at a
    contact change that the gap does not see (a flight between two impacts of one period reaching
    the wall again: an impact added to a chatter; or the chatter completing into sticking), the
    flow itself says the contacts changed.  None when the run is not finite."""
    step = 2.0 * max(bracket, 1e-9 * max(1.0, abs(good.p)))
    p = good.p + math.copysign(step, float(good.tangent[2]))
    pts, cont = pmap.run(p, good.ev.points[0], 2 * M)
    return int(cont[-M:].sum()) if np.all(np.isfinite(pts)) else None


def _flip_of_half(cont: ArclengthCorrector, a: BranchPoint, b: BranchPoint, m: int) -> tuple[BranchPoint, float]:
    """The flip of the period-m orbit between two points of a period-2m branch that runs into it:
    secant iterations in p on det(D(F^m) + I) of the period-m orbit (Newton-refined at each p from
    the midpoint of the branch's z_0 and z_m).  Returns the period-2m branch point there (the
    period-m orbit run twice, multipliers mu_m^2) and the last secant step in p."""
    pmap = cont.pmap
    w_mid = 0.5 * (b.ev.points[0] + b.ev.points[m]) - pmap.offset(b.p)

    def f(p: float) -> tuple[float, np.ndarray]:
        w, ev, ok, _ = refine_orbit(pmap, w_mid, p, m)
        return (float(np.linalg.det(ev.J + np.eye(2))) if ok else math.nan), w

    p0, p1 = a.p, b.p
    f0, w0 = f(p0)
    f1, w1 = f(p1)
    step = abs(p1 - p0)
    for _ in range(30):
        if not (math.isfinite(f0) and math.isfinite(f1)) or f1 == f0:
            break
        p2 = p1 - f1 * (p1 - p0) / (f1 - f0)
        p0, f0 = p1, f1
        f1, w1 = f(p2)
        step, p1 = abs(p2 - p0), p2
        if step < cont.locate_tol:
            break
    w, ev, ok, _ = refine_orbit(pmap, w1, p1, 2 * m)
    return BranchPoint(w, p1, ev), step


def _new_contact_orbit(cont: ArclengthCorrector, good: BranchPoint, bad: BranchPoint | None) -> BranchPoint | None:
    """The orbit with another contact count next to a graze at ``good``: the corrector's own
    solution beyond it if it converged, else Newton at fixed p on both sides of the graze."""
    near = max(1e3 * cont.locate_tol, 1e-6)
    if (bad is not None and not np.array_equal(bad.ev.contacts, good.ev.contacts)
            and float(np.max(np.abs(bad.x - good.x))) < near):
        # the corrector's own solution just past the graze (not an orbit elsewhere it fell onto)
        return _oriented(bad, bad.x - good.x)
    pmap, M = cont.pmap, cont.M
    h = max(1e3 * cont.locate_tol, 1e-6)
    for dp in (h * good.tangent[2] / max(abs(good.tangent[2]), 1e-300), -h * np.sign(good.tangent[2])):
        for dw in (good.tangent[:2] * 1e-3, -good.tangent[:2] * 1e-3, np.zeros(2)):
            w, ev, ok, _ = refine_orbit(pmap, good.w + dw, good.p + dp, M)
            if ok and not np.array_equal(ev.contacts, good.ev.contacts) and float(np.max(np.abs(w - good.w))) < 1e-2:
                pt = BranchPoint(w, good.p + dp, ev)
                return _oriented(pt, pt.x - good.x)
    return None


def _oriented(pt: BranchPoint, away: np.ndarray) -> BranchPoint:
    if pt.tangent @ away < 0:
        pt.tangent = -pt.tangent
    return pt


def _branch(pmap: PeriodMap, M: int, pts: list[BranchPoint], labels: list[str], events: list[Event]) -> Branch:
    return Branch(
        param=pmap.param, M=M, params=dict(pmap.params), theta=pmap.theta,
        values=np.array([p.p for p in pts]), points=np.array([p.ev.points for p in pts]),
        contacts=np.array([p.ev.contacts for p in pts]), multipliers=np.array([p.mult for p in pts]),
        gaps=np.array([pmap.gap(p.ev.points, p.ev.contacts, p.p) for p in pts]), labels=labels,
        events=events, derivatives=pmap.derivatives, periods_run=pmap.evaluations)


def switch_at_flip(sim: Simulator, params: Mapping[str, Any], branch: Branch, event: Event,
                   delta: float = 1e-4, **kwargs: Any) -> Branch | None:
    """Start the period-2M branch at a located flip of ``branch`` and continue it.

    The period-2M orbit bifurcates from the flip point along the eigenvector e of mu = -1, with
    amplitude ~ sqrt(|p - p_flip|).  Newton on F^{2M} is started at p_flip +- ``delta`` from
    z_flip +- sqrt(delta) e (then with delta / 100); the first solution that is not the period-M
    orbit (|F^M(w) - w| > 1e-7) and has twice its contacts starts :func:`continue_orbit` with period 2M, directed away from the flip.
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
    impacts = 2 * int(np.asarray(branch.contacts[event.index]).sum())
    for d in (delta, 1e-2 * delta):
        for side in (+1.0, -1.0):
            p = event.value + side * d
            for amp in (+1.0, -1.0):
                w, ev2, ok, _ = refine_orbit(pmap, w_f + amp * math.sqrt(d) * e, p, 2 * M)
                # the bifurcating orbit: period 2M (not the period-M orbit) with the contacts of two
                # turns of the period-M orbit (not a coexisting orbit Newton may fall onto)
                if not ok or int(ev2.contacts.sum()) != impacts:
                    continue
                half = pmap.evaluate(w, p, M, derivatives=False).image
                if float(np.max(np.abs(half - w))) > 1e-7:
                    z = w + pmap.offset(p)
                    return continue_orbit(sim, params, 2 * M, p, z, direction=side, pmap=pmap, **kwargs)
    return None
