"""Lyapunov exponents of the stroboscopic map, with an uncertainty.

The exponents of the one-period map F are the growth rates of the singular directions of
the Jacobian products J_N ... J_1 along an orbit.  They are computed by the QR method
(Benettin et al. 1980; Eckmann & Ruelle 1985): Q_0 = I, J_k Q_{k-1} = Q_k R_k, and
lambda_i = (1/N) sum_k log |R_k[i, i]|, in units of 1/(forcing period), natural log.
Re-orthonormalising every period keeps the product from overflowing (a chaotic orbit
stretches by e^{0.3} per period, a strongly damped one contracts by e^{-nu}).

Uncertainty: the per-period logs are split into ``blocks`` consecutive blocks; the
exponents' standard error is the standard deviation of the block means over sqrt(blocks)
(batch means: blocks much longer than the correlation time are nearly independent).

The per-period Jacobians come from the FMU's own derivatives when it reports them (one run,
the variational equations alongside) or, as the fallback, from central differences by
restarts from perturbed states at each point of the orbit (4 more runs per period).

Checks: lambda_1 + lambda_2 = (1/N) sum log |det J_k|, which for this oscillator is
-nu + 2 log r x (impacts per period) (det J = r^2 e^{-nu} across an impact, e^{-nu} in
free flight); for a periodic orbit the exponents are log |multipliers| / M.
"""
from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from ...errors import HarnessInputError
from .sampling import check_count, check_theta
from ...fmu.simulator import Simulator, has_derivatives, tracking_derivatives

__all__ = ["LyapunovResult", "qr_logs", "lyapunov_from_jacobians", "orbit_jacobians", "lyapunov_exponents",
           "lyapunov_continued", "DEFAULT_BLOCKS", "FD_STEP"]

#: Blocks of the batch-means uncertainty.
DEFAULT_BLOCKS = 10
#: Central-difference step of the fallback, relative to the scale (1, 2 pi) of (u, v):
#: below the distance to grazing of most orbit points, above the FMU's ~1e-11 error.
FD_STEP = 1e-6
#: log of a vanishing stretch (sticking on the rigid wall makes J singular): finite, so
#: that means stay defined; far below any physical exponent.
LOG_FLOOR = math.log(1e-300)


@dataclass(frozen=True)
class LyapunovResult:
    """Lyapunov exponents of the stroboscopic map.

    Attributes
    ----------
    exponents : ndarray, shape (2,)
        lambda_1 >= lambda_2, per forcing period (natural log).
    uncertainty : ndarray, shape (2,)
        Standard errors from the block means (inf with fewer than 2 blocks).
    periods : int
        Jacobians (periods) averaged.
    blocks : int
        Blocks of the uncertainty.
    method : str
        "exact" (the FMU's derivatives), "fd" (differences) or "given" (Jacobians passed in).
    impacts : int
        Wall entries during the averaged periods (-1: not known); lambda_1 + lambda_2 =
        -nu + 2 log(r) impacts / periods for this oscillator.
    """

    exponents: np.ndarray
    uncertainty: np.ndarray
    periods: int
    blocks: int
    method: str
    impacts: int = -1

    @property
    def largest(self) -> float:
        """lambda_1."""
        return float(self.exponents[0])

    @property
    def largest_uncertainty(self) -> float:
        """Standard error of lambda_1."""
        return float(self.uncertainty[0])

    def __str__(self) -> str:
        return ", ".join(f"{e:+.6g} +- {u:.2g}" for e, u in zip(self.exponents, self.uncertainty))


def qr_logs(jacobians: Sequence[np.ndarray] | np.ndarray) -> np.ndarray:
    """log |R_k[i, i]| of the QR iteration over the Jacobians, shape (N, 2).

    Parameters
    ----------
    jacobians : array_like, shape (N, 2, 2)
        J_1 .. J_N in the order the orbit visits them.
    """
    Js = np.asarray(jacobians, dtype=float)
    if Js.ndim != 3 or Js.shape[1:] != (2, 2):
        raise HarnessInputError("jacobians", f"expected an array of shape (N, 2, 2), got {Js.shape}")
    logs = np.empty((Js.shape[0], 2))
    Q = np.eye(2)
    for k, J in enumerate(Js):
        Q, R = np.linalg.qr(J @ Q)
        d = np.abs(np.diag(R))
        with np.errstate(divide="ignore"):
            logs[k] = np.maximum(np.log(d), LOG_FLOOR)
    return logs


def lyapunov_from_jacobians(jacobians: Sequence[np.ndarray] | np.ndarray, blocks: int = DEFAULT_BLOCKS,
                            method: str = "given", impacts: int = -1) -> LyapunovResult:
    """Exponents and their batch-means uncertainty from per-period Jacobians along an orbit.

    Parameters
    ----------
    jacobians : array_like, shape (N, 2, 2)
    blocks : int
        Number of blocks (reduced to N when there are fewer periods; with fewer than 2 the
        uncertainty is inf).
    method, impacts
        Recorded in the result.
    """
    blocks = check_count(blocks, "blocks", minimum=1)
    logs = qr_logs(jacobians)
    n = logs.shape[0]
    if n == 0:
        return LyapunovResult(np.full(2, np.nan), np.full(2, np.inf), 0, 0, method, impacts)
    exps = logs.mean(axis=0)
    b = min(blocks, n)
    if b >= 2:
        length = n // b
        means = logs[: b * length].reshape(b, length, 2).mean(axis=1)
        err = means.std(axis=0, ddof=1) / math.sqrt(b)
    else:
        err = np.full(2, np.inf)
    order = np.argsort(-exps)  # lambda_1 first (the QR order holds only asymptotically)
    return LyapunovResult(exps[order], err[order], n, b, method, impacts)


def _fd_jacobian(sim: Simulator, params: Mapping[str, Any], t0: float, x: np.ndarray, h: float) -> np.ndarray:
    from .jacobian import central_difference

    J = np.empty((2, 2))
    for j, scale in enumerate((1.0, 2.0 * math.pi)):
        J[:, j] = central_difference(sim, params, x, t0, j, h * scale)
    return J


def orbit_jacobians(sim: Simulator, params: Mapping[str, Any], t: Sequence[float], u: Sequence[float],
                    v: Sequence[float], h: float = FD_STEP) -> np.ndarray:
    """Central-difference Jacobians of the one-period map at the orbit points (t_k, u_k, v_k).

    The fallback for a simulator without derivatives: each point costs 4 one-period runs
    from restarts.  The simulator is left restarted elsewhere; the caller restarts it where
    its run goes on.
    """
    t, u, v = (np.asarray(a, dtype=float) for a in (t, u, v))
    with tracking_derivatives(sim, False) if getattr(sim, "tracking", False) else contextlib.nullcontext():
        return np.array([_fd_jacobian(sim, params, float(t[k]), np.array([u[k], v[k]]), h) for k in range(t.size)])


def period_jacobians(sim: Simulator, n_periods: int) -> tuple[np.ndarray, np.ndarray]:
    """Run ``n_periods`` periods on a simulator that tracks derivatives (started before, with
    tracking on): the per-period Jacobians (n, 2, 2) and states (n, 2) at their ends."""
    Js = np.empty((n_periods, 2, 2))
    xs = np.empty((n_periods, 2))
    t0 = sim.time
    for k in range(n_periods):
        sim.reset_derivatives()  # type: ignore[attr-defined]
        sim.advance(t0 + k + 1)  # absolute times: no drift of the section
        Js[k] = sim.derivatives()[0]  # type: ignore[attr-defined]
        u, v, _ = sim.read()
        xs[k] = u, v
    return Js, xs


def lyapunov_exponents(sim: Simulator, params: Mapping[str, Any], state0: Sequence[float], theta: float = 0.0,
                       n_transient: int = 300, n_periods: int = 2000, blocks: int = DEFAULT_BLOCKS,
                       method: str = "auto", h: float = FD_STEP) -> LyapunovResult:
    """Lyapunov exponents of the one-period map on the attractor reached from ``state0``.

    Parameters
    ----------
    sim : Simulator
    params : mapping
        FMU parameters.
    state0 : (u, v)
        Start at t = theta.
    theta : float
        Section phase (the exponents do not depend on it; the Jacobians do).
    n_transient : int
        Periods discarded first.
    n_periods : int
        Periods averaged (>= 2).
    blocks : int
        Blocks of the uncertainty.
    method : str
        "auto", "exact" (the FMU's derivatives) or "fd" (differences, 4 extra runs per period).
    h : float
        Relative difference step of "fd".

    Returns
    -------
    LyapunovResult
    """
    from .jacobian import resolve_method

    theta = check_theta(theta)
    n_transient = check_count(n_transient, "n_transient")
    n_periods = check_count(n_periods, "n_periods", minimum=2)
    method = resolve_method(sim, method)
    x0 = (float(state0[0]), float(state0[1]))
    if method == "exact":
        with tracking_derivatives(sim, True):
            sim.start(params, theta, x0)
            sim.advance(theta + n_transient)
            n0 = sim.read()[2]
            Js, _ = period_jacobians(sim, n_periods)
            impacts = sim.read()[2] - n0
        return lyapunov_from_jacobians(Js, blocks, "exact", impacts)
    with tracking_derivatives(sim, False) if getattr(sim, "tracking", False) else contextlib.nullcontext():
        sim.start(params, theta, x0)
        t = theta + n_transient + np.arange(n_periods, dtype=float)
        xs = np.empty((n_periods, 2))
        n0 = 0
        for k in range(n_periods):
            sim.advance(float(t[k]))
            u, v, n = sim.read()
            xs[k] = u, v
            n0 = n if k == 0 else n0
        sim.advance(float(t[-1]) + 1.0)  # the last Jacobian's period, for the impact count
        impacts = sim.read()[2] - n0
        Js = orbit_jacobians(sim, params, t, xs[:, 0], xs[:, 1], h)
    return lyapunov_from_jacobians(Js, blocks, "fd", impacts)


def lyapunov_continued(sim: Simulator, params: Mapping[str, Any], n_periods: int, exact: bool,
                       blocks: int = DEFAULT_BLOCKS) -> LyapunovResult:
    """Lyapunov exponents over the next ``n_periods`` periods from where ``sim`` stands (a
    section time); the run goes on from their end, so a continuation carries that state.

    ``exact``: ``sim`` was started with derivatives tracked.  Otherwise differences: the orbit
    first, then the Jacobians at its points by restarts, then a restart at its end (equivalent:
    the state at a section time fixes the future).  ``params`` are those in force now.
    """
    n0 = sim.read()[2]
    if exact:
        Js, _ = period_jacobians(sim, n_periods)
        return lyapunov_from_jacobians(Js, blocks, "exact", sim.read()[2] - n0)
    from .sampling import sample_periods

    t0 = sim.time
    u0, v0, _ = sim.read()
    r = sample_periods(sim, 0, n_periods)
    t = np.concatenate(([t0], r.t[:-1]))
    Js = orbit_jacobians(sim, params, t, np.concatenate(([u0], r.u[:-1])), np.concatenate(([v0], r.v[:-1])))
    sim.start(params, float(r.t[-1]), r.final_state)
    return lyapunov_from_jacobians(Js, blocks, "fd", int(r.impacts.sum()))
