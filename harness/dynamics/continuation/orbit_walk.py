"""One continuation of a periodic orbit under way (:func:`.continuation.continue_orbit`): the
steps of the pseudo-arclength corrector, and the events met between two accepted points.

The branch so far, its current end, the step and the events are kept together in
:class:`OrbitWalk`, since a graze switches the current end to the orbit with the new contact
count (and counts as a step), and a located event ends the branch or adds a point to it.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from .arclength import ArclengthCorrector, BranchPoint
from .branch import Branch, Event
from .graze_location import CONTACT_CHANGE_SLACK, GrazeLocation, contact_change_interval, locate_graze
from ...config.defaults import WALLS
from ..maps.periodic_map import PeriodMap, refine_orbit
from .section_crossing import impact_at_section, section_crossed, section_crossing
from .step_control import StepControl

__all__ = ["OrbitWalk", "STICK_IMPACTS"]

#: Impacts per period from which a new contact pattern on a rigid wall is a chatter ending in
#: sticking (the FMU ends chatter by sticking after ~100 impacts).
STICK_IMPACTS = 20

#: Smallest cosine between the tangents of two accepted points (larger turns: a shorter step).
MAX_TURN = 0.98

#: A gap (distance to the wall of a free passage) below this at a corrector failure is a graze.
GRAZE_GAP = 1e-5

#: A multiplier above this at a corrector failure: a contact of the orbit is grazing.
GRAZE_MULTIPLIER = 1e3

#: A located flip (fold) is kept only with a multiplier within this of -1 (+1): det(D + I) also
#: changes sign where a multiplier passes through infinity (the 1/v of a grazing impact's
#: saltation), which is a pole of the test function, not a bifurcation.
POLE_TOL = 1e-2


def _growth(iterations: int) -> float:
    """Step growth after a corrector that took ``iterations``: longer after an easy step,
    shorter after a hard one."""
    return 1.5 if iterations <= 3 else (0.5 if iterations >= 6 else 1.0)


class OrbitWalk:
    """One continuation of a periodic orbit under way: the branch so far, its current end ``a``,
    the step, and the events met (kept together, since a graze switches the current end to the
    orbit with the new contact count and counts as a step).

    Parameters
    ----------
    cont : ArclengthCorrector
    a : BranchPoint
        The first point, its tangent oriented in the direction of continuation.
    control : StepControl
    follow_grazing : bool
    progress : tqdm-like or None
    """

    def __init__(self, cont: ArclengthCorrector, a: BranchPoint, control: StepControl, follow_grazing: bool,
                 progress: Any) -> None:
        self.cont, self.pmap, self.M = cont, cont.pmap, cont.M
        self.a = a
        self.control = control
        self.follow_grazing = follow_grazing
        self.progress = progress
        self.pts: list[BranchPoint] = [a]
        self.labels = [""]
        self.events: list[Event] = []
        #: the corrector already failed from the current point (its corner was looked at)
        self.failed_here = False

    def record(self, kind: str, pt: BranchPoint, bracket: float, note: str = "",
               located: GrazeLocation | None = None) -> None:
        """Add a located event point to the branch (a graze with its location on the defining
        equation: its value and interval, the point staying the last orbit with the old contacts)."""
        self.pts.append(pt)
        self.labels.append(kind)
        ev = Event(kind, pt.p, len(self.pts) - 1, pt.mult, pt.ev.points[0], bracket, note)
        if located is not None:
            ev.value, ev.bracket, ev.interval, ev.quantity = located.value, located.width, located.interval, located.quantity
        elif kind in ("graze", "stick"):
            # located by the contact pattern only: the corrector's last orbit with the old contacts
            # may lie beyond the change (by ~1e-9 next to a compliant graze), so its interval is
            # widened to one that holds the change
            ev.quantity = "contacts"
            ev.interval = contact_change_interval(pt.p, bracket, float(pt.tangent[2]))
            ev.bracket = ev.interval[1] - ev.interval[0]
            ev.note += (f"; located by the contact change only, in [{ev.interval[0]:.12g}, {ev.interval[1]:.12g}] "
                        f"(the bisection's bracket widened by {CONTACT_CHANGE_SLACK:g} (1 + |p|) each side: "
                        "its orbits are the corrector's, to 1e-10)")
        self.events.append(ev)

    def advance(self, pt: BranchPoint) -> None:
        """Make ``pt`` the current end of the branch."""
        self.pts.append(pt)
        self.labels.append("")
        self.a = pt

    def step(self) -> bool:
        """Try one step from the current point; False when the branch ends."""
        a, sc = self.a, self.control
        trial, its = self.cont.correct(a.x + sc.size * a.tangent, a.tangent, lenient=True)
        if trial is None and not self.failed_here:
            self.failed_here = True
            go_on = self.graze_at_corner()
            if go_on is not None:
                return go_on
        if trial is None:
            if not sc.shrink():
                sc.stop("lost", f"corrector failed down to the smallest step {sc.smallest:g} (orbit lost)")
                return False
            return True
        moved = not np.array_equal(trial.ev.contacts, a.ev.contacts)
        crossing = moved and section_crossed(self.pmap, a, trial, sc.size)
        turn = float(trial.tangent @ a.tangent)
        if crossing:
            # an impact time crossed a section t = theta + k: the same orbit, but a section point
            # may have jumped across that impact, so the tangents' w parts are not comparable;
            # the orientation is the parameter's direction
            if trial.tangent[2] * a.tangent[2] < 0:
                trial.tangent = -trial.tangent
        else:
            if abs(turn) < MAX_TURN and sc.can_shrink():
                # the tangent turned too much in one step: the corrector may have fallen back onto
                # the branch already followed (a step across a fold); retry shorter
                sc.shrink()
                return True
            if turn < 0:  # keep the orientation through folds
                trial.tangent = -trial.tangent
        self.failed_here = False
        if moved and not crossing:
            good, bracket, bad = self.cont.locate_contact_change(a, sc.size)
            return not self.graze(good, bracket, bad)
        # (across an impact at the section z_0 - z_m may change sign without meeting the period-m orbit)
        if not moved and self.meets_half_period_flip(trial):
            return False
        self.locate_smooth_events(trial)
        self.advance(trial)
        sc.accept(_growth(its))
        if self.progress is not None:
            self.progress.update(1)
        return True

    def graze_at_corner(self) -> bool | None:
        """After a first corrector failure from the current point: a graze there, or None.

        The corrector fails where the branch has a corner: a graze that is a nonsmooth fold (the
        orbit meets its partner with the extra contact on the wall).  Bisect on "converges with
        the same contacts"; a vanishing gap there is a graze.  Returns whether the branch goes on
        after the graze, None when the failure is not a graze.
        """
        a = self.a
        good, bracket, bad = self.cont.locate_contact_change(a, self.control.size)
        crossed = section_crossing(self.cont, good) if good is not a else None
        if crossed is not None:
            # an impact reached the section phase: the same orbit goes on, its section point
            # across the impact (not an event)
            self.advance(crossed)
            self.control.count()
            return True
        # a vanishing gap of a free passage, or a contact becoming grazing (its multipliers
        # diverge like 1/sqrt(depth): the square-root singularity)
        # or a change of the contacts that the gap cannot see, told by the flow just beyond
        # (on a rigid wall an impact added to a chatter, or the chatter completing into
        # sticking: the map is nonsmooth there too)
        # the current point itself is the last good one where the step had already shrunk onto
        # the corner (the bisection's bracket within the location's tolerance)
        at_corner = good is not a or bracket <= 10.0 * self.cont.locate_tol
        n_beyond = _contacts_beyond(self.pmap, good, bracket, self.M) if at_corner else None
        changed = n_beyond is not None and n_beyond != int(good.ev.contacts.sum())
        if not at_corner or not (self.pmap.gap(good.ev.points, good.ev.contacts, good.p) < GRAZE_GAP
                             or float(np.abs(good.mult).max()) > GRAZE_MULTIPLIER or changed):
            return None
        if good.tangent @ a.tangent < 0:
            good.tangent = -good.tangent
        return not self.graze(good, bracket, bad, n_beyond)

    def graze(self, good: BranchPoint, bracket: float, bad: BranchPoint | None, n_beyond: int | None = None) -> bool:
        """Record a graze at ``good``; switch to the orbit with the new contact count if it
        exists (True: the branch ends here)."""
        a, M = self.a, self.M
        n_old = int(a.ev.contacts.sum())
        # the graze on its defining equation (gap or entry velocity = 0), None for another change
        # (where the walk had shrunk onto the corner, the last good orbit is its current point:
        # the samples of the defining quantity start from the point before it)
        located = locate_graze(self.cont, a if good is not a or len(self.pts) < 2 else self.pts[-2], good)
        at = located.value if located is not None else good.p
        nxt = _new_contact_orbit(self.cont, good, bad, at) if self.follow_grazing else None
        if nxt is not None and int(nxt.ev.contacts.sum()) == n_old and impact_at_section(self.pmap, good):
            # an impact time crossed the section phase: the same orbit goes on, no event
            self.advance(nxt)
            self.control.count()
            return False
        if nxt is not None and any(np.array_equal(np.roll(nxt.ev.contacts, k), good.ev.contacts) for k in range(M)):
            nxt = None  # the same contacts shifted: the same orbit again, not a new one
        kind = self.graze_kind(good, nxt if nxt is not None else bad, n_beyond)
        if kind != "graze":
            located = None
        how = _how_located(located)
        if nxt is None:
            self.record(kind, good, bracket, f"{n_old} impact(s) per period before; no orbit with another contact "
                        "count found next to it" + ("" if self.follow_grazing else " (not sought)") + "; branch ends"
                        + how, located)
            self.control.stop(kind, f"{kind} at {self.pmap.param} = {at if located else good.p:.10g}")
            return True
        n_new = int(nxt.ev.contacts.sum())
        how_on = "beyond it" if (nxt.p - good.p) * (good.p - a.p) > 0 else "back on the same side (nonsmooth fold)"
        self.record(kind, good, bracket, f"{n_old} -> {n_new} impacts per period; continued {how_on}" + how, located)
        self.advance(nxt)
        self.control.count()
        return False

    def graze_kind(self, good: BranchPoint, other: BranchPoint | None, n_beyond: int | None) -> str:
        """"stick" for the sticking onset on a rigid wall, else "graze"."""
        rigid = int(self.pmap.params.get("wall", WALLS["none"])) == WALLS["rigid"]
        if rigid and other is not None:
            # the sticking onset: on one side the orbit sticks to the wall for part of the period
            # (its D(F^M) is exactly 0: the sticking phase forgets the state), on the other not
            if _sticks(good) != _sticks(other):
                return "stick"
        elif rigid and n_beyond is not None and n_beyond >= STICK_IMPACTS:
            return "stick"  # nothing to compare: the flow beyond chatters as long as a sticking orbit
        return "graze"

    def meets_half_period_flip(self, trial: BranchPoint) -> bool:
        """A period-2m branch that runs into the flip of the period-m orbit it was born from:
        z_0 - z_m changes sign there (beyond, the branch is the same orbit shifted by m).
        Records that flip and ends the branch (True)."""
        a, M = self.a, self.M
        if M % 2:
            return False
        e = a.ev.points[0] - a.ev.points[M // 2]
        e = e / max(float(np.linalg.norm(e)), 1e-300)
        halving_a = float(e @ (a.ev.points[0] - a.ev.points[M // 2]))
        halving_b = float(e @ (trial.ev.points[0] - trial.ev.points[M // 2]))
        if not halving_a * halving_b < 0:
            return False
        # where the branch meets the period-m orbit: that orbit's flip, located on the
        # period-m orbit itself (the corrector here would fall onto it: it solves F^M = w too)
        pt, bracket = _flip_of_half(self.cont, a, trial, M // 2)
        lo, hi = sorted((a.p, trial.p))
        # the branch turns at the flip (p = p_flip + c s^2 along it), so the flip lies near the
        # step, not necessarily inside it; one far away: z_0 - z_m changed sign for another reason
        near = max(10.0 * (hi - lo), 1e-4 * (1.0 + abs(pt.p)), 10.0 * bracket)
        if not lo - near <= pt.p <= hi + near:
            return False
        self.record("flip", pt, bracket, f"the period-{M} branch meets the period-{M // 2} orbit at its flip "
                    "(beyond: the same orbit shifted by half its period); branch ends")
        self.control.stop("flip", f"branch point at {self.pmap.param} = {pt.p:.10g}")
        return True

    def locate_smooth_events(self, trial: BranchPoint) -> None:
        """Locate and record each flip, fold and NS between the current point and ``trial``."""
        a = self.a
        ta, tb = a.tests(), trial.tests()
        for kind in ("flip", "fold", "ns"):
            fa, fb = ta[kind], tb[kind]
            if math.isfinite(fa) and math.isfinite(fb) and fa * fb < 0:
                pt, bracket = self.cont.locate_root(a, self.control.size, lambda q, k=kind: q.tests()[k], fa, fb)
                if kind == "ns" and abs(pt.mult[0].imag) < 1e-12:
                    continue  # a real pair with product 1: a neutral saddle, not a bifurcation
                if kind != "ns" and float(np.min(np.abs(pt.mult - (1.0 if kind == "fold" else -1.0)))) > POLE_TOL:
                    continue  # the test changed sign through a pole (a multiplier through infinity), not a zero
                if pt.tangent @ a.tangent < 0:
                    pt.tangent = -pt.tangent
                self.record(kind, pt, bracket)

    def branch(self) -> Branch:
        """The branch walked, closed by its ``end`` event.  Its points are in the order they were
        found: an event located inside a step comes before the step's end point (two events of
        one step in the order flip, fold, ns), so no sort is needed."""
        last = self.pts[-1]
        self.events.append(Event("end", last.p, len(self.pts) - 1, last.mult, last.ev.points[0], 0.0,
                                 self.control.note))
        return _branch(self.pmap, self.M, self.pts, self.labels, self.events)


def _how_located(located: GrazeLocation | None) -> str:
    """The note's account of how a graze was located."""
    if located is None:
        return ""
    lo, hi = located.interval
    j = located.flight
    if located.quantity == "gap":
        which = f"gap of period {located.period}" + (f" after its impact {j}" if j else "")
    else:
        which = f"entry velocity of impact {j + 1} of period {located.period}"
    if located.method == "newton":
        return (f"; located where the {which} reaches 0, solved with the orbit by Newton on the extended system "
                f"(orbit + gap of the free flight = 0, {located.samples} iterations), in [{lo:.15g}, {hi:.15g}]")
    return (f"; located where the {which} reaches 0 (fit of {located.samples} orbits down to "
            f"{located.nearest:.2g}), in [{lo:.12g}, {hi:.12g}]")


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


def _new_contact_orbit(cont: ArclengthCorrector, good: BranchPoint, bad: BranchPoint | None,
                       at: float) -> BranchPoint | None:
    """The orbit with another contact count next to a graze at ``at`` (``good`` the last orbit with
    the old contacts): the corrector's own solution beyond it if it converged, else Newton at fixed
    p on both sides of the graze."""
    near = max(1e3 * cont.locate_tol, 1e-6)
    if (bad is not None and not np.array_equal(bad.ev.contacts, good.ev.contacts)
            and float(np.max(np.abs(bad.x - good.x))) < near):
        # the corrector's own solution just past the graze (not an orbit elsewhere it fell onto)
        return _oriented(bad, bad.x - good.x)
    pmap, M = cont.pmap, cont.M
    h = max(1e3 * cont.locate_tol, 1e-6)
    ahead = float(np.sign(good.tangent[2])) or 1.0
    # on both sides of the graze, measured from the graze itself (which the last orbit that
    # converged may be well short of, next to a rigid wall's square-root singularity)
    for p in (at + h * ahead, at - h * ahead, good.p + h * ahead, good.p - h * ahead):
        for dw in (good.tangent[:2] * 1e-3, -good.tangent[:2] * 1e-3, np.zeros(2)):
            w, ev, ok, _ = refine_orbit(pmap, good.w + dw, p, M)
            if ok and not np.array_equal(ev.contacts, good.ev.contacts) and float(np.max(np.abs(w - good.w))) < 1e-2:
                pt = BranchPoint(w, p, ev)
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
