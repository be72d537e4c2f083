"""Linear part of the oscillator: eigenvalues, propagator, (alpha, gamma) and its inverse.

References are to Molenaar, de Weger & van de Water, Nonlinearity 14 (2001) 301
("the paper") and to the verified account docs/theory.md (section 2).

The free oscillator (3), written for the deviation w = u - p from the periodic
solution p(t) (4), is w'' + nu w' + k2 w = 0 with k2 = Omega^2.  Inside a
compliant wall (40) the same form holds with k2 = Omega^2 + kappa^2, so every
function here takes the stiffness ``k2`` (not Omega) where that is useful.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "eigenvalues",
    "propagator",
    "propagator_k2",
    "propagator_minus_identity",
    "alpha_gamma",
    "AlphaGammaInverse",
    "invert_alpha_gamma",
    "underdamped_branches",
]

# Below this value of |d| t^2 (d = nu^2/4 - k2) a Taylor series in d t^2 replaces the
# cosh/sinh (cos/sin) form, which is 0/0 at critical damping (4 terms: < 1e-28 relative).
_SERIES_D = 1e-6
# P(t) - I: matrix series where rate*t <= 0.05 (terms <= 0.05^k/k!: 12 terms reach 1e-24
# relative); beyond, P - I from the closed form has relative error <= eps/(rate t) ~ 1e-14.
_SERIES_RATE_T = 0.05
_N_SERIES_RATE_T = 13


def eigenvalues(nu: float, Omega: float) -> tuple[complex, complex]:
    """Roots s1, s2 of s^2 + nu s + Omega^2 = 0 (below (7)).

    Returns
    -------
    s1, s2 : complex
        ``s_{1,2} = (-nu +- sqrt(nu^2 - 4 Omega^2))/2``; complex conjugates when
        the oscillator is underdamped (nu < 2 Omega).
    """
    disc = np.sqrt(complex(nu * nu - 4.0 * Omega * Omega))
    return (-nu + disc) / 2.0, (-nu - disc) / 2.0


def _damped_c_and_s(t: np.ndarray, nu: float, k2: float) -> tuple[np.ndarray, np.ndarray]:
    """e^{-nu t/2} C and e^{-nu t/2} S, C = cosh(sqrt(d) t), S = sinh(sqrt(d) t)/sqrt(d).

    d = nu^2/4 - k2 of any sign (docs/theory.md section 2): cosh/sinh for d > 0, cos/sin for
    d < 0 (both accurate to a few ulp, also for small sqrt(|d|) t); a short Taylor series
    in d t^2 only where |d| t^2 <= 1e-6 (there sqrt(d) may vanish: critical damping); and
    for sqrt(d) t > 30 the exponentials are combined, (e^{(q-b)t} +- e^{-(q+b)t})/2, so
    that nothing overflows at large t.  ``t`` is a 1-D float array; every value is computed
    elementwise, so a point's result does not depend on the other points passed with it.
    """
    b = 0.5 * nu
    d = b * b - k2
    E = np.exp(-b * t)
    if d > 0:
        q = math.sqrt(d)
        qt = q * t
        far = np.abs(qt) > 30.0
        if far.any():
            with np.errstate(over="ignore", invalid="ignore"):
                eC = E * np.cosh(qt)
                eS = E * np.sinh(qt) / q
            tf = t[far]
            ep, em = np.exp((q - b) * tf), np.exp(-(q + b) * tf)
            eC[far] = 0.5 * (ep + em)
            eS[far] = 0.5 * (ep - em) / q
        else:
            eC = E * np.cosh(qt)
            eS = E * np.sinh(qt) / q
    elif d < 0:
        w = math.sqrt(-d)
        wt = w * t
        eC = E * np.cos(wt)
        eS = E * np.sin(wt) / w
    else:
        return E, E * t
    z = d * t * t
    tiny = np.abs(z) <= _SERIES_D
    if tiny.any():
        zs = z[tiny]
        # C = 1 + z/2 + z^2/24 + z^3/720, S/t = 1 + z/6 + z^2/120 + z^3/5040: error < z^4/8!
        c = 1.0 + zs * (1.0 / 2 + zs * (1.0 / 24 + zs / 720))
        sv = 1.0 + zs * (1.0 / 6 + zs * (1.0 / 120 + zs / 5040))
        Et = E[tiny]
        eC[tiny] = Et * c
        eS[tiny] = Et * sv * t[tiny]
    return eC, eS


def propagator_k2(t, nu: float, k2: float) -> np.ndarray:
    """Propagator P(t) of w'' + nu w' + k2 w = 0, valid at every damping.

    docs/theory.md section 2, equivalent to the paper's (7):
    ``P = e^{-nu t/2} [[C + nu S/2, S], [-k2 S, C - nu S/2]]`` with
    ``d = nu^2/4 - k2``, ``C = cosh(sqrt(d) t)``, ``S = sinh(sqrt(d) t)/sqrt(d)``
    (cos/sin when d < 0, a series near d t^2 = 0).  For overdamped motion at
    large t the exponentials are combined so that nothing overflows.

    Parameters
    ----------
    t : float or array_like
        Elapsed time(s).
    nu : float
        Damping nu.
    k2 : float
        Stiffness (Omega^2 for the free oscillator, Omega^2 + kappa^2 in the wall).

    Returns
    -------
    ndarray, shape ``np.shape(t) + (2, 2)``
        ``P(t)`` mapping (w, w') at time 0 to (w, w') at time t.
    """
    t = np.asarray(t, dtype=float)
    shape = t.shape
    t = t.reshape(-1)
    b = 0.5 * nu
    eC, eS = _damped_c_and_s(t, nu, k2)
    out = np.empty(t.shape + (2, 2))
    out[:, 0, 0] = eC + b * eS
    out[:, 0, 1] = eS
    out[:, 1, 0] = -k2 * eS
    out[:, 1, 1] = eC - b * eS
    return out.reshape(shape + (2, 2))


def propagator(t, nu: float, Omega: float) -> np.ndarray:
    """The paper's free propagator P(t), equation (7); see :func:`propagator_k2`."""
    return propagator_k2(t, nu, Omega * Omega)


def propagator_minus_identity(t, nu: float, k2: float) -> np.ndarray:
    """``P(t) - I`` with small relative error also for small t.

    Needed by the exact integrator: the displacement from an anchor point over a
    short time (e.g. between chattering impacts 1e-8 apart) must not be computed
    as a difference of O(1) numbers.  For ``rate * t <= 0.05`` the matrix series
    ``sum_k M^k t^k / k!`` with ``M = [[0, 1], [-k2, -nu]]`` is summed using
    ``M^k = a_k M + b_k I`` (from ``M^2 = -nu M - k2 I``); otherwise
    ``propagator_k2(t) - I``.

    Returns
    -------
    ndarray, shape ``np.shape(t) + (2, 2)``
    """
    t = np.asarray(t, dtype=float)
    shape = t.shape
    e11, e12, e21, e22 = propagator_minus_identity_entries(t.reshape(-1), nu, k2, spectral_rate(nu, k2))
    out = np.empty(e11.shape + (2, 2))
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = e11, e12, e21, e22
    return out.reshape(shape + (2, 2))


def series_terms(x: float) -> int:
    """Number of terms of the P - I series for points with rate * |t| <= x: until the bound
    x^k / k! on the k-th term is below 1e-17 x (all 12 when x = 0)."""
    bound = x
    for k in range(1, _N_SERIES_RATE_T):
        bound *= x / (k + 1)
        if bound < 1e-17 * x:
            return k
    return _N_SERIES_RATE_T - 1


def _series_entries(ts: np.ndarray, nu: float, k2: float, n_terms: int) -> tuple[np.ndarray, np.ndarray]:
    """A(t), B(t) of P(t) - I = A M + B I: the first ``n_terms`` terms of the series."""
    if ts.size > 8:
        A = np.zeros_like(ts)
        B = np.zeros_like(ts)
        a_k, b_k = 1.0, 0.0
        fac = ts.copy()  # t^k / k!
        for k in range(1, n_terms + 1):
            A += a_k * fac
            B += b_k * fac
            a_k, b_k = -nu * a_k + b_k, -k2 * a_k
            fac = fac * ts / (k + 1)
        return A, B
    # a few points (the usual case: tau = 0 of a search's first chunk): the same sums per point
    A = np.empty_like(ts)
    B = np.empty_like(ts)
    for i, t in enumerate(ts.tolist()):
        A[i], B[i] = series_point(t, nu, k2, n_terms)
    return A, B


def series_point(t: float, nu: float, k2: float, n_terms: int) -> tuple[float, float]:
    """A(t), B(t) of :func:`_series_entries` at one point, in pure Python (the same operations)."""
    A = B = 0.0
    a_k, b_k, fac = 1.0, 0.0, t
    for k in range(1, n_terms + 1):
        A += a_k * fac
        B += b_k * fac
        a_k, b_k = -nu * a_k + b_k, -k2 * a_k
        fac = fac * t / (k + 1)
    return A, B


def propagator_minus_identity_entries(t: np.ndarray, nu: float, k2: float,
                                      rate: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The entries (E11, E12, E21, E22) of :func:`propagator_minus_identity` for a 1-D float
    array ``t``, as four arrays (no (n, 2, 2) array is built); ``rate`` = spectral_rate(nu, k2).

    The series covers the points with ``rate * |t| <= 0.05``; its number of terms is set by
    the largest of them (all points of one call share it), the closed form covers the rest.
    """
    b = 0.5 * nu
    small = rate * np.abs(t) <= _SERIES_RATE_T
    if not small.any():
        eC, eS = _damped_c_and_s(t, nu, k2)
        bS = b * eS
        return eC + bS - 1.0, eS, -k2 * eS, eC - bS - 1.0
    at = np.flatnonzero(small).tolist()
    if len(at) <= 8:
        # a few points in the series range (a search's first chunk: tau = 0 alone): the closed
        # form everywhere, then the series at those points (the values elsewhere are per point)
        eC, eS = _damped_c_and_s(t, nu, k2)
        bS = b * eS
        e11, e12, e21, e22 = eC + bS - 1.0, eS, -k2 * eS, eC - bS - 1.0
        ts = [float(t[i]) for i in at]
        n_terms = series_terms(rate * max(abs(x) for x in ts))
        for i, x in zip(at, ts):
            A, B = series_point(x, nu, k2, n_terms)
            e11[i], e12[i], e21[i], e22[i] = B, A, -k2 * A, B - nu * A
        return e11, e12, e21, e22
    e11, e12, e21, e22 = (np.empty_like(t) for _ in range(4))
    big = ~small
    if big.any():
        eC, eS = _damped_c_and_s(t[big], nu, k2)
        bS = b * eS
        e11[big], e12[big], e21[big], e22[big] = eC + bS - 1.0, eS, -k2 * eS, eC - bS - 1.0
    ts = t[small]
    # terms are bounded by x^k / k!, x = rate * max|t|: sum until that is < 1e-17 relative
    A, B = _series_entries(ts, nu, k2, series_terms(rate * float(np.max(np.abs(ts)))))
    e11[small], e12[small], e21[small], e22[small] = B, A, -k2 * A, B - nu * A
    return e11, e12, e21, e22


def alpha_gamma(nu: float, Omega: float) -> tuple[float, float]:
    """alpha = Tr P(1), gamma = det P(1) = e^{-nu}, equation (9)."""
    P = propagator(1.0, nu, Omega)
    return float(P[0, 0] + P[1, 1]), float(np.exp(-nu))


@dataclass(frozen=True)
class AlphaGammaInverse:
    """Result of inverting (9).

    Attributes
    ----------
    nu, Omega : float
        Damping and natural frequency.
    branch : int or None
        Index of the psi branch (underdamped case), None when P(1) has real
        eigenvalues (the inverse is then unique).
    psi : float or None
        psi = sqrt(4 Omega^2 - nu^2)/2 on that branch (section 8 of the paper).
    sign_P12 : float
        sign(P12) = c1 of (39)/(48); +1 in the real-eigenvalue case.
    """

    nu: float
    Omega: float
    branch: int | None
    psi: float | None
    sign_P12: float


def underdamped_branches(alpha: float, gamma: float, n: int) -> list[float]:
    """The first ``n`` admissible psi > 0 with 2 gamma^{1/2} cos psi = alpha.

    Ordered increasingly: psi0, 2pi - psi0, 2pi + psi0, 4pi - psi0, ... where
    psi0 = arccos(alpha / (2 sqrt gamma)) in [0, pi].  Branch 0 is psi0.
    """
    c = alpha / (2.0 * np.sqrt(gamma))
    if not -1.0 < c < 1.0:
        raise ValueError("(alpha, gamma) has real eigenvalues: not underdamped")
    psi0 = float(np.arccos(c))
    out = []
    for m in range(n):
        k = (m + 1) // 2
        out.append(2.0 * np.pi * k + (psi0 if m % 2 == 0 else -psi0))
    return out


def invert_alpha_gamma(alpha: float, gamma: float, branch: int | None = None) -> AlphaGammaInverse:
    """Invert (9): (alpha, gamma) -> (nu, Omega).

    nu = -ln gamma always.  If P(1) has real positive eigenvalues lambda_i the
    inverse is unique: Omega^2 = ln(lambda_1) ln(lambda_2) (docs/theory.md section 2).
    If they are complex, psi (alpha = 2 gamma^{1/2} cos psi) is fixed only modulo
    2 pi and up to sign, and the branch sets sign(P12) = c1 -- so the caller must
    choose: ``branch`` indexes :func:`underdamped_branches`.

    Raises
    ------
    ValueError
        If underdamped and ``branch`` is None, or if (alpha, gamma) has real
        negative eigenvalues (no real (nu, Omega)).
    """
    if not gamma > 0:
        raise ValueError("gamma must be positive")
    nu = -float(np.log(gamma))
    disc = alpha * alpha - 4.0 * gamma
    if disc >= 0:
        if alpha <= 0:
            raise ValueError("real negative eigenvalues: no (nu, Omega) gives this (alpha, gamma)")
        r = np.sqrt(disc)
        lam1 = (alpha + r) / 2.0
        lam2 = gamma / lam1  # avoids cancellation in (alpha - r)/2
        Om2 = float(np.log(lam1) * np.log(lam2))
        return AlphaGammaInverse(nu, float(np.sqrt(Om2)), None, None, 1.0)
    if branch is None:
        raise ValueError(
            "underdamped (alpha, gamma): the psi branch is ambiguous and sets sign(P12)=c1; "
            "pass branch=0, 1, 2, ... (see underdamped_branches)"
        )
    psi = underdamped_branches(alpha, gamma, branch + 1)[branch]
    Omega = float(np.sqrt(psi * psi + nu * nu / 4.0))
    return AlphaGammaInverse(nu, Omega, int(branch), float(psi), float(np.sign(np.sin(psi))) or 1.0)


def propagator_minus_identity_scalar(t: float, nu: float, k2: float, rate: float) -> tuple[float, float, float, float]:
    """Scalar fast path of :func:`propagator_minus_identity` (for root finding).

    ``rate`` is the spectral radius max|s_i| of the generator (precomputed by the caller).
    Returns the entries (E11, E12, E21, E22) of P(t) - I.
    """
    if rate * abs(t) <= _SERIES_RATE_T:
        A = B = 0.0
        a_k, b_k, fac = 1.0, 0.0, t
        for k in range(1, _N_SERIES_RATE_T):
            A += a_k * fac
            B += b_k * fac
            a_k, b_k = -nu * a_k + b_k, -k2 * a_k
            fac = fac * t / (k + 1)
            if abs(fac) * (abs(a_k) + abs(b_k)) < 1e-18 * (abs(A) + abs(B)):
                break
        return B, A, -k2 * A, B - nu * A
    eC, eS = _scalar_damped_c_and_s(t, nu, k2)
    b = 0.5 * nu
    return eC + b * eS - 1.0, eS, -k2 * eS, eC - b * eS - 1.0


def _scalar_damped_c_and_s(t: float, nu: float, k2: float) -> tuple[float, float]:
    """Pure-Python scalar version of :func:`_damped_c_and_s`."""
    b = 0.5 * nu
    d = b * b - k2
    z = d * t * t
    E = math.exp(-b * t)
    if abs(z) <= _SERIES_D:
        c = 1.0 + z * (1.0 / 2 + z * (1.0 / 24 + z / 720))
        sv = 1.0 + z * (1.0 / 6 + z * (1.0 / 120 + z / 5040))
        return E * c, E * sv * t
    if d > 0:
        q = math.sqrt(d)
        if abs(q * t) > 30.0:
            ep, em = math.exp((q - b) * t), math.exp(-(q + b) * t)
            return 0.5 * (ep + em), 0.5 * (ep - em) / q
        return E * math.cosh(q * t), E * math.sinh(q * t) / q
    w = math.sqrt(-d)
    return E * math.cos(w * t), E * math.sin(w * t) / w


def spectral_rate(nu: float, k2: float) -> float:
    """max |s_i| for s^2 + nu s + k2 = 0."""
    d = nu * nu / 4.0 - k2
    if d >= 0:
        return nu / 2.0 + math.sqrt(d)
    return math.sqrt(k2)
