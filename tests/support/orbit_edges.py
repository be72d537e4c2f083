"""Window edges of any periodic orbit (period M, k contacts per M periods) on the exact flow:
the generic counterpart of :mod:`tests.support.edges` (maximal orbits), for the long-period,
many-impact attractors that a global search finds.

An edge reported at sigma_e with kind fold, flip or graze is confirmed when, ``margin`` inside
it, the exact flow has a stable period-M orbit with k contacts continued from the window's seed,
and ``margin`` beyond it:

- flip: that orbit still exists and its dominant multiplier is real and below -1;
- fold: Newton from it finds no stable period-M orbit with k contacts within 1e-2 of it;
- graze: no such orbit with k contacts either: the contact count has changed (or the orbit is
  gone).
"""
from __future__ import annotations

import math

import numpy as np

from mapcheck.orbits import PeriodicOrbit

from .edges import ExactFlow, dominant


def _good(flow: ExactFlow, sigma: float, orb: PeriodicOrbit, M: int, k: int) -> bool:
    if not (orb.converged and int(np.sum(orb.contacts)) == k):
        return False
    return float(np.max(np.abs(flow.multipliers(sigma, orb.z[0], M)))) < 1.0


def continue_generic(flow: ExactFlow, M: int, k: int, z0, s_from: float, s_to: float,
                     steps: int = 3, min_fraction: float = 1e-4) -> PeriodicOrbit:
    """March the stable period-M orbit with k contacts from s_from (through z0) to s_to (secant
    predictor, the step halved when the orbit is not found); AssertionError if it is lost."""
    orb = flow.orbit(s_from, M, z0)
    assert _good(flow, s_from, orb, M, k), f"no stable {M}/{k} orbit of the exact flow at sigma = {s_from}"
    z, s, ds, prev = np.asarray(orb.z[0]), s_from, (s_to - s_from) / steps, None
    while s != s_to:
        sk = s_to if abs(s_to - s) <= abs(ds) else s + ds
        guess = z if prev is None else z + (z - prev[1]) * (sk - s) / (s - prev[0])
        o = flow.orbit(sk, M, guess)
        if not (o.converged and int(np.sum(o.contacts)) == k and np.max(np.abs(o.z[0] - z)) < 0.2):
            ds /= 2.0
            assert abs(ds) > min_fraction * abs(s_to - s_from), (
                f"{M}/{k} orbit of the exact flow lost at sigma = {sk} on the way to {s_to}")
            continue
        prev, s, z, orb = (s, z), sk, np.asarray(o.z[0]), o
    return orb


def confirm_edge(flow: ExactFlow, M: int, k: int, seed_sigma: float, seed_state, edge: float, kind: str,
                 margin: float) -> str:
    """'' when the exact flow confirms the edge (module docstring), else what it found."""
    out = math.copysign(1.0, edge - seed_sigma)
    s_in, s_out = edge - out * margin, edge + out * margin
    inside = continue_generic(flow, M, k, seed_state, seed_sigma, s_in)
    if not _good(flow, s_in, inside, M, k):
        return f"{M}/{k} not a stable orbit at {s_in}"
    beyond = flow.orbit(s_out, M, inside.z[0])
    near = beyond.converged and hausdorff_ok(beyond, inside)
    if kind == "flip":
        if not near:
            return f"{M}/{k}: orbit lost beyond the flip at {s_out}"
        mu = dominant(flow.multipliers(s_out, beyond.z[0], M))
        return "" if abs(mu.imag) < 1e-9 and mu.real < -1.0 else f"{M}/{k}: multiplier {mu} at {s_out}"
    if kind in ("fold", "graze"):
        still = near and int(np.sum(beyond.contacts)) == k and _good(flow, s_out, beyond, M, k)
        return f"{M}/{k}: still a stable orbit at {s_out} beyond the {kind}" if still else ""
    return f"kind {kind} not checked"


def hausdorff_ok(a: PeriodicOrbit, b: PeriodicOrbit, tol: float = 1e-2) -> bool:
    za, zb = np.asarray(a.z), np.asarray(b.z)
    d = np.max(np.abs(za[:, None, :] - zb[None, :, :]), axis=2)
    return float(max(d.min(axis=1).max(), d.min(axis=0).max())) <= tol
