"""An impact time crossing the section phase t = theta + k: no event, the same orbit going on.

The contacts counted per sampled period move from one period to the next when an impact time of
the orbit crosses a section t = theta + k; their number over the M periods, the orbit and its
multipliers do not change.  At an inner section (0 < k < M) F^M is smooth there and the corrector
steps across (:func:`section_crossed` tells such a step from a fall onto another orbit); at theta
itself the section point z_0 jumps across the impact (pre-impact velocity <-> post-impact by the
jump law), which the corrector cannot step over: :func:`section_crossing` finds the orbit beyond
from the jumped state.
"""
from __future__ import annotations

import numpy as np

from ...config.defaults import WALLS
from .arclength import ArclengthCorrector, BranchPoint
from ..maps.periodic_map import PeriodMap, refine_orbit

__all__ = ["SECTION_WALL_TOL", "impact_at_section", "section_crossed", "section_crossing"]


def section_crossed(pmap: PeriodMap, a: BranchPoint, b: BranchPoint, step: float) -> bool:
    """Between a and b the contacts moved between the periods of the orbit, their number over M
    periods the same, and b is a's orbit: its multipliers within 0.2, its section points away from
    the wall within max(0.05, 20 step) of a's.  An impact time crossed a section t = theta + k;
    the orbit, its impacts and multipliers go on, so this is no event (at an inner section F^M is
    smooth; at theta itself z_0 jumps across the impact)."""
    if int(b.ev.contacts.sum()) != int(a.ev.contacts.sum()):
        return False
    k = _crossed_section(np.asarray(a.ev.contacts), np.asarray(b.ev.contacts))
    if k is None:
        return False
    u_wall = float(pmap.params.get("u_wall", 0.0))
    pa, pb = np.asarray(a.ev.points), np.asarray(b.ev.points)
    moved = float(np.max(np.abs(np.delete(pa, k, axis=0) - np.delete(pb, k, axis=0)))) if len(pa) > 1 else 0.0
    # the section point between the two periods passed the wall within the step
    if min(abs(pa[k, 0] - u_wall), abs(pb[k, 0] - u_wall)) > max(10.0 * moved, 10.0 * step, 1e-6):
        return False
    if float(np.max(np.abs(np.sort_complex(a.mult) - np.sort_complex(b.mult)))) > 0.2:
        return False
    away = (np.abs(pa[:, 0] - u_wall) > 1e-2) & (np.abs(pb[:, 0] - u_wall) > 1e-2)
    return bool(not np.any(away) or float(np.max(np.abs(pa[away] - pb[away]))) <= max(0.05, 20.0 * step))


#: A section point this close to the wall (relative to the orbit's size) has an impact at the
#: section phase: the contact change there is the impact crossing the section, not a graze.
SECTION_WALL_TOL = 1e-6


def _crossed_section(ca: np.ndarray, cb: np.ndarray) -> int | None:
    """The index k of the section t = theta + k an impact crossed between the contact patterns ca and
    cb (one contact moved to the neighbouring period: out of period k - 1 into period k, or back),
    or None where the patterns differ otherwise."""
    d = cb - ca
    nz = np.flatnonzero(d)
    M = len(ca)
    if len(nz) != 2 or sorted(d[nz]) != [-1, 1]:
        return None
    i, j = int(nz[d[nz] == 1][0]), int(nz[d[nz] == -1][0])  # into period i, out of period j
    if i == (j + 1) % M:
        return i  # later: past t = theta + i
    if j == (i + 1) % M:
        return j  # earlier: back before t = theta + j
    return None


def impact_at_section(pmap: PeriodMap, pt: BranchPoint) -> bool:
    """One of the orbit's section points lies on the wall: an impact at t = theta + k."""
    size = max(1.0, float(np.max(np.abs(pt.ev.points))))
    u_wall = float(pmap.params.get("u_wall", 0.0))
    return bool(np.min(np.abs(np.asarray(pt.ev.points)[:, 0] - u_wall)) <= SECTION_WALL_TOL * size)


def section_crossing(cont: ArclengthCorrector, good: BranchPoint) -> BranchPoint | None:
    """The orbit just beyond ``good`` when ``good``'s section point z_0 lies on the wall (an impact
    at t = theta): z_0 jumps across that impact (pre-impact v <-> post-impact state by the jump
    law), so the corrector cannot step over it, but the orbit, its contacts per M periods and its
    multipliers are continuous.  Newton from the jumped state a little beyond ``good``; the point
    found is kept when it has the same number of contacts, the same other section points and
    nearby multipliers.  None where ``good`` has no impact at its section or nothing is found."""
    pmap, M = cont.pmap, cont.M
    z0 = np.asarray(good.ev.points[0], dtype=float)
    u_wall = float(pmap.params.get("u_wall", 0.0))
    size = max(1.0, float(np.max(np.abs(good.ev.points))))
    if abs(z0[0] - u_wall) > SECTION_WALL_TOL * size:
        return None
    r = float(pmap.params.get("r", 1.0))
    rigid = int(pmap.params.get("wall", 0)) == WALLS["rigid"]
    vs = (-r * z0[1], -z0[1] / r) if rigid else (r * z0[1], z0[1] / r)
    ahead = float(np.sign(good.tangent[2])) or 1.0
    n_old = int(good.ev.contacts.sum())
    for h in (max(10.0 * cont.locate_tol, 1e-9), 1e-7, 1e-6):
        p = good.p + ahead * h * (1.0 + abs(good.p))
        for v in vs:
            start = np.array([min(z0[0], u_wall) if rigid else z0[0], v])
            w, ev, ok, _ = refine_orbit(pmap, start - pmap.offset(p), p, M)
            if not ok or int(ev.contacts.sum()) != n_old:
                continue
            rest = float(np.max(np.abs(ev.points[1:] - good.ev.points[1:]))) if M > 1 else 0.0
            mult = np.sort_complex(np.linalg.eigvals(ev.J))
            if rest < 1e-3 * size and float(np.max(np.abs(mult - np.sort_complex(good.mult)))) < 1e-2:
                pt = BranchPoint(w, p, ev)
                if pt.tangent[2] * ahead < 0:
                    pt.tangent = -pt.tangent
                return pt
    return None
