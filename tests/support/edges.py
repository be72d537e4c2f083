"""Window edges of periodic orbits on the exact closed-form flow: the independent truth that the
harness's edges (Newton shooting on the FMU) are checked against.

Only mapcheck is used: :class:`mapcheck.exact.ExactOscillator` (the exact piecewise-linear
solution with its wall events) and :func:`mapcheck.orbits.solve_periodic_orbit` (Newton with
central differences on the closed form's M-period map).  A window edge reported by the harness as
a bracket (good, bad) is checked on each side: just inside, the exact flow has a stable maximal
period-M orbit (one impacting step per period, one contact in it) continued from the window's
interior; just outside, it has not, and the reason is the reported kind:

- flip: the dominant multiplier is real and goes through -1 (inside in (-1, -0.99), outside
  below -1, the orbit otherwise unchanged: converged, maximal);
- graze: the largest u of the orbit's non-impacting steps rises to the wall (u = 0), so the
  contact count changes across the edge; its root, extrapolated from two points inside, lies in
  the bracket.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.optimize import brentq

from mapcheck.exact import ExactOscillator
from mapcheck.orbits import PeriodicOrbit, solve_periodic_orbit

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
        from mapcheck.orbits import _jacobian

        h, step = 1e-5 * NEWTON["scale"], self.step_of(sigma)
        z = np.asarray(z0, dtype=float)
        J1, J2 = _jacobian(step, z, M, h), _jacobian(step, z, M, 2.0 * h)
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


def good(orb: PeriodicOrbit) -> bool:
    """A stable maximal orbit: what belongs to a window."""
    return orb.converged and orb.maximal and orb.stable


def after_impact(orb: PeriodicOrbit) -> np.ndarray:
    """The point right after the impacting step: the same point of the orbit at every sigma."""
    return orb.z[(int(np.argmax(orb.contacts > 0)) + 1) % orb.z.shape[0]]


def continue_orbit(flow: ExactFlow, M: int, orb: PeriodicOrbit, s_from: float, s_to: float,
                   steps: int = 4, min_fraction: float = 1e-4) -> PeriodicOrbit:
    """March the stable maximal orbit from s_from to s_to (secant predictor, step halved when the
    orbit is not found) and return it at s_to.  Raises AssertionError if it is lost on the way:
    the exact flow's window then ends before s_to."""
    z, s, ds, prev = after_impact(orb), s_from, (s_to - s_from) / steps, None
    while s != s_to:
        sk = s_to if abs(s_to - s) <= abs(ds) else s + ds
        guess = z if prev is None else z + (z - prev[1]) * (sk - s) / (s - prev[0])
        o = flow.orbit(sk, M, guess)
        if not good(o):
            ds /= 2.0
            assert abs(ds) > min_fraction * abs(s_to - s_from), (
                f"period-{M} orbit of the exact flow lost at sigma = {sk} on the way to {s_to}")
            continue
        prev, s, z, orb = (s, z), sk, after_impact(o), o
    return orb


@dataclass(frozen=True)
class EdgeSides:
    """The exact flow on both sides of a reported edge."""

    s_in: float
    s_out: float
    inside: PeriodicOrbit
    outside: PeriodicOrbit
    #: graze only: the root of the near-grazing step's max u, extrapolated from inside
    graze_root: float = math.nan
    #: graze only: contacts of the inside orbit's point iterated M periods at s_out
    contacts_out: int = -1


def dominant(mult: np.ndarray) -> complex:
    return complex(mult[int(np.argmax(np.abs(mult)))])


def edge_sides(flow: ExactFlow, M: int, seed: PeriodicOrbit, s_seed: float, kind: str, good_s: float,
               bad_s: float, margin: float) -> EdgeSides:
    """Continue the seed orbit to ``margin`` inside the bracket (good_s, bad_s) and solve at
    ``margin`` beyond it; for a graze also the near-grazing step's max u at two inside points and
    the contacts at s_out from the inside orbit."""
    out = math.copysign(1.0, bad_s - good_s)
    s_in, s_out = good_s - out * margin, bad_s + out * margin
    inside = continue_orbit(flow, M, seed, s_seed, s_in)
    outside = flow.orbit(s_out, M, after_impact(inside))
    if kind != "graze":
        return EdgeSides(s_in, s_out, inside, outside)
    # u_max(sigma) of the step that comes closest to the wall without contact: smooth inside the
    # window, zero at the graze; linear extrapolation from s_in and a point 2 brackets further in
    s_in2 = s_in - out * 2.0 * abs(bad_s - good_s)
    inside2 = continue_orbit(flow, M, inside, s_in, s_in2, steps=1)
    free = inside.contacts == 0
    u1 = flow.max_u_per_step(s_in, inside.z[0], M)[free].max()
    u2 = flow.max_u_per_step(s_in2, inside2.z[0], M)[inside2.contacts == 0].max()
    root = s_in + (s_in - s_in2) * (-u1) / (u1 - u2)
    step = flow.step_of(s_out)
    z, n = inside.z[0], 0
    for _ in range(M):
        *z, c = step(*z)
        n += c
    return EdgeSides(s_in, s_out, inside, outside, root, n)
