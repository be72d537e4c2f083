"""A graze solved with its orbit: Newton on the extended system, as flips and folds are.

At a graze one period of the orbit touches the wall tangentially: a contact of zero entry velocity
is no contact at all (it changes neither the state nor its derivatives), so the grazing orbit is an
orbit of the map in which that period is a *free flight* -- the linear free flow (8) in closed
form, with no wall -- and the highest point of that flight is on the wall.  In the unknowns (w, p)
(w = z - p(theta) the orbit's section point, p the continued parameter):

    F_k^M(w, p) - w = 0,      gap_k(w, p) = 0,

F_k^M the M-period map with period k replaced by the free flight (the other periods the FMU's),
gap_k the wall's distance from that flight's highest point.  Both are smooth on both sides of the
graze -- the free flight is analytic, and the other periods keep their contacts -- while the
FMU's own map is not: an iterate whose flight dips 1e-13 into the wall gets a contact, whose
restitution changes the state by (1 - r) v_entry ~ sqrt(1e-13).  So Newton converges
quadratically to the graze itself, to the rounding of the map (1e-13 and better with the
closed-form solver; CVODE's tolerance otherwise), the same from the impacting side (an entry
velocity heading to 0) as from the free side (a gap heading to 0).

Derivatives by central differences on the extended map (exact to ~1e-10 relative; Newton's
convergence only needs them approximately, its answer is the residual's zero).  The interval
reported is the solve's: three times the last correction plus the residual's effect, the
residual at the solution (the map's rounding or the solver's tolerance) carried to p through the
extended Jacobian.

Solved this way: a free passage's gap (a period without contact), and the entry velocity of a
period's only contact.  Others (the flight after an impact on a rigid wall, the first of several
contacts) are left to :func:`.graze_location.locate_graze`'s extrapolation.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..maps.jacobian import free_propagator
from ..maps.periodic_map import PeriodMap

__all__ = ["solve_graze", "free_flight_map", "MAX_ITER"]

#: Newton iterations before the solve gives up.
MAX_ITER = 20

#: Relative step of the central differences (of (w, p), scale 1 + |x|).
FD_STEP = 1e-6

#: The solution may lie at most this far (relative, 1 + |p|) from the last orbit with the old
#: contacts: a graze farther off is another branch's.
MAX_SHIFT = 1e-3


def free_flight_map(pmap: PeriodMap, w: np.ndarray, p: float, M: int, k: int) -> tuple[np.ndarray, np.ndarray,
                                                                                         np.ndarray] | None:
    """The M-period map at (w, p) with period ``k`` a free flight: (image in w coordinates, the
    section points z_0..z_{M-1}, contacts per period (0 for period ``k``)); None where the FMU fails."""
    prm = pmap.at(p)
    off = pmap.offset(p)
    z = np.asarray(w, dtype=float) + off
    pts, cont = np.empty((M, 2)), np.zeros(M, dtype=int)
    i = 0
    while i < M:
        if i == k:
            pts[i] = z
            # the forcing is 1-periodic: the free flow over one period from the section to the next
            z = free_propagator(float(prm["nu"]), float(prm["Omega"]), 1.0) @ (z - off) + off
            i += 1
            continue
        n = (k if i < k else M) - i
        try:
            run, c = pmap.run(p, z, n)
        except Exception:  # noqa: BLE001  (any refusal of the FMU: no image here)
            return None
        if not np.all(np.isfinite(run)):
            return None
        pts[i:i + n], cont[i:i + n] = run[:-1], c
        z = run[-1]
        i += n
    return z - off, pts, cont


def _residual(pmap: PeriodMap, x: np.ndarray, M: int, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    out = free_flight_map(pmap, x[:2], float(x[2]), M, k)
    if out is None:
        return None
    image, pts, cont = out
    g = pmap.gap(pts[k][None, :], np.zeros(1, dtype=int), float(x[2]))
    return np.append(image - x[:2], g), pts, cont


def _jacobian(pmap: PeriodMap, x: np.ndarray, M: int, k: int) -> np.ndarray | None:
    J = np.empty((3, 3))
    for j in range(3):
        h = FD_STEP * (1.0 + abs(x[j]))
        e = np.zeros(3)
        e[j] = h
        plus, minus = _residual(pmap, x + e, M, k), _residual(pmap, x - e, M, k)
        if plus is None or minus is None:
            return None
        J[:, j] = (plus[0] - minus[0]) / (2.0 * h)
    return J if np.all(np.isfinite(J)) else None


def solve_graze(pmap: PeriodMap, w: np.ndarray, p: float, M: int, k: int,
                contacts: np.ndarray) -> dict[str, Any] | None:
    """The graze of period ``k`` of the period-M orbit near (``w``, ``p``) (the last orbit with the
    old contacts ``contacts``), by Newton on the extended system.

    Returns ``{"value", "half_width", "w", "iterations", "gap", "residual"}``, or None where Newton
    does not converge, the solution lies farther than :data:`MAX_SHIFT` from ``p``, or its other
    periods' contacts are not ``contacts``' (another branch)."""
    x = np.append(np.asarray(w, dtype=float), float(p))
    r = _residual(pmap, x, M, k)
    if r is None:
        return None
    scale = 1.0 + abs(pmap.sigma(float(p)))  # the orbit's size: u ~ 1 + sigma, v ~ 2 pi (1 + sigma)
    eps = np.finfo(float).eps
    last = math.inf
    for it in range(1, MAX_ITER + 1):
        J = _jacobian(pmap, x, M, k)
        if J is None:
            return None
        try:
            dx = np.linalg.solve(J, -r[0])
        except np.linalg.LinAlgError:
            return None
        x_new = x + dx
        r_new = _residual(pmap, x_new, M, k)
        if r_new is None or not np.all(np.isfinite(r_new[0])):
            return None
        step = float(np.max(np.abs(dx) / (1.0 + np.abs(x))))
        x, r = x_new, r_new
        if step < 64.0 * eps or (step >= last and step < 1e-9):
            break  # at the rounding of the map: another step only moves x within it
        last = step
    else:
        return None
    res = float(np.max(np.abs(r[0])))
    if res > 1e-8 * scale or abs(x[2] - p) > MAX_SHIFT * (1.0 + abs(p)):
        return None
    others = [i for i in range(M) if i != k]
    if not np.array_equal(r[2][others], np.asarray(contacts)[others]):
        return None
    try:
        row = np.abs(np.linalg.inv(J)[2])
    except np.linalg.LinAlgError:
        return None
    # the residual at the solution is the map's rounding (or the solver's tolerance), measured as the
    # residual's departure from its linear model 1e-12 away; its effect on p through the Jacobian
    d = 1e-12 * (1.0 + np.abs(x)) * np.array([1.0, -1.0, 1.0])
    r_d = _residual(pmap, x + d, M, k)
    dev = np.abs(r_d[0] - r[0] - J @ d) if r_d is not None else np.full(3, np.inf)
    noise = float(row @ np.maximum(np.maximum(np.abs(r[0]), dev), 4.0 * eps * scale))
    half = 3.0 * (abs(float(dx[2])) + noise) + 16.0 * eps * (1.0 + abs(x[2]))
    return {"value": float(x[2]), "half_width": half, "w": x[:2].copy(), "iterations": it,
            "gap": float(r[0][2]), "residual": res}
