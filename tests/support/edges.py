"""Window edges of periodic orbits on the exact closed-form flow: the independent truth that the
harness's edges (Newton shooting on the FMU) are checked against.

Only mapcheck is used: :class:`mapcheck.exact_flow.ExactFlow` (the exact piecewise-linear
solution with its wall events, :class:`mapcheck.exact.ExactOscillator`, strobed, with Newton on
its M-period map by :func:`mapcheck.orbits.solve_periodic_orbit`).  A window edge reported by the harness as
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

import numpy as np

from mapcheck.exact_flow import NEWTON, ExactFlow
from mapcheck.orbits import PeriodicOrbit

__all__ = ["NEWTON", "ExactFlow", "EdgeSides", "continue_orbit", "dominant", "edge_sides", "good", "after_impact"]


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
