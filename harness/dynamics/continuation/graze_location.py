"""A graze of a continued branch located on its defining equation, with an interval that contains it.

At a graze the orbit's contact pattern changes because one contact of one period is exactly
tangent to the wall.  Seen from the orbit on either side, that is the zero of a smooth quantity
of the orbit:

* a period without contact (a free passage): its **gap**, the distance to the wall of its
  highest point, reaches 0 (the passage touches the wall);
* a period with contacts: the **entry velocity** of its first contact, the velocity relative to
  the wall when the free flight from the section reaches it, reaches 0 (the impact dies out).

Where the quantity is a free passage's gap or the entry velocity of a period's only contact, the
graze is solved with its orbit by Newton on the extended system (:mod:`.graze_newton`: orbit +
gap = 0, the grazing period a free flight), to the rounding of the map, and its interval is the
solve's.  Otherwise (the flight after an impact on a rigid wall, the first of several contacts, or
where that Newton fails) it is extrapolated as follows.

Both are smooth functions along the branch (the impacting orbit's family is smooth in its impact
velocity: on a rigid wall sigma(v) is analytic, while the stroboscopic map and its multipliers
blow up like 1/v, which is why Newton gives up a little before the graze).  Neither is ever
solved for as "the last parameter where Newton converged": :func:`locate_graze` samples the branch
on the orbit's own side at defining values q from the nearest well-conditioned one q0 (or the
nearest Newton reached) to 4 q0, fits the parameter as a polynomial in q (degrees 3 and 4) and takes p(q = 0).
The interval it reports is that value plus and minus three times the sum of the truncation error
(the two degrees' difference) and the data error (each sample's q moved by one more Newton
correction of its orbit, carried through the fit), so that it contains the zero of the defining
equation, not just the last orbit that converged.

Both quantities come from the free flow's closed form (8) between the section and the contact
(:func:`harness.dynamics.maps.jacobian.free_propagator`), on the FMU's orbit.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from mapcheck.segments import brentq  # scipy.optimize imported on first use

from .arclength import ArclengthCorrector, BranchPoint
from ...config.defaults import WALLS
from .graze_newton import solve_graze
from ..maps.jacobian import free_propagator
from ..maps.periodic_map import PeriodMap, refine_orbit, wall_free_offset

__all__ = ["GrazeLocation", "locate_graze", "entry_velocity", "period_quantities", "CONTACT_CHANGE_SLACK",
           "contact_change_interval"]

TWO_PI = 2.0 * math.pi

#: Samples per period of the free flight when its first wall crossing is searched.
FLIGHT_SAMPLES = 96

#: On a rigid wall, periods with up to this many impacts are followed flight by flight (each
#: flight's gap and each impact's entry velocity); a longer chatter only by its first contact.
RIGID_FLIGHTS_MAX = 4

#: Smallest entry velocity (relative to 1 + |sigma|) used in a fit: below it the crossing time's
#: rounding (~eps / v) makes v itself uncertain to ~eps a / v.
VELOCITY_FLOOR = 1e-4

#: Smallest gap (relative to 1 + |sigma|) used in a fit (the gap is computed to rounding).
GAP_FLOOR = 1e-9

#: The defining values sampled lie in [q0, SPREAD q0], q0 the nearest usable one (a narrow
#: spread: the extrapolation to q = 0 from [q0, 4 q0] errs by ~q0^5 with degree 4).
SPREAD = 4.0

#: Residual max |F^M(w) - w| of the orbits fitted (the corrector's 1e-10 would make the gap
#: uncertain to ~1e-10, carried through the extrapolation).
SAMPLE_TOL = 1e-13

#: Degrees of the polynomials p(q) compared: their zeros' difference bounds the truncation.
DEGREES = (3, 4)

#: Where no defining quantity locates a contact change, its interval (the last orbit with the old
#: contacts, the first parameter without them) is widened by this times 1 + |p| on both sides: those
#: orbits are the corrector's (residual 1e-10), and next to a graze it accepts orbits with the old
#: contacts where none exists at a residual of 1e-13.  Measured on Figure 9's compliant grazes (before
#: they were located on their gap): the last orbit lay 1.3e-9 to 2.9e-9 (up to 1.6e-9 (1 + |sigma|))
#: past the exact graze, its 5e-10 to 8e-10 bracket excluding it.  An empirical bound, said so
#: in the event's note, three times the largest excess measured over 1 + |p|.
CONTACT_CHANGE_SLACK = 5e-9


@dataclass
class GrazeLocation:
    """A graze on its defining equation.

    Attributes
    ----------
    value : float
        The parameter where the defining quantity reaches zero (the fit's p at q = 0).
    interval : (float, float)
        An interval of the parameter that contains that zero.
    quantity : str
        ``"gap"`` (a free passage reaching the wall) or ``"entry velocity"`` (a contact dying out).
    period : int
        Which period k = 0..M-1 of the orbit grazes.
    samples : int
        Orbits of the fit.
    nearest : float
        The smallest defining value among them.
    flight : int
        Which flight of that period (0: from the section to the first contact; j: after the j-th
        impact, on a rigid wall).
    method : str
        ``"newton"`` (solved with the orbit on the extended system, :mod:`.graze_newton`;
        ``samples`` its iterations, ``nearest`` the final |gap|) or ``"fit"`` (extrapolated).
    """

    value: float
    interval: tuple[float, float]
    quantity: str
    period: int
    samples: int
    nearest: float
    flight: int = 0
    method: str = "fit"

    @property
    def width(self) -> float:
        return self.interval[1] - self.interval[0]


class _Flight:
    """A free flight of one period (exact: the linear free flow), in time t relative to the section,
    from the state ``z`` at t = ``t0``."""

    def __init__(self, pmap: PeriodMap, z: np.ndarray, p: float, t0: float = 0.0) -> None:
        prm = pmap.at(p)
        self.nu, self.Om = float(prm["nu"]), float(prm["Omega"])
        self.amp = 1.0 + pmap.sigma(p)
        self.theta, self.t0 = pmap.theta, float(t0)
        self.x = np.asarray(z, dtype=float) - self._p(self.t0)

    def _p(self, t: float) -> np.ndarray:
        th = TWO_PI * (self.theta + t)
        return np.array([self.amp * math.cos(th) - 1.0, -TWO_PI * self.amp * math.sin(th)])

    def state(self, t: float) -> tuple[float, float]:
        z = free_propagator(self.nu, self.Om, t - self.t0) @ self.x + self._p(t)
        return float(z[0]), float(z[1])

    def grid(self, t1: float) -> tuple[np.ndarray, np.ndarray]:
        t = np.linspace(self.t0, t1, max(8, int(FLIGHT_SAMPLES * (t1 - self.t0))) + 1)
        P1 = free_propagator(self.nu, self.Om, t[1] - t[0])
        x, hom = self.x.copy(), np.empty(t.size)
        for i in range(t.size):  # P(i dt) x by repeated steps (a semigroup)
            hom[i] = x[0]
            x = P1 @ x
        return t, hom + self.amp * np.cos(TWO_PI * (self.theta + t)) - 1.0

    def highest_near(self, lo: float, hi: float) -> float:
        """The time of the local maximum of u in [lo, hi] (golden-section: u is unimodal there)."""
        g = (math.sqrt(5.0) - 1.0) / 2.0
        a, b = lo, hi
        for _ in range(80):
            c, d = b - g * (b - a), a + g * (b - a)
            if self.state(c)[0] < self.state(d)[0]:
                a = c
            else:
                b = d
            if b - a < 1e-15:
                break
        return 0.5 * (a + b)

    def first_entry(self, t1: float) -> float | None:
        """The first time in (t0, t1] that u crosses 0 upward, or None."""
        t, u = self.grid(t1)
        for i in range(1, t.size):
            if u[i] > 0.0 and u[i - 1] <= 0.0:
                return brentq(lambda s: self.state(s)[0], t[i - 1], t[i], xtol=1e-16, rtol=1e-15)
            if i < t.size - 1 and u[i] >= u[i - 1] and u[i] >= u[i + 1] and u[i - 1] <= 0.0:
                # a maximum between samples may reach the wall by less than their spacing shows
                tm = self.highest_near(t[i - 1], t[i + 1])
                if self.state(tm)[0] > 0.0:
                    return brentq(lambda s: self.state(s)[0], t[i - 1], tm, xtol=1e-16, rtol=1e-15)
        return None

    def highest_inside(self, t1: float) -> float | None:
        """The highest u at a local maximum strictly inside (t0, t1), or None."""
        t, u = self.grid(t1)
        tops = [self.state(self.highest_near(t[i - 1], t[i + 1]))[0]
                for i in range(1, t.size - 1) if u[i] >= u[i - 1] and u[i] >= u[i + 1]]
        return max(tops) if tops else None


def entry_velocity(pmap: PeriodMap, z: np.ndarray, p: float) -> float:
    """Velocity at the first wall entry (u = 0 upward) of the free flight from the section point
    ``z`` within one period; NaN when the flight does not reach the wall, or when ``z`` lies
    inside it (a compliant wall's contact across the section: no free flight starts there)."""
    if float(z[0]) > 0.0:
        return math.nan
    fl = _Flight(pmap, z, p)
    tc = fl.first_entry(1.0)
    return math.nan if tc is None else fl.state(tc)[1]


def _rigid_period(pmap: PeriodMap, z: np.ndarray, p: float, n: int) -> dict[tuple[int, str], float] | None:
    """Flight by flight through one period with ``n`` impacts on a rigid wall (free flights, each
    impact v -> -r v): the gap of every flight's highest inner point, the entry velocity of every
    impact; None when the flights do not meet the wall ``n`` times (a chatter the sampling cannot
    resolve, a sticking phase)."""
    r = float(pmap.at(p)["r"])
    out: dict[tuple[int, str], float] = {}
    fl = _Flight(pmap, z, p)
    for j in range(n + 1):
        tc = fl.first_entry(1.0)
        top = fl.highest_inside(1.0 if tc is None else tc)
        if top is not None and top < 0.0:
            out[(j, "gap")] = -top
        if tc is None:
            return out if j == n else None
        if j == n:
            return None
        v = fl.state(tc)[1]
        out[(j, "entry velocity")] = v
        fl = _Flight(pmap, np.array([0.0, -r * v]), p, tc)
    return None


def period_quantities(pmap: PeriodMap, z: np.ndarray, n: int, p: float) -> dict[tuple[int, str], float]:
    """The defining quantities of one period (section point ``z``, ``n`` contacts), by (flight,
    kind): the gap of a period without contact; on a rigid wall every flight's gap and impact's
    entry velocity; on a compliant wall the entry velocity of the first contact."""
    if n == 0:
        return {(0, "gap"): pmap.gap(np.asarray(z)[None, :], np.zeros(1, dtype=int), p)}
    if int(pmap.params.get("wall", WALLS["compliant"])) == WALLS["rigid"] and n <= RIGID_FLIGHTS_MAX:
        flights = _rigid_period(pmap, z, p, n)
        if flights is not None:
            return flights
    return {(0, "entry velocity"): entry_velocity(pmap, z, p)}


def _orbit_quantities(pmap: PeriodMap, pt: BranchPoint) -> dict[tuple[int, int, str], float]:
    return {(k, *key): q for k, n in enumerate(pt.ev.contacts)
            for key, q in period_quantities(pmap, pt.ev.points[k], int(n), pt.p).items()}


def _grazing_key(pmap: PeriodMap, a: BranchPoint, good: BranchPoint) -> tuple[int, int, str] | None:
    """The (period, flight, kind) whose quantity is heading to zero between ``a`` and ``good``: the
    one that fell the most (relatively), if one fell at all."""
    qa, qg = _orbit_quantities(pmap, a), _orbit_quantities(pmap, good)
    best, key = 1.0, None
    for k in qa.keys() & qg.keys():
        if math.isfinite(qa[k]) and math.isfinite(qg[k]) and qa[k] > 0 and qg[k] > 0 and qg[k] / qa[k] < best:
            best, key = qg[k] / qa[k], k
    return key


def _quantity(pmap: PeriodMap, pt: BranchPoint, key: tuple[int, int, str]) -> float:
    """The defining quantity ``key`` = (period, flight, kind) of the orbit at ``pt``."""
    k, j, kind = key
    return period_quantities(pmap, pt.ev.points[k], int(pt.ev.contacts[k]), pt.p).get((j, kind), math.nan)


def _sample(cont: ArclengthCorrector, a: BranchPoint, good: BranchPoint, k: tuple[int, int, str], q0: float,
            q1: float) -> list[tuple[float, float, float]]:
    """Orbits of the branch behind ``good`` (old contacts) with the quantity in [q0, q1]: marched
    back from ``good`` in steps aimed at q1 / 8 apart, halved where the corrector fails (next to a
    rigid wall's graze its Newton basin shrinks like the squared entry velocity) and doubled again
    after it succeeds; (p, q, uncertainty of q) per orbit."""
    pmap, out = cont.pmap, []
    prev, q_prev = good, _quantity(pmap, good, k)
    dist = float(np.linalg.norm(good.x - a.x))
    rate = (_quantity(pmap, a, k) - q_prev) / dist  # dq/ds, from a to good
    cap, fails = dist / 8.0, 0
    if q_prev >= q0:
        out.append(_with_error(pmap, good, q_prev, k))
    while q_prev < q1 and fails < 24 and len(out) < 16:
        aim = max(q0, q_prev) + (q1 - q0) / 8.0
        back = min((aim - q_prev) / rate, cap)
        pt = cont.along(prev, -back)
        if pt is None or not np.array_equal(pt.ev.contacts, good.ev.contacts):
            cap, fails = back / 2.0, fails + 1
            continue
        pt = _refined(cont, pt)
        if pt.tangent @ good.tangent < 0:
            pt.tangent = -pt.tangent
        q = _quantity(pmap, pt, k)
        if not (math.isfinite(q) and q > q_prev):
            break  # the quantity no longer grows away from the graze: not this one's branch
        rate = (q - q_prev) / float(np.linalg.norm(pt.x - prev.x))
        prev, q_prev, cap = pt, q, 2.0 * back
        if q < q0:
            continue
        out.append(_with_error(pmap, pt, q, k))
    return out


def _refined(cont: ArclengthCorrector, pt: BranchPoint) -> BranchPoint:
    """The orbit at ``pt.p`` refined by Newton at fixed p towards a residual of :data:`SAMPLE_TOL`
    (the corrector's orbit is good to its 1e-10 only): the refined orbit where its residual is
    smaller (next to a rigid graze rounding times the large Jacobian may floor it above the
    tolerance), else ``pt``."""
    res0 = float(np.max(np.abs(pt.ev.image - pt.w)))
    w, ev, _, res = refine_orbit(cont.pmap, pt.w, pt.p, cont.M, tol=SAMPLE_TOL, max_iter=4)
    if res < res0 and np.array_equal(ev.contacts, pt.ev.contacts):
        return BranchPoint(w, pt.p, ev)
    return pt


def _with_error(pmap: PeriodMap, pt: BranchPoint, q: float, k: tuple[int, int, str]) -> tuple[float, float, float]:
    """(p, q, uncertainty of q): the orbit is known to its corrector's residual, so one more Newton
    correction of it moves q by about q's error."""
    try:
        dw = np.linalg.solve(pt.ev.J - np.eye(2), -(pt.ev.image - pt.w))
        q_moved = _quantity_from(pmap, pt.ev.points[0] + dw, pt.ev.contacts, pt.p, k)
    except np.linalg.LinAlgError:
        q_moved = math.nan
    err = abs(q_moved - q) if math.isfinite(q_moved) else abs(q)
    return pt.p, q, err + 64.0 * np.finfo(float).eps * (1.0 + abs(pt.p))


def _quantity_from(pmap: PeriodMap, z0: np.ndarray, contacts: np.ndarray, p: float,
                   key: tuple[int, int, str]) -> float:
    """The quantity ``key`` of the orbit started at ``z0`` (run to its period by the FMU)."""
    k, j, kind = key
    z = np.asarray(z0, dtype=float)
    if k:
        run, _ = pmap.run(p, z, k)
        z = run[-1]
    return period_quantities(pmap, z, int(contacts[k]), p).get((j, kind), math.nan)


def _fit_zero(data: list[tuple[float, float, float]]) -> tuple[float, float] | None:
    """p at q = 0 from polynomials p(q) of the degrees :data:`DEGREES` (least squares); (value, error bound)."""
    p = np.array([d[0] for d in data])
    q = np.array([d[1] for d in data])
    dq = np.array([d[2] for d in data])
    if q.size < DEGREES[1] + 3:
        return None
    scale = float(q.max())
    x = q / scale
    zeros = []
    for deg in DEGREES:
        V = np.vander(x, deg + 1, increasing=True)
        pinv = np.linalg.pinv(V)
        coef = pinv @ (p - p[0])
        zeros.append((p[0] + coef[0], coef, pinv[0]))
    value, coef, row0 = zeros[1]
    truncation = abs(zeros[1][0] - zeros[0][0])
    # |dp/dq| over the samples, from the fit's own coefficients
    slope = float(sum(j * abs(coef[j]) * float(x.max()) ** (j - 1) for j in range(1, coef.size))) / scale
    data_err = slope * float(np.abs(row0) @ dq)
    rounding = 64.0 * np.finfo(float).eps * (1.0 + abs(value))
    return float(value), 3.0 * (truncation + data_err) + rounding


def contact_change_interval(p: float, bracket: float, direction: float) -> tuple[float, float]:
    """The interval of a contact change located by the contact pattern only: from the last orbit
    with the old contacts at ``p`` to the first parameter without them ``bracket`` beyond it (towards
    ``direction``), widened by :data:`CONTACT_CHANGE_SLACK` (1 + |p|) on both sides."""
    slack = CONTACT_CHANGE_SLACK * (1.0 + abs(p))
    d = math.copysign(1.0, direction)
    lo, hi = sorted((p - d * slack, p + d * (abs(bracket) + slack)))
    return lo, hi


def _newton(cont: ArclengthCorrector, good: BranchPoint, key: tuple[int, int, str]) -> GrazeLocation | None:
    """The graze solved with its orbit (:func:`.graze_newton.solve_graze`) where the quantity is a free
    passage's gap or the entry velocity of a period's only contact (at the graze both are a free
    flight touching the wall); None otherwise or where Newton fails."""
    k, j, kind = key
    n = int(good.ev.contacts[k])
    if j != 0 or not ((kind == "gap" and n == 0) or (kind == "entry velocity" and n == 1)):
        return None
    sol = solve_graze(cont.pmap, good.w, good.p, cont.M, k, good.ev.contacts)
    if sol is None:
        return None
    v, h = sol["value"], sol["half_width"]
    return GrazeLocation(v, (v - h, v + h), kind, k, sol["iterations"], abs(sol["gap"]), 0, "newton")


def locate_graze(cont: ArclengthCorrector, a: BranchPoint, good: BranchPoint) -> GrazeLocation | None:
    """Locate the graze that ends the old contact pattern just beyond ``good`` (the last orbit with
    it, after ``a`` on the branch), on its defining equation.

    Returns None when no period's gap or first entry velocity heads to zero (another contact
    change: an impact added inside a chatter, the sticking onset), which the caller locates by the
    contact pattern.
    """
    pmap = cont.pmap
    key = _grazing_key(pmap, a, good)
    if key is None:
        return None
    qa, qg = _quantity(pmap, a, key), _quantity(pmap, good, key)
    s = float(np.linalg.norm(good.x - a.x))
    if s == 0.0 or not qa > qg:
        return None
    solved = _newton(cont, good, key)
    if solved is not None:
        return solved
    floor = (VELOCITY_FLOOR if key[2] == "entry velocity" else GAP_FLOOR) * (1.0 + abs(pmap.sigma(good.p)))
    q0 = max(qg, floor)
    data = _sample(cont, a, good, key, q0, SPREAD * q0)
    fit = _fit_zero(data)
    if fit is None:
        return None
    value, err = fit
    # Every sample has q > 0, so the zero lies beyond the nearest of them; a fitted zero behind it
    # is not the zero this change is at.  It may well lie behind ``good`` itself: ``good`` is the
    # contact-change bisection's last orbit, corrected to the corrector's residual only (1e-10),
    # which moves a free passage's highest point by ~1e-11 and so its contact count by ~1e-9 in
    # sigma next to a compliant wall's graze (Figure 9's windows: ``good`` 1.3e-9 to 2.9e-9 past
    # the exact graze, the refined samples' zero within 1e-10 of it).
    nearest = min(data, key=lambda d: d[1])[0]
    if (value - nearest) * math.copysign(1.0, float(good.tangent[2])) < -err:
        return None
    return GrazeLocation(value, (value - err, value + err), key[2], key[0], len(data), min(d[1] for d in data), key[1])
