"""The saddle-node of single-impact period-M orbits of a rigid-wall oscillator at grazing, in
closed form: the fold where such an orbit is born, its impact time and velocity.  The fold touches
sigma = 0 where the damped natural frequency is a rational multiple of the forcing's
(omega_d M = n pi: resonant grazing), quadratically tangent to the grazing line."""
from __future__ import annotations

import math

import numpy as np

from .linear import propagator

__all__ = ["fold"]


def fold(nu: float, r: float, Omega: float, M: int = 1) -> tuple[float, float, float]:
    """(sigma_SN, impact time t_i, impact velocity v) of the single-impact period-M orbit's fold
    on a rigid wall with restitution ``r``."""
    P = propagator(float(M), nu, Omega)
    B = np.eye(2) - P
    q = np.array([r * P[0, 1], 1 + r * P[1, 1]])
    K0 = q[1] * B[0, 0] - q[0] * B[1, 0]
    K2 = 2 * math.pi * (q[1] * B[0, 1] - q[0] * B[1, 1])
    A = abs(K0) / math.hypot(K0, K2)
    t = ((math.atan2(K2, -K0) + (math.pi if K0 > 0 else 0.0)) / (2 * math.pi)) % 1.0
    t = t - 1.0 if t > 0.5 else t
    w = np.array([1 - A * math.cos(2 * math.pi * t), 2 * math.pi * A * math.sin(2 * math.pi * t)])
    return A - 1.0, t, float(-(B @ w) @ q / (q @ q))
