"""The M-period stroboscopic map of the FMU in any parameter, with its exact derivatives.

G(w, p) = F^M(w + o(p); p) - o(p) - w, where F is the FMU's one-period map at the section
phase ``theta`` and o(p) = p(theta) the wall-free orbit (4) (see :mod:`.shooting` for why the
coordinates w = z - p(theta) are used).  One FMU run of M periods gives the orbit, the contacts of
every period and, from the FMU's sensitivity outputs, D(F^M) and d(F^M)/d sigma exactly.  For a
parameter other than sigma the parameter derivative is a central difference (two more runs).

Also here: the *gap* of an orbit, the smallest distance to the wall reached during its
non-impacting periods, computed from the wall-free closed form (8) of those periods (no contact
in the period means the flow there is the free linear flow), so it is a smooth function of the
parameter that crosses 0 at a graze.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from .jacobian import free_propagator, resolve_method
from ...config.defaults import SOLVERS, WALLS
from ...errors import FmuRejectedInput, HarnessInputError
from ...fmu.simulator import Simulator

__all__ = ["MapEvaluation", "PeriodMap", "failed_evaluation", "map_accuracy", "wall_free_offset"]

TWO_PI = 2.0 * math.pi

#: Error of one period of CVODE's map per unit of its relative tolerance ``rtol``: at the default
#: rtol = 1e-12, F^M of CVODE and of the closed form differ by 1e-11 to 1e-10 per period on
#: orbits of a rigid and a compliant wall (up to 1e-8 over 6 periods from a state far from any
#: orbit), so a Newton residual of 7e-10 is CVODE's accuracy, not a failure.
CVODE_ERROR_PER_RTOL = 1e3


#: A Newton tolerance below this asks to polish an orbit as far as the map allows (see refine_orbit).
POLISH_TOL = 1e-11


def map_accuracy(params: Mapping[str, Any], M: int = 1) -> float:
    """The residual max |F^M(w) - w| the FMU's map resolves with the solver in ``params``: 0 for the
    closed form (exact up to rounding: the callers' own tolerances apply), M periods of CVODE's
    error at its ``rtol`` otherwise (the FMU's default solver is CVODE)."""
    if int(params.get("solver", 0)) == SOLVERS["closed-form"]:
        return 0.0
    return CVODE_ERROR_PER_RTOL * max(1, int(M)) * float(params.get("rtol", 1e-12))


def wall_free_offset(sigma: float, theta: float) -> np.ndarray:
    """p(theta), p'(theta) of (4): the wall-free orbit at the section phase."""
    th = TWO_PI * theta
    return np.array([(1.0 + sigma) * math.cos(th) - 1.0, -TWO_PI * (1.0 + sigma) * math.sin(th)])


@dataclass
class MapEvaluation:
    """One evaluation of F^M at (w, p).

    Attributes
    ----------
    image : ndarray (2,)
        F^M in w coordinates.
    points : ndarray (M, 2)
        The stroboscopic points z_0 .. z_{M-1} (absolute (u, v) at t = theta + k).
    contacts : ndarray of int (M,)
        Wall entries (impacts) during each period.
    J : ndarray (2, 2) or None
        D(F^M) (the same in w and z coordinates).
    dp : ndarray (2,) or None
        d(image)/dp at fixed w.
    """

    image: np.ndarray
    points: np.ndarray
    contacts: np.ndarray
    J: np.ndarray | None = None
    dp: np.ndarray | None = None


class PeriodMap:
    """F^M of the FMU at section phase ``theta`` as a function of (w, p).

    Parameters
    ----------
    sim : Simulator
        The FMU (restarted for every evaluation).
    params : mapping
        FMU parameters; ``param`` is set per evaluation.
    param : str
        The parameter varied (any settable Real parameter of the FMU).
    theta : float
        Section phase, away from the impacts (default 1/2).
    derivatives : {"auto", "exact", "fd"}
        D(F^M) from the FMU's variational equations ("exact", the default when available) or
        by central differences.
    h_param : float
        Relative step of the central difference in ``param`` (not sigma with exact derivatives).
    """

    def __init__(self, sim: Simulator, params: Mapping[str, Any], param: str = "sigma", theta: float = 0.5,
                 derivatives: str = "auto", h_param: float = 1e-6) -> None:
        self.sim = sim
        self.params = {k: v for k, v in params.items() if k not in ("u0", "v0")}
        self.param = param
        if param in ("u0", "v0", "wall", "solver", "contact", "sensitivities"):
            raise HarnessInputError("param", f"{param!r} cannot be continued (not a real model parameter)")
        self.theta = float(theta)
        self.derivatives = resolve_method(sim, derivatives, "derivatives")
        if hasattr(sim, "track_derivatives"):
            sim.track_derivatives(self.derivatives == "exact")
        self.h_param = float(h_param)
        self.evaluations = 0  # periods integrated

    def tol(self, M: int, tol: float) -> float:
        """``tol``, or the residual the solver resolves over M periods where that is larger
        (:func:`map_accuracy`): Newton and the corrector stop at what the map can tell apart."""
        return max(float(tol), map_accuracy(self.params, M))

    # -- coordinates ----------------------------------------------------------------------
    def at(self, p: float) -> dict[str, Any]:
        """The FMU parameters at parameter value ``p``."""
        return {**self.params, self.param: float(p)}

    def sigma(self, p: float) -> float:
        return float(p) if self.param == "sigma" else float(self.params.get("sigma", 0.0))

    def offset(self, p: float) -> np.ndarray:
        """o(p) = p(theta): z = w + o."""
        return wall_free_offset(self.sigma(p), self.theta)

    def _doffset(self) -> np.ndarray:
        """do/dp (nonzero for sigma only)."""
        if self.param != "sigma":
            return np.zeros(2)
        th = TWO_PI * self.theta
        return np.array([math.cos(th), -TWO_PI * math.sin(th)])

    # -- evaluation -----------------------------------------------------------------------
    def run(self, p: float, z0: np.ndarray, periods: int) -> tuple[np.ndarray, np.ndarray]:
        """Points z_0..z_periods (absolute) and contacts per period, one run."""
        sim = self.sim
        sim.start(self.at(p), self.theta, (float(z0[0]), float(z0[1])))
        pts = np.empty((periods + 1, 2))
        cont = np.empty(periods, dtype=int)
        pts[0] = z0
        n_prev = 0
        for k in range(periods):
            sim.advance(self.theta + k + 1.0)
            u, v, n = sim.read()
            pts[k + 1] = u, v
            cont[k] = n - n_prev
            n_prev = n
        self.evaluations += periods
        return pts, cont

    def evaluate(self, w: np.ndarray, p: float, M: int, derivatives: bool = True) -> MapEvaluation:
        """F^M at (w, p) in w coordinates; with ``derivatives``: D(F^M) and d/dp.

        A point inside a rigid wall is not a state (the FMU refuses it): a Newton or predictor
        step that lands there gets a non-finite image, which every caller treats as a failed
        evaluation (a shorter step, or no orbit), instead of an error that ends the search.  So does
        a parameter the FMU refuses (sigma <= -1: no forcing), which a corrector near the end of an
        even sigma range can step to.
        """
        off = self.offset(p)
        z0 = np.asarray(w, dtype=float) + off
        u_wall = float(self.params.get("u_wall", 0.0))
        inside = int(self.params.get("wall", WALLS["compliant"])) == WALLS["rigid"] and (z0[0] > u_wall or (z0[0] == u_wall and z0[1] > 0.0))
        try:
            pts, cont = (None, None) if inside else self.run(p, np.asarray(w, dtype=float) + off, M)
        except FmuRejectedInput:
            if self.sigma(p) > -1.0:  # any other refusal is the caller's input: said as such
                raise
            pts = None
        if pts is None:
            return failed_evaluation(M, derivatives)
        image = pts[-1] - off
        if not derivatives:
            return MapEvaluation(image, pts[:-1], cont)
        if self.derivatives == "exact":
            J, S = self.sim.derivatives()  # type: ignore[attr-defined]
        else:
            J = self._fd_jacobian(w, p, M)
            S = None
        if self.param == "sigma" and S is not None:
            do = self._doffset()
            dp = J @ do + S - do
        else:
            h = self.h_param * max(1.0, abs(p))
            plus = self.evaluate(w, p + h, M, False).image
            minus = self.evaluate(w, p - h, M, False).image
            dp = (plus - minus) / (2.0 * h)
        return MapEvaluation(image, pts[:-1], cont, np.asarray(J, dtype=float), dp)

    def _fd_jacobian(self, w: np.ndarray, p: float, M: int) -> np.ndarray:
        J = np.empty((2, 2))
        for j, h in enumerate((1e-7, 1e-6)):
            dw = np.zeros(2)
            dw[j] = h
            J[:, j] = (self.evaluate(w + dw, p, M, False).image - self.evaluate(w - dw, p, M, False).image) / (2 * h)
        return J

    # -- distance to the wall -------------------------------------------------------------
    def gap(self, points: np.ndarray, contacts: np.ndarray, p: float, samples: int = 96) -> float:
        """Smallest distance to the wall (u_wall = 0) over the non-impacting periods of an orbit.

        Each period without contact follows the free linear flow exactly:
        z(t) = P(t)(z_k - p(theta)) + p(theta + t), so its largest u is found on a grid of
        ``samples`` points refined by Newton on v = 0 with the exact free flow.  Returns +inf when every
        period has a contact (nothing to graze), a negative number when a free passage would
        cross the wall (its orbit is virtual there).
        """
        free = [k for k in range(len(contacts)) if contacts[k] == 0]
        if not free:
            return math.inf
        prm = self.at(p)
        nu, Om, sigma = float(prm["nu"]), float(prm["Omega"]), self.sigma(p)
        t = np.linspace(0.0, 1.0, samples + 1)
        dt = t[1]
        P1 = free_propagator(nu, Om, dt)
        off0 = wall_free_offset(sigma, self.theta)
        pu = (1.0 + sigma) * np.cos(TWO_PI * (self.theta + t)) - 1.0
        best = -math.inf
        for k in free:
            x = points[k] - off0
            hom = np.empty(samples + 1)
            for i in range(samples + 1):  # P(i dt) x by repeated steps (exact: a semigroup)
                hom[i] = x[0]
                x = P1 @ x
            u = hom + pu
            i = int(np.argmax(u))
            best = max(best, self._refine_max(points[k] - off0, float(t[i]), nu, Om, sigma))
        return -best

    def _refine_max(self, x: np.ndarray, t0: float, nu: float, Om: float, sigma: float) -> float:
        """Largest u of the free flow z(t) = P(t) x + p(theta + t) near t0: Newton on z'(t)[0] = 0."""
        A = np.array([[0.0, 1.0], [-Om * Om, -nu]])
        amp = 1.0 + sigma

        def state(t: float) -> tuple[np.ndarray, float, float]:
            h = free_propagator(nu, Om, t) @ x
            th = TWO_PI * (self.theta + t)
            u = h[0] + amp * math.cos(th) - 1.0
            v = h[1] - TWO_PI * amp * math.sin(th)
            a = (A @ h)[1] - TWO_PI ** 2 * amp * math.cos(th)
            return h, u, v, a  # type: ignore[return-value]

        t = t0
        _, u, v, a = state(t)
        for _ in range(8):
            if a >= 0:
                break  # not near a maximum: keep the sample
            t_new = min(1.0, max(0.0, t - v / a))
            _, u_new, v, a = state(t_new)
            if u_new < u:
                break
            t, u = t_new, u_new
            if abs(v) < 1e-14:
                break
        return float(u)


def failed_evaluation(M: int, derivatives: bool = True) -> MapEvaluation:
    """A failed evaluation of F^M: non-finite image, points and derivatives (every caller treats
    it as "no orbit here": a shorter step, or the end of a search)."""
    nan = np.full(2, np.nan)
    return MapEvaluation(nan, np.full((M, 2), np.nan), np.zeros(M, dtype=int),
                         None if not derivatives else np.full((2, 2), np.nan),
                         None if not derivatives else nan.copy())


def refine_orbit(pmap: PeriodMap, w0: np.ndarray, p: float, M: int, tol: float = 1e-10,
                 max_iter: int = 12) -> tuple[np.ndarray, MapEvaluation, bool, float]:
    """Newton on F^M(w) - w = 0 at fixed p with D(F^M) from :meth:`PeriodMap.evaluate`, to a
    residual ``tol`` or the solver's accuracy where that is larger (:meth:`PeriodMap.tol`).

    Returns (w, evaluation at w, converged, residual max|F^M(w) - w|).  Steps are damped to at
    most 0.5 in max norm (the map is nonsmooth at grazing; a wild step lands on another branch).
    """
    # converged within the solver's accuracy; a tol far below the default is a request to polish
    # (a graze's samples, a flip at fixed sigma): Newton goes on towards it up to max_iter
    accept = pmap.tol(M, tol) if hasattr(pmap, "tol") else tol
    tol = tol if tol < POLISH_TOL else accept
    w = np.asarray(w0, dtype=float).copy()
    ev = pmap.evaluate(w, p, M)
    res = float(np.max(np.abs(ev.image - w)))
    for _ in range(max_iter):
        if not np.isfinite(res):
            break
        if res < tol:
            return w, ev, True, res
        try:
            dw = np.linalg.solve(ev.J - np.eye(2), -(ev.image - w))
        except np.linalg.LinAlgError:
            break
        big = float(np.max(np.abs(dw)))
        if big > 0.5:
            dw *= 0.5 / big
        w = w + dw
        ev = pmap.evaluate(w, p, M)
        res = float(np.max(np.abs(ev.image - w)))
    return w, ev, bool(res < accept), res
