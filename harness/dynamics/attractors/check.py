"""An attractor found by sampling, confirmed by Newton shooting on the FMU.

A basin scan names an attractor from its stroboscopic samples (:mod:`.basins`).  Samples that
repeat to the tolerance could still be a slow passage; Newton's method on the FMU's own
period-M map (:func:`mapcheck.orbits.solve_periodic_orbit`, with the FMU's exact derivatives
when it reports them) from the sampled point settles it: a converged fixed point of F^M, its
wall entries per step, and its multipliers (inside the unit circle: attracting).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from mapcheck.orbits import solve_periodic_orbit

from ...errors import FmuRejectedInput
from ...fmu.simulator import Simulator
from .identity import hausdorff


@dataclass(frozen=True)
class ShotOrbit:
    """Newton's verdict on a sampled attractor.

    Attributes
    ----------
    converged : bool
        F^M(z) = z to ``tol`` (relative to the orbit's scale).
    residual : float
        max |F^M(z) - z| at the last iterate.
    multiplier : float
        Largest |eigenvalue| of D(F^M) at the orbit (< 1: attracting); NaN when not converged.
    impacts : int
        Wall entries over the orbit's period (-1 when not converged).
    distance : float
        Largest distance (max norm) of the shot orbit's points from the sampled ones.
    """

    converged: bool
    residual: float
    multiplier: float
    impacts: int
    distance: float

    @property
    def confirmed(self) -> bool:
        """Converged, attracting, and where the samples said."""
        return bool(self.converged and self.multiplier < 1.0)


def shoot_attractor(sim: Simulator, params: Mapping[str, Any], theta: float, points: np.ndarray,
                    tol: float = 1e-10) -> ShotOrbit:
    """Newton shooting of the period-M orbit through ``points`` (M sampled points in orbit order).

    Parameters
    ----------
    sim : Simulator
        Restarted for every map evaluation.
    params : mapping
        FMU parameters.
    theta : float
        Section phase of the points.
    points : numpy.ndarray, shape (M, 2)
        The attractor's stroboscopic points, consecutive in time.
    tol : float
        Residual target relative to the orbit's scale max(1, |u|, |v|).
    """
    pts = np.asarray(points, dtype=float)
    M = len(pts)
    run = {k: v for k, v in params.items() if k not in ("u0", "v0")}
    exact = hasattr(sim, "track_derivatives") and getattr(sim, "derivatives_available", False)
    if hasattr(sim, "track_derivatives"):
        sim.track_derivatives(exact)

    def step(u: float, v: float) -> tuple[float, float, int]:
        sim.start(run, theta, (u, v))
        sim.advance(theta + 1.0)
        return sim.read()

    def dstep(u: float, v: float) -> tuple[float, float, int, np.ndarray]:
        u1, v1, n = step(u, v)
        return u1, v1, n, sim.derivatives()[0]  # type: ignore[attr-defined]

    scale = np.full(2, max(1.0, float(np.max(np.abs(pts)))))
    try:
        orb = solve_periodic_orbit(step, pts[0], M, tol=tol, scale=scale, rel_h=1e-7,
                                   dstep=dstep if exact else None)
    except FmuRejectedInput:
        return ShotOrbit(False, float("inf"), float("nan"), -1, float("inf"))
    finally:
        if hasattr(sim, "track_derivatives"):
            sim.track_derivatives(False)
    if not orb.converged:
        return ShotOrbit(False, float(orb.residual), float("nan"), -1, float("inf"))
    return ShotOrbit(True, float(orb.residual), float(np.max(np.abs(orb.multipliers))), int(orb.contacts.sum()),
                     hausdorff(orb.z, pts))
