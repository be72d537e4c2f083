"""Orbit classification from stroboscopic samples.

A sampled orbit x_0 .. x_{N-1} (x = (u, v) at t = n + theta) has period M when
x_{k+M} = x_k for every k (within a tolerance) and the impact counts per period repeat
with period M too; M is the smallest such shift.  Period 0 means "no period found"; it
covers chaotic orbits, quasi-periodic ones and orbits that have not converged in the
transient, which :func:`classify_dynamics` tells apart (the sweeps' ``dynamics`` variable:
-1 unclassified, 0 not converged, 1 periodic, 2 quasi-periodic, 3 chaotic).

The period-adding windows of the paper's Figure 9 are maximal orbits: period M with one
impact per M periods, M = 1, 2, 3 as sigma decreases.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mapcheck.compare import equal_runs

NOT_PERIODIC = 0


@dataclass(frozen=True)
class OrbitClass:
    """Result of :func:`classify_orbit`.

    Attributes
    ----------
    period : int
        Smallest period M >= 1 in forcing periods, or 0 (:data:`NOT_PERIODIC`).
    impacts : int
        Wall entries in one orbit period (over M forcing periods); -1 when not periodic.
    residual : float
        max_k ||x_{k+M} - x_k||_inf for the period found (for M = 0: for the best M tried).
    """

    period: int
    impacts: int
    residual: float

    @property
    def periodic(self) -> bool:
        """True unless the orbit is "not periodic"."""
        return self.period != NOT_PERIODIC

    @property
    def label(self) -> str:
        """Short human-readable label, e.g. ``"P3, 1 impact"``."""
        if not self.periodic:
            return "not periodic"
        s = "" if self.impacts == 1 else "s"
        return f"P{self.period}, {self.impacts} impact{s}"


def classify_orbit(
    u: np.ndarray,
    v: np.ndarray,
    impacts: np.ndarray,
    tol: float = 1e-5,
    max_period: int | None = None,
) -> OrbitClass:
    """Classify a sampled orbit by its period and impacts per period.

    Parameters
    ----------
    u, v : array_like, shape (N,)
        Stroboscopic samples.
    impacts : array_like of int, shape (N,)
        Wall entries in the period ending at each sample.
    tol : float
        Periodicity tolerance, relative to ``1 + amplitude`` of the orbit (the amplitude is
        the largest peak-to-peak range of u and v), so it works for orbits of any size.
    max_period : int, optional
        Largest period tried; default N // 2 (each shift is checked on at least N/2 pairs).

    Returns
    -------
    OrbitClass
    """
    u = np.asarray(u, dtype=float)
    v = np.asarray(v, dtype=float)
    imp = np.asarray(impacts)
    n = u.size
    if not (v.size == n and imp.size == n):
        raise ValueError("u, v and impacts must have the same length")
    if not np.all(np.isfinite(u)) or not np.all(np.isfinite(v)) or n < 2:
        return OrbitClass(NOT_PERIODIC, -1, float("inf"))
    if max_period is None:
        max_period = n // 2
    max_period = max(1, min(max_period, n - 1))
    amplitude = max(np.ptp(u), np.ptp(v))
    threshold = tol * (1.0 + amplitude)
    best = float("inf")
    for m in range(1, max_period + 1):
        residual = float(max(np.max(np.abs(u[m:] - u[:-m])), np.max(np.abs(v[m:] - v[:-m]))))
        best = min(best, residual)
        if residual <= threshold and np.array_equal(imp[m:], imp[:-m]):
            # impacts over one orbit period: use the last full period (most converged)
            return OrbitClass(m, int(imp[n - m :].sum()), residual)
    return OrbitClass(NOT_PERIODIC, -1, best)


def still_settling(u: np.ndarray, v: np.ndarray, period: int, tol: float = 1e-5) -> bool:
    """True when an orbit classified with ``period`` is still converging to a shorter one.

    Near a flip bifurcation a period-M orbit is approached with a multiplier close to -1:
    the samples alternate with a slowly shrinking amplitude and look like period 2M.  For
    each proper divisor d of ``period`` the d-shift differences |x_{k+d} - x_k| are
    compared between the first and the last quarter of the samples; a decay by more than
    10 % (from above the tolerance: a genuine period-2M orbit keeps its differences constant
    up to integration noise far below it) means the transient is not over.
    """
    u = np.asarray(u, dtype=float)
    v = np.asarray(v, dtype=float)
    threshold = tol * (1.0 + max(np.ptp(u), np.ptp(v)))
    for d in range(1, period):
        if period % d:
            continue
        diffs = np.maximum(np.abs(u[d:] - u[:-d]), np.abs(v[d:] - v[:-d]))
        q = max(1, diffs.size // 4)
        early, late = float(diffs[:q].mean()), float(diffs[-q:].mean())
        if early > threshold and late < 0.9 * early:
            return True
    return False


def classify_samples(u: np.ndarray, v: np.ndarray, impacts: np.ndarray, tol: float = 1e-5,
                     max_period: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Classify many orbits at once: arrays ``(..., N)`` -> (period, impacts) arrays ``(...)``."""
    u = np.asarray(u)
    shape = u.shape[:-1]
    period = np.zeros(shape, dtype=np.int64)
    orbit_impacts = np.full(shape, -1, dtype=np.int64)
    for idx in np.ndindex(shape):
        c = classify_orbit(u[idx], np.asarray(v)[idx], np.asarray(impacts)[idx], tol, max_period)
        period[idx], orbit_impacts[idx] = c.period, c.impacts
    return period, orbit_impacts


def windows(values: np.ndarray, period: np.ndarray, impacts: np.ndarray | None = None) -> list[tuple[int, float, float]]:
    """Contiguous runs of the same period along a sorted parameter axis.

    Parameters
    ----------
    values : array_like, shape (K,)
        Parameter values, sorted.
    period : array_like of int, shape (K,)
        Period at each value.
    impacts : array_like of int, optional
        When given, only runs of orbits with exactly one impact per orbit period (maximal
        orbits, as in period adding) are returned.

    Returns
    -------
    list of (period, lowest value, highest value)
        One entry per run of periodic points, in the order of ``values``.
    """
    values = np.asarray(values)
    period = np.asarray(period)
    keep = period > 0
    if impacts is not None:
        keep &= np.asarray(impacts) == 1
    out: list[tuple[int, float, float]] = []
    for k, j in equal_runs(keep, period):
        lo, hi = sorted((float(values[k]), float(values[j])))
        out.append((int(period[k]), lo, hi))
    return out


# ----------------------------------------------------------------------------------------
# Dynamics: periodic, quasi-periodic, chaotic, not converged (with Lyapunov exponents)
# ----------------------------------------------------------------------------------------
#: Codes of :func:`classify_dynamics` (the NetCDF variable ``dynamics``).
UNCLASSIFIED, NOT_CONVERGED, PERIODIC, QUASI_PERIODIC, CHAOTIC = -1, 0, 1, 2, 3
DYNAMICS_NAMES = {UNCLASSIFIED: "unclassified", NOT_CONVERGED: "not converged", PERIODIC: "periodic",
                  QUASI_PERIODIC: "quasi-periodic", CHAOTIC: "chaotic"}
#: An exponent is called positive / negative when it is this many standard errors from 0.
SIGMAS = 3.0
#: Largest 3-sigma band around 0 that still counts as "lambda_1 = 0" (per forcing period):
#: a wider band cannot tell a torus from slow convergence or weak chaos.
ZERO_BAND = 0.02


#: Why a point is :data:`NOT_CONVERGED` (or :data:`UNCLASSIFIED`): the sweeps' ``dynamics_reason``.
DECIDED, SETTLING_NO_EXPONENT, SETTLING_EXPONENT_NOT_NEGATIVE, ATTRACTING_NO_PERIOD, BAND_TOO_WIDE, NO_PERIOD_NO_EXPONENT = \
    0, 1, 2, 3, 4, 5
#: One word per reason (the NetCDF ``flag_meanings``).
REASON_KEYS = {DECIDED: "decided", SETTLING_NO_EXPONENT: "settling_no_exponent",
               SETTLING_EXPONENT_NOT_NEGATIVE: "settling_exponent_not_negative",
               ATTRACTING_NO_PERIOD: "attracting_no_period", BAND_TOO_WIDE: "exponent_band_too_wide",
               NO_PERIOD_NO_EXPONENT: "no_period_no_exponent"}
REASON_NAMES = {
    DECIDED: "decided",
    SETTLING_NO_EXPONENT: "period found but the samples still converge, no exponent computed",
    SETTLING_EXPONENT_NOT_NEGATIVE: "period found but the samples still converge and lambda_1 is not negative",
    ATTRACTING_NO_PERIOD: "lambda_1 < 0 but no period up to max_period: attracting orbit not reached or longer",
    BAND_TOO_WIDE: "lambda_1 = 0 within 3 standard errors, band too wide to tell a torus from slow convergence",
    NO_PERIOD_NO_EXPONENT: "no period found and no exponent computed",
}


def explain_dynamics(period: int, settling: bool, largest: float, uncertainty: float,
                     sigmas: float = SIGMAS, zero_band: float = ZERO_BAND) -> tuple[int, int]:
    """Periodic, quasi-periodic, chaotic or not (yet) converged, and why.

    The period test and the exponent are read together, so that the label never contradicts
    the numbers next to it: a detected period decides (periodic) unless the samples still
    converge; then a negative lambda_1 (point estimate) decides (periodic: the orbit is
    attracting, whichever divisor of the period it settles on).  Without a period the
    exponent decides (chaotic, quasi-periodic); :data:`NOT_CONVERGED` is left for points
    where neither does, with the reason.

    Parameters
    ----------
    period : int
        From :func:`classify_orbit` (0: not periodic within the tolerance).
    settling : bool
        From :func:`still_settling`: the samples look periodic but still converge.
    largest, uncertainty : float
        lambda_1 of the stroboscopic map and its standard error (NaN: not computed).
    sigmas, zero_band : float
        An exponent is positive (negative) beyond ``sigmas`` standard errors; zero within
        them when that band is at most ``zero_band`` wide.

    Returns
    -------
    (code, reason) : tuple of int
        ``code`` one of :data:`PERIODIC`, :data:`CHAOTIC` (no period, lambda_1 > 0 beyond
        ``sigmas`` standard errors), :data:`QUASI_PERIODIC` (no period, lambda_1 = 0 within a
        band narrower than ``zero_band``: motion on an invariant circle), :data:`NOT_CONVERGED`,
        :data:`UNCLASSIFIED` (no period, no exponent); ``reason`` a key of
        :data:`REASON_NAMES` (:data:`DECIDED` unless not converged or unclassified).
    """
    have_exponent = math.isfinite(largest) and math.isfinite(uncertainty)
    if period > 0:
        if not settling:
            return PERIODIC, DECIDED
        if not have_exponent:
            return NOT_CONVERGED, SETTLING_NO_EXPONENT
        if largest < 0:
            return PERIODIC, DECIDED
        return NOT_CONVERGED, SETTLING_EXPONENT_NOT_NEGATIVE
    if not have_exponent:
        return UNCLASSIFIED, NO_PERIOD_NO_EXPONENT
    band = sigmas * uncertainty
    if largest - band > 0:
        return CHAOTIC, DECIDED
    if largest + band < 0:
        return NOT_CONVERGED, ATTRACTING_NO_PERIOD
    if band <= zero_band:
        return QUASI_PERIODIC, DECIDED
    return NOT_CONVERGED, BAND_TOO_WIDE


def classify_dynamics(period: int, settling: bool, largest: float, uncertainty: float,
                      sigmas: float = SIGMAS, zero_band: float = ZERO_BAND) -> int:
    """The code of :func:`explain_dynamics` alone (periodic, quasi-periodic, chaotic, not
    converged or unclassified)."""
    return explain_dynamics(period, settling, largest, uncertainty, sigmas, zero_band)[0]


def dynamics_attrs() -> dict:
    """CF attributes of the sweeps' ``dynamics`` variable (codes, meanings, the rules)."""
    codes = sorted(DYNAMICS_NAMES)
    return {
        "long_name": "dynamics of the orbit", "flag_values": np.array(codes, dtype=np.int64),
        "flag_meanings": " ".join(DYNAMICS_NAMES[c].replace(" ", "_").replace("-", "_") for c in codes),
        "sigmas": SIGMAS,  # an exponent is positive / zero / negative beyond this many standard errors
        "comment": "periodic: a period found and converged, or a period found and largest Lyapunov exponent "
                   "< 0; chaotic: no period, largest exponent > 0 by more than 3 standard errors; "
                   f"quasi_periodic: no period, largest exponent 0 within 3 standard errors (band <= {ZERO_BAND}); "
                   "not_converged: neither the period nor the exponent decides (why: dynamics_reason); "
                   "unclassified: no period and no exponents (sampling.lyapunov = 0)"}


def reason_attrs() -> dict:
    """CF attributes of the sweeps' ``dynamics_reason`` variable."""
    reasons = sorted(REASON_NAMES)
    return {
        "long_name": "why dynamics is not_converged or unclassified (0: decided; -1: not computed)",
        "flag_values": np.array(reasons, dtype=np.int64),
        "flag_meanings": " ".join(REASON_KEYS[c] for c in reasons),
        "comment": "; ".join(f"{REASON_KEYS[c]}: {REASON_NAMES[c]}" for c in reasons)}
