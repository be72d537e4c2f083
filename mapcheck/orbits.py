"""Periodic orbits of any stroboscopic map by Newton's method, and window edges by
continuation + bisection.

Works for maps without a closed-form orbit: the physical map (31)/(32), its A~ and
delay variants, and the exact pre-impact map of the ODE (:mod:`mapcheck.exact`).  A map
is given as ``step(u, v) -> (u1, v1, contacts)`` at fixed parameters, where
``contacts`` counts impacts / wall entries during the step (for (31): 1 if chi >= 0).

A *maximal* period-M orbit (figure 8) has exactly one impacting step per period.

A map that knows its own derivative (the FMU with sensitivity outputs) is given as
``dstep(u, v) -> (u1, v1, contacts, J)``; Newton then uses the chained exact Jacobian
D(F^M) = J_M ... J_1 from the same pass that computes the orbit, instead of 4 more orbits
per iteration for central differences.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = ["PeriodicOrbit", "solve_periodic_orbit", "window_edge", "map_step"]

Step = Callable[[float, float], tuple[float, float, int]]
DerivativeStep = Callable[[float, float], tuple[float, float, int, np.ndarray]]


@dataclass
class PeriodicOrbit:
    """A period-M orbit z_1..z_M (z_{M+1} = z_1).

    Attributes
    ----------
    z : ndarray, shape (M, 2)
    contacts : ndarray of int, shape (M,)
        Contacts during step k (z_k -> z_{k+1}).
    multipliers : ndarray (complex), shape (2,)
        Eigenvalues of D(F^M)(z_1) (central finite differences).
    converged : bool
    residual : float
        |F^M(z_1) - z_1|.
    """

    z: np.ndarray
    contacts: np.ndarray
    multipliers: np.ndarray
    converged: bool
    residual: float

    @property
    def stable(self) -> bool:
        return bool(self.converged and np.all(np.abs(self.multipliers) < 1.0))

    @property
    def maximal(self) -> bool:
        """Exactly one step of the period has a contact, and it has exactly one."""
        return bool(self.converged and np.count_nonzero(self.contacts) == 1 and self.contacts.max() == 1)


def map_step(f: Callable, *args, contact: Callable | None = None) -> Step:
    """Wrap a vectorized map ``f(u, v, *args) -> (u1, v1)`` as a :data:`Step`;
    ``contact(u, v) -> bool`` says whether the step impacts (e.g. chi >= 0)."""

    def step(u: float, v: float) -> tuple[float, float, int]:
        u1, v1 = f(u, v, *args)
        c = int(bool(contact(u, v))) if contact is not None else 0
        return float(u1), float(v1), c

    return step


def _orbit(step: Step, z: np.ndarray, M: int) -> tuple[np.ndarray, np.ndarray]:
    pts = np.empty((M + 1, 2))
    cont = np.empty(M, dtype=int)
    pts[0] = z
    for k in range(M):
        u, v, c = step(float(pts[k, 0]), float(pts[k, 1]))
        pts[k + 1] = u, v
        cont[k] = c
    return pts, cont


def _orbit_with_jacobian(dstep: DerivativeStep, z: np.ndarray, M: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The orbit, its contacts and D(F^M)(z) = J_M ... J_1 from one pass of ``dstep``."""
    pts = np.empty((M + 1, 2))
    cont = np.empty(M, dtype=int)
    J = np.eye(2)
    pts[0] = z
    for k in range(M):
        u, v, c, Jk = dstep(float(pts[k, 0]), float(pts[k, 1]))
        pts[k + 1] = u, v
        cont[k] = c
        J = np.asarray(Jk, dtype=float) @ J
    return pts, cont, J


def _jacobian(step: Step, z: np.ndarray, M: int, h: np.ndarray, base: np.ndarray | None = None) -> np.ndarray:
    """Central differences of F^M.  If a perturbed orbit changes its contact pattern (the
    orbit is within h of grazing, where the map has a square-root singularity) the step is
    shrunk, down to 1e-6 of the original, so that both stencil points stay on one branch.
    ``base``: the contacts of the orbit from z, where the caller has them already."""
    if base is None:
        base = _orbit(step, z, M)[1]
    for shrink in (1.0, 1e-2, 1e-4, 1e-6):
        J = np.empty((2, 2))
        same = True
        for j in range(2):
            dz = np.zeros(2)
            dz[j] = h[j] * shrink
            zp, cp = _orbit(step, z + dz, M)
            zm, cm = _orbit(step, z - dz, M)
            same &= bool(np.array_equal(cp, base) and np.array_equal(cm, base))
            J[:, j] = (zp[-1] - zm[-1]) / (2.0 * dz[j])
        if same:
            break
    return J


def solve_periodic_orbit(step: Step, z0, M: int, *, tol: float = 1e-12, max_iter: int = 40,
                         rel_h: float = 1e-6, scale: np.ndarray | None = None,
                         dstep: DerivativeStep | None = None) -> PeriodicOrbit:
    """Newton's method on F^M(z) - z = 0 with a finite-difference Jacobian, or with the
    map's own derivative when ``dstep`` is given.

    Parameters
    ----------
    step : callable
        ``step(u, v) -> (u1, v1, contacts)``.
    z0 : array_like, shape (2,)
        Initial guess for z_1.
    M : int
    tol : float
        Convergence: |F^M(z) - z| < tol * max(scale).
    rel_h : float
        Finite-difference step relative to ``scale``.
    scale : ndarray, shape (2,), optional
        Typical size of (u, v); default |z0| (at least 1e-12).
    dstep : callable, optional
        ``dstep(u, v) -> (u1, v1, contacts, J)``, the same map with its Jacobian: used
        instead of ``step`` and of the differences (``rel_h`` is then unused).

    Returns
    -------
    PeriodicOrbit
    """
    z = np.asarray(z0, dtype=float).copy()
    sc = np.maximum(np.abs(z), 1e-12) if scale is None else np.asarray(scale, dtype=float)
    h = rel_h * sc
    converged = False
    res = np.inf
    DF = None
    for _ in range(max_iter):
        if dstep is not None:
            pts, cont, DF = _orbit_with_jacobian(dstep, z, M)
        else:
            pts, cont = _orbit(step, z, M)
        g = pts[-1] - z
        res = float(np.max(np.abs(g)))
        if res < tol * float(np.max(sc)):
            converged = True
            break
        J = (DF if DF is not None else _jacobian(step, z, M, h, cont)) - np.eye(2)
        try:
            dz = np.linalg.solve(J, -g)
        except np.linalg.LinAlgError:
            break
        # damp huge steps (non-smooth maps): never move by more than the orbit's scale
        big = np.max(np.abs(dz) / sc)
        if big > 1.0:
            dz /= big
        z = z + dz
    if not np.all(np.isfinite(z)):
        pts, cont = _orbit(step, z, M)
        mult = np.full(2, np.nan)
    elif dstep is not None:
        if not converged:  # converged: the last pass was at this very z, reuse it
            pts, cont, DF = _orbit_with_jacobian(dstep, z, M)
        mult = np.linalg.eigvals(DF)
    else:
        if not converged:  # converged: the last pass was at this very z, reuse it
            pts, cont = _orbit(step, z, M)
        mult = np.linalg.eigvals(_jacobian(step, z, M, h, cont))
    return PeriodicOrbit(pts[:-1], cont, mult.astype(complex), converged, res)


def edge_kind(orb: PeriodicOrbit) -> str:
    """Why a periodic orbit stopped being a stable maximal one, at the far side of an edge.

    Returns "lost" (no convergence), "graze" (an extra or double contact), "no-impact",
    "torus" (complex multipliers leave the unit circle), "flip" (a multiplier through -1)
    or "fold" (through +1).
    """
    if not orb.converged:
        return "lost"
    if np.count_nonzero(orb.contacts) > 1 or orb.contacts.max() > 1:
        return "graze"
    if np.count_nonzero(orb.contacts) == 0:
        return "no-impact"
    m = orb.multipliers[np.argmax(np.abs(orb.multipliers))]
    if abs(m.imag) > 1e-9:
        return "torus"
    return "flip" if m.real < 0 else "fold"


def window_edge(step_of: Callable[[float], Step], M: int, p_in: float, z_in, direction: float,
                dp: float, p_limit: float, xtol: float = 1e-7, **newton) -> tuple[float, str, PeriodicOrbit]:
    """March from ``p_in`` (a stable maximal period-M orbit near ``z_in``) in ``direction``
    until the orbit is lost (unstable, extra or missing contact, Newton failure), then
    bisect the edge to ``xtol``, continuing the orbit as the initial guess.

    Returns
    -------
    (edge, kind, orbit)
        Last parameter value with a stable maximal orbit, the reason it is lost beyond
        (see :class:`mapcheck.windows.Window`; "lost" if Newton fails, "range" if
        ``p_limit`` is reached), and the orbit at the edge.
    """
    def ok(p: float, z) -> tuple[bool, PeriodicOrbit]:
        orb = solve_periodic_orbit(step_of(p), z, M, **newton)
        return orb.maximal and orb.stable, orb

    good, orb = ok(p_in, z_in)
    if not good:
        raise ValueError(f"no stable maximal period-{M} orbit at p = {p_in}")
    p_good, z_good = p_in, orb.z[int(np.argmax(orb.contacts > 0) + 1) % M]
    # keep z_1 = the point right after the impacting step, so continuation is consistent
    while True:
        p_next = p_good + direction * dp
        if (p_next - p_limit) * direction > 0:
            return p_good, "range", orb
        good, o2 = ok(p_next, z_good)
        if not good:
            p_bad, orb_bad = p_next, o2
            break
        p_good, orb = p_next, o2
        z_good = orb.z[int(np.argmax(orb.contacts > 0) + 1) % M]
    while abs(p_bad - p_good) > xtol:
        pm = 0.5 * (p_good + p_bad)
        good, o2 = ok(pm, z_good)
        if good:
            p_good, orb = pm, o2
            z_good = orb.z[int(np.argmax(orb.contacts > 0) + 1) % M]
        else:
            p_bad, orb_bad = pm, o2
    kind = edge_kind(orb_bad)
    if kind == "lost":
        # Newton found nothing beyond the edge: look at the edge orbit's contacts there
        for cont in (_orbit(step_of(p_bad), orb.z[0], M)[1], orb_bad.contacts):
            if np.count_nonzero(cont) > 1 or cont.max() > 1:
                kind = "graze"
                break
            if not cont.any():
                kind = "no-impact"
                break
    return p_good, kind, orb
