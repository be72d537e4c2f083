"""The FMU's one-period map at a section phase, in coordinates relative to the wall-free orbit
(the map that :mod:`.shooting` solves for periodic orbits and window edges).

The map is the FMU's one-period map at the section phase ``theta`` (default 1/2: half a
period away from the impacts near t = n, so every sample is out of contact).  It is
written in coordinates relative to the wall-free orbit p(t) of (4), w = z - p(theta),
a translation (same fixed points and multipliers) that makes continuation in sigma work:
a change of sigma moves p(theta) by O(dsigma) while the impacting orbit lives within
O(1e-3) of grazing, so continuing z itself would lose the impact on the first step.
"""
from __future__ import annotations

import math
from typing import Any, Callable, Mapping

import numpy as np

from .jacobian import resolve_method
from ...fmu.simulator import Simulator

__all__ = ["StroboscopicMap"]

TWO_PI = 2.0 * math.pi


class StroboscopicMap:
    """The FMU's one-period map at phase ``theta``, in coordinates w = z - p(theta).

    Parameters
    ----------
    sim : Simulator
        Restarted for every evaluation (``start`` at t0 = theta).
    params : mapping
        FMU parameters (sigma is set per call of :meth:`at`).
    theta : float
        Section phase; keep it away from the impacts (1/2).
    derivatives : str
        "auto" (the FMU's exact derivatives when it reports them), "exact" or "fd" (central
        differences, the fallback and cross-check).
    """

    def __init__(self, sim: Simulator, params: Mapping[str, Any], theta: float = 0.5,
                 derivatives: str = "auto") -> None:
        self.sim = sim
        self.params = {k: v for k, v in params.items() if k not in ("u0", "v0")}
        self.theta = float(theta)
        self.evaluations = 0
        self.derivatives = resolve_method(sim, derivatives, "derivatives")
        if hasattr(sim, "track_derivatives"):
            # variational equations only where they are used
            sim.track_derivatives(self.derivatives == "exact")

    def offset(self, sigma: float) -> np.ndarray:
        """p(theta) of (4) at this sigma."""
        th = TWO_PI * self.theta
        return np.array([(1.0 + sigma) * math.cos(th) - 1.0, -TWO_PI * (1.0 + sigma) * math.sin(th)])

    def at(self, sigma: float) -> Callable[[float, float], tuple[float, float, int]]:
        """The map at ``sigma`` as ``step(wu, wv) -> (wu1, wv1, wall entries)``."""
        params = {**self.params, "sigma": float(sigma)}
        off = self.offset(sigma)
        t0 = self.theta

        def step(wu: float, wv: float) -> tuple[float, float, int]:
            self.sim.start(params, t0, (wu + off[0], wv + off[1]))
            self.sim.advance(t0 + 1.0)
            u, v, n = self.sim.read()
            self.evaluations += 1
            return u - off[0], v - off[1], n

        return step

    def at_with_jacobian(self, sigma: float) -> Callable[[float, float], tuple[float, float, int, np.ndarray]] | None:
        """The map at ``sigma`` with its exact Jacobian, ``dstep(wu, wv) -> (wu1, wv1, n, J)``
        (J in w coordinates = J in z: a translation), or None with finite differences."""
        if self.derivatives != "exact":
            return None
        step = self.at(sigma)

        def dstep(wu: float, wv: float) -> tuple[float, float, int, np.ndarray]:
            u, v, n = step(wu, wv)
            return u, v, n, self.sim.derivatives()[0]  # type: ignore[attr-defined]

        return dstep

    def iterate(self, sigma: float, w: np.ndarray, n: int) -> tuple[np.ndarray, int]:
        """n periods in one run (no restarts) from w; returns (w_n, wall entries)."""
        off = self.offset(sigma)
        self.sim.start({**self.params, "sigma": float(sigma)}, self.theta, tuple(np.asarray(w) + off))
        self.sim.advance(self.theta + n)
        u, v, k = self.sim.read()
        return np.array([u, v]) - off, k
