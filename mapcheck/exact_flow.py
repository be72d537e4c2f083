"""The exact flow as a stroboscopic map, with its periodic orbits: :class:`ExactFlow` strobes
:class:`mapcheck.exact.ExactOscillator` at a phase theta and finds period-M orbits on it by Newton
shooting (:func:`mapcheck.orbits.solve_periodic_orbit`), their multipliers to ~1e-10 and the
largest u of each period -- the independent truth that window edges found on the FMU are checked
against (an edge is a flip where a multiplier crosses -1, a graze where that largest u reaches the
wall).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .exact import ExactOscillator
from .segments import brentq
from .orbits import PeriodicOrbit, solve_periodic_orbit

__all__ = ["ExactFlow", "NEWTON"]

#: Newton on the closed form's M-period map: the orbit to 1e-12 of its size (u ~ 1, v ~ 2 pi);
#: a step never moves z by more than (0.1, 0.6), so that the march stays on its branch; a good
#: orbit converges in <= 10 iterations, a lost one stops after 15 (a failure costs 40 otherwise).
NEWTON = dict(tol=1e-11, rel_h=1e-6, scale=np.array([0.1, 0.6]), max_iter=15)


@dataclass(frozen=True)
class ExactFlow:
    """The closed-form oscillator at fixed (nu, Omega, r, Gamma, wall), strobed at phase theta."""

    nu: float
    Omega: float
    r: float
    Gamma: float
    wall: str
    theta: float = 0.5

    def oscillator(self, sigma: float) -> ExactOscillator:
        return ExactOscillator(self.nu, self.Omega, sigma, r=self.r, Gamma=self.Gamma, wall=self.wall)

    def step_of(self, sigma: float) -> Callable[[float, float], tuple[float, float, int]]:
        """The one-period map at sigma: (u, v) at theta -> (u, v, contacts) at theta + 1."""
        ex, t0 = self.oscillator(sigma), self.theta
        return lambda u, v: ex.state_at(u, v, t0, t0 + 1.0)

    def orbit(self, sigma: float, M: int, z0) -> PeriodicOrbit:
        return solve_periodic_orbit(self.step_of(sigma), np.asarray(z0, dtype=float), M, **NEWTON)

    def multipliers(self, sigma: float, z0, M: int) -> np.ndarray:
        """The multipliers of the period-M orbit through ``z0`` to ~1e-10: central differences at
        h and 2h (h = 1e-5 x the Newton scale), Richardson-extrapolated.  The orbit's own ones
        (h = 1e-6 x scale) carry ~1e-8 of rounding, too much to tell which side of -1 a multiplier
        is 1e-8 from a flip (slope d mu / d sigma ~ 1)."""
        from .orbits import _jacobian, _orbit

        h, step = 1e-5 * NEWTON["scale"], self.step_of(sigma)
        z = np.asarray(z0, dtype=float)
        base = _orbit(step, z, M)[1]
        J1, J2 = _jacobian(step, z, M, h, base), _jacobian(step, z, M, 2.0 * h, base)
        return np.linalg.eigvals(J1 + (J1 - J2) / 3.0)

    def settle(self, sigma: float, M: int, n: int = 100) -> PeriodicOrbit:
        """The period-M orbit the flow settles on from the wall-free orbit p(theta) (4): n periods
        of the exact map, then Newton."""
        w = 2.0 * math.pi * self.theta
        z = np.array([(1.0 + sigma) * math.cos(w) - 1.0, -2.0 * math.pi * (1.0 + sigma) * math.sin(w)])
        step = self.step_of(sigma)
        for _ in range(n):
            *z, _c = step(*z)
        return self.orbit(sigma, M, z)

    def max_u_per_step(self, sigma: float, z0, M: int, points: int = 400) -> np.ndarray:
        """The largest u during each of the M periods from z0: a grid of ``points`` per period
        locates it, brentq on v = 0 (the exact state from the period's start) refines it."""
        ex, out = self.oscillator(sigma), np.empty(M)
        z = np.asarray(z0, dtype=float)
        for k in range(M):
            t0 = self.theta + k
            t = t0 + np.linspace(0.0, 1.0, points + 1)
            s, _ = ex.dense(z[0], z[1], t, t0=t0)
            i = int(np.argmax(s[:, 0]))
            out[k] = s[i, 0]
            if 0 < i < points and s[i - 1, 1] > 0.0 > s[i + 1, 1]:
                def v_at(tt: float) -> float:
                    return ex.state_at(z[0], z[1], t0, tt)[1]
                tm = brentq(v_at, t[i - 1], t[i + 1], xtol=1e-15, rtol=4 * np.finfo(float).eps)
                out[k] = ex.state_at(z[0], z[1], t0, tm)[0]
            z = s[-1]
        return out
