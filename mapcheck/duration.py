"""Impact duration at a compliant wall (section 6): exact (41) and the approximations
(42), (45), (50) with beta from (43)."""
from __future__ import annotations

import math

import numpy as np

from .coeffs import grazing_acceleration
from .exact import ExactOscillator

__all__ = ["beta", "duration_exact", "duration_42", "duration_45", "duration_50"]


def beta(v_c, kappa: float, r: float, sigma=0.0, Omega: float = 0.0):
    """beta = r v_c kappa / |A~|, equation (43), A~ = (1 + sigma) A + sigma Omega^2.

    beta << 1: low-velocity (soft) impacts (44); beta >> 1: high-velocity (hard) (49).
    """
    At = grazing_acceleration(sigma, Omega, "tilde")
    return r * np.asarray(v_c, dtype=float) * kappa / np.abs(At)


def duration_42(v_c, kappa: float, r: float, sigma=0.0, Omega: float = 0.0):
    """Delta t = (1/kappa) arccos[(1 - beta^2)/(1 + beta^2)] = (2/kappa) arctan(beta), (42).

    From u'' = A~ - kappa^2 u (damping and the time dependence of the forcing neglected);
    error O(1/kappa^2).  The arctan form is used (same value, better conditioned).
    """
    return 2.0 / kappa * np.arctan(beta(v_c, kappa, r, sigma, Omega))


def duration_45(v_c, r: float, sigma=0.0, Omega: float = 0.0):
    """Low-velocity limit (45): Delta t = 2 r v_c / |A~| = 2 beta / kappa (independent of kappa)."""
    At = grazing_acceleration(sigma, Omega, "tilde")
    return 2.0 * r * np.asarray(v_c, dtype=float) / np.abs(At)


def duration_50(kappa: float):
    """High-velocity limit (50): Delta t = pi / kappa (independent of v_c)."""
    return math.pi / kappa


def duration_exact(nu: float, Omega: float, sigma: float, Gamma: float, r: float, v_c, t_c=0.0):
    """Exact impact duration, (41): u(t_c + Delta t) = 0 for the compliant-wall ODE (40)
    started at u(t_c) = 0, u'(t_c) = r v_c (footnote 2), solved in closed form.

    Parameters
    ----------
    nu, Omega, sigma : float
        Oscillator and forcing (5).
    Gamma : float
        kappa^2 / Omega^2.
    r : float
    v_c : float or array_like
        Collision velocity (> 0).
    t_c : float or array_like
        Collision time (the paper's approximations take the acceleration at t = n, so
        t_c = 0 compares like with like).

    Returns
    -------
    ndarray
        Delta t (NaN if the mass does not leave the wall within one period).
    """
    osc = ExactOscillator(nu, Omega, sigma, r=r, Gamma=Gamma, wall="compliant")
    v_c, t_c = np.broadcast_arrays(np.asarray(v_c, dtype=float), np.asarray(t_c, dtype=float))
    out = np.full(v_c.shape, np.nan)
    for idx in np.ndindex(v_c.shape):
        t0 = float(t_c[idx])
        # (0, r v_c) with v > 0 starts inside the wall (no second velocity jump)
        for t, kind in osc.crossings(0.0, r * float(v_c[idx]), t0, t0 + 1.0):
            if kind == "exit":
                out[idx] = t - t0
                break
    return out
