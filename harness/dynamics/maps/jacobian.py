"""Jacobian of the stroboscopic map: the FMU's own derivatives, or central differences.

The map F takes the state at t0 = n + theta to the state one period later.  When the FMU
reports the derivatives of its map (the variational equations with saltation matrices at
the wall events: outputs ``J_uu`` ... ``S_v``, detected by name) one run gives J
exactly, down to any distance from grazing (``method="exact"``).  Otherwise, or with
``method="fd"`` (the cross-check), J is measured by restarting the simulator from perturbed
states.  Saving and restoring the FMU state is not needed either: (u, v)
at a section time determine the future completely, the FMU takes them as its start values
``u0``/``v0``, and a reset + re-initialization costs ~20 us against ~300 us per period.  Near grazing F has a square-root singularity, so the step must
be small against the distance to the grazing set but large against the integrator's noise;
:func:`map_jacobian` tries a ladder of steps and keeps the one where successive estimates
agree best (the classical step selection for noisy differences), and reports that
disagreement as the error estimate.

For the map near grazing (docs/theory.md section 8) :func:`jacobian_vs_x` follows the
family of orbits whose wall-free continuation at t = n is (u, v) = (x, 0): J is measured at
the section phase ``measure_theta`` (default 1/2, far from the impact near t = n, where
every element is generic) and expressed in the coordinates of the section phase ``theta``
by the exact free-flight change of coordinates, J_theta = P(d) J P(d)^-1 with
d = theta - measure_theta mod 1.  At ``theta = 0`` these are the paper's virtual
coordinates at t = n, in which J12 is *not* singular (d sqrt(chi)/dv = 0 at v = 0) and J11
is.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from mapcheck.linear import propagator

from ...errors import HarnessInputError
from .sampling import check_theta
from ...fmu.simulator import Simulator, has_derivatives, tracking_derivatives

TWO_PI = 2.0 * math.pi

#: Steps tried, as multiples of the state scale: 1e-2 down to ~1e-9 in factors of 4.
DEFAULT_STEPS = tuple(1e-2 * 4.0 ** -k for k in range(15))

#: How a Jacobian is obtained: "exact" (the FMU's variational equations), "fd" (central
#: differences), "auto" (exact when the simulator has derivatives, else fd).
METHODS = ("auto", "exact", "fd")


def resolve_method(sim: Any, method: str, argument: str = "method") -> str:
    """"exact" or "fd" for ``method`` on ``sim`` ("auto": exact when available).

    Raises
    ------
    HarnessInputError
        For an unknown method, or "exact" on a simulator without derivatives.
    """
    if method not in METHODS:
        raise HarnessInputError(argument, f"unknown Jacobian method {method!r}; one of {', '.join(METHODS)}")
    if method == "auto":
        return "exact" if has_derivatives(sim) else "fd"
    if method == "exact" and not has_derivatives(sim):
        raise HarnessInputError(argument, "exact derivatives requested, but the FMU does not report them "
                                "(no sensitivity outputs J_uu ... S_v); use the finite differences (fd)")
    return method


@dataclass(frozen=True)
class JacobianResult:
    """A measured Jacobian.

    Attributes
    ----------
    J : ndarray, shape (2, 2)
        d(u, v)_{n+1} / d(u, v)_n.
    image : ndarray, shape (2,)
        F(state), the unperturbed image.
    step : float
        The smaller of the two difference steps chosen (one per column).
    error : float
        max |J(step) - J(previous step)|: the estimated absolute error (fd); 0 for "exact"
        (the variational equations' error is the integrator's, not estimated here).
    method : str
        "exact" or "fd".
    S : ndarray, shape (2,) or None
        d(u, v)_{n+1} / d sigma (exact method only).
    """

    J: np.ndarray
    image: np.ndarray
    step: float
    error: float
    method: str = "fd"
    S: np.ndarray | None = None


def one_period(sim: Simulator, params: Mapping[str, Any], state: Sequence[float], t0: float) -> np.ndarray:
    """F(state): (u, v) one period after ``t0``, from a fresh (re)start."""
    sim.start(params, t0, (float(state[0]), float(state[1])))
    sim.advance(t0 + 1.0)
    u, v, _ = sim.read()
    return np.array([u, v])


def central_difference(sim: Simulator, params: Mapping[str, Any], state: np.ndarray, t0: float,
                       j: int, step: float) -> np.ndarray:
    """Column ``j`` of the one-period map's Jacobian by a central difference of absolute
    ``step`` in component ``j`` of ``state`` (two restarts)."""
    dx = np.zeros(2)
    dx[j] = step
    return (one_period(sim, params, state + dx, t0) - one_period(sim, params, state - dx, t0)) / (2.0 * step)


def exact_jacobian(sim: Simulator, params: Mapping[str, Any], state: Sequence[float],
                   theta: float = 0.0) -> JacobianResult:
    """J and dF/d sigma of the one-period map from the FMU's variational equations (one run)."""
    theta = check_theta(theta)
    with tracking_derivatives(sim, True):
        image = one_period(sim, params, state, theta)
        J, S = sim.derivatives()  # type: ignore[attr-defined]
    return JacobianResult(J=J, image=image, step=0.0, error=0.0, method="exact", S=S)


def map_jacobian(
    sim: Simulator,
    params: Mapping[str, Any],
    state: Sequence[float],
    theta: float = 0.0,
    steps: Sequence[float] = DEFAULT_STEPS,
    scale: Sequence[float] = (1.0, TWO_PI),
    method: str = "auto",
) -> JacobianResult:
    """Jacobian of the one-period map at ``state`` (taken at t = theta).

    Parameters
    ----------
    sim : Simulator
    params : mapping
        FMU parameters; tight ``rtol``/``atol`` make small steps usable.
    state : (u, v)
        Point of the section at phase ``theta``.
    theta : float
        Section phase in [0, 1).
    steps : sequence of float
        Candidate relative steps, decreasing.
    scale : (float, float)
        Step in u is ``h * scale[0]``, in v ``h * scale[1]`` (v ~ 2 pi u along orbits).
    method : str
        "auto" (the FMU's derivatives when it reports them, else differences), "exact" or
        "fd" (``steps`` and ``scale`` apply to "fd" only).

    Returns
    -------
    JacobianResult
    """
    theta = check_theta(theta)
    if resolve_method(sim, method) == "exact":
        return exact_jacobian(sim, params, state, theta)
    if len(steps) < 2:
        raise HarnessInputError("steps", "need at least two candidate steps")
    x = np.asarray(state, dtype=float)
    if getattr(sim, "tracking", False):
        with tracking_derivatives(sim, False):  # no variational equations behind the differences
            return map_jacobian(sim, params, x, theta, steps, scale, "fd")
    image = one_period(sim, params, x, theta)
    # One ladder per column (perturbation direction): u and v perturbations reach the
    # grazing set at different steps, so each column gets its own best step.
    J = np.empty((2, 2))
    chosen = np.empty(2)
    errors = np.empty(2)
    for j in range(2):
        cols = []
        for h in steps:
            cols.append(central_difference(sim, params, x, theta, j, h * scale[j]))
        diffs = [float(np.max(np.abs(cols[k + 1] - cols[k]))) for k in range(len(steps) - 1)]
        best = int(np.argmin(diffs))
        J[:, j] = cols[best + 1]
        chosen[j] = steps[best + 1]
        errors[j] = diffs[best]
    return JacobianResult(J=J, image=image, step=float(chosen.min()), error=float(errors.max()))


def free_propagator(nu: float, Omega: float, dt: float) -> np.ndarray:
    """P(dt) of the wall-free oscillator (7): exp(dt [[0, 1], [-Omega^2, -nu]]), in closed form
    (:func:`mapcheck.linear.propagator`, equal to scipy's expm to 2e-13).  Not expm itself: its
    Pade step calls LAPACK, whose threads on a loaded 2-core machine made each call ~6 ms; the graze
    location samples thousands of free flights (``windows`` with two workers: shooting 10 s, not 1 s)."""
    return np.asarray(propagator(float(dt), nu, Omega), dtype=float).reshape(2, 2)


def wall_free_orbit(sigma: float, t: float) -> np.ndarray:
    """(p, p') of (4): the wall-free periodic orbit p(t) = (1 + sigma) cos(2 pi t) - 1."""
    return np.array([(1 + sigma) * math.cos(TWO_PI * t) - 1.0, -TWO_PI * (1 + sigma) * math.sin(TWO_PI * t)])


def grazing_family_state(x: float, t: float, nu: float, Omega: float, sigma: float) -> np.ndarray:
    """State at time ``t`` (within the period before t = 0) of the wall-free orbit through
    (u, v) = (x, 0) at t = 0, by (8): u(t) = P(t) [u(0) - p(0)] + p(t)."""
    return free_propagator(nu, Omega, t) @ (np.array([x, 0.0]) - wall_free_orbit(sigma, 0.0)) + wall_free_orbit(sigma, t)


@dataclass(frozen=True)
class JacobianScan:
    """J against x along the grazing family, in the coordinates of phase ``theta``.

    Attributes
    ----------
    x : ndarray (K,)
    J : ndarray (K, 2, 2)
        In the coordinates of phase ``theta``.
    J_measured : ndarray (K, 2, 2)
        As measured at phase ``measure_theta``.
    P1 : ndarray (2, 2)
        Free-flight Jacobian P(1) (same in every phase's coordinates).
    step, error : ndarray (K,)
    theta, measure_theta : float
    method : str
        "exact" or "fd".
    """

    x: np.ndarray
    J: np.ndarray
    J_measured: np.ndarray
    P1: np.ndarray
    step: np.ndarray
    error: np.ndarray
    theta: float
    measure_theta: float
    method: str = "fd"


def jacobian_vs_x(
    sim: Simulator,
    params: Mapping[str, Any],
    x: Sequence[float],
    theta: float = 0.0,
    measure_theta: float = 0.5,
    progress: Any = None,
    method: str = "auto",
) -> JacobianScan:
    """J(x) near grazing for the family with wall-free state (x, 0) at t = n.

    Parameters
    ----------
    sim : Simulator
    params : mapping
        Must contain ``nu``, ``Omega``, ``sigma`` (for the free-flight coordinates).
    x : sequence of float
        Penetration of the wall-free orbit at t = n (x > 0: impact).
    theta : float
        Section phase of the coordinates J is expressed in (0: the paper's t = n).
    measure_theta : float
        Section phase where J is measured; it must not be within the impact, so 1/2.
    progress : tqdm-like, optional
    method : str
        "auto", "exact" or "fd" (see :func:`map_jacobian`).  With exact derivatives the scan
        reaches x = 1e-9 and below; differences stop being usable near x ~ 1e-5.
    """
    method = resolve_method(sim, method, "method")
    theta = check_theta(theta, "theta")
    measure_theta = check_theta(measure_theta, "measure_theta")
    for name in ("nu", "Omega", "sigma"):
        if name not in params:
            raise HarnessInputError(name, "needed for the free-flight coordinates of the Jacobian")
    nu, Om, sigma = float(params["nu"]), float(params["Omega"]), float(params["sigma"])
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        raise HarnessInputError("x", "empty range of x")
    t_meas = measure_theta - 1.0  # measured over [n - 1 + m, n + m], so the impact near n is inside
    d = (theta - measure_theta) % 1.0
    T = free_propagator(nu, Om, d)
    Tinv = np.linalg.inv(T)
    Js, Jm, hs, errs = [], [], [], []
    for xi in x:
        state = grazing_family_state(float(xi), t_meas, nu, Om, sigma)
        res = map_jacobian(sim, params, state, theta=measure_theta, method=method)
        Jm.append(res.J)
        Js.append(T @ res.J @ Tinv)
        hs.append(res.step)
        errs.append(res.error)
        if progress is not None:
            progress.update(1)
    return JacobianScan(
        x=x, J=np.array(Js), J_measured=np.array(Jm), P1=free_propagator(nu, Om, 1.0),
        step=np.array(hs), error=np.array(errs), theta=theta, measure_theta=measure_theta, method=method,
    )
