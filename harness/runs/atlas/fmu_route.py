"""The atlas's pixels through the FMU (CVODE, or the nonlinear contact laws the closed form does not
have), with the batch kernel's outcome per start (:class:`harness.fmu.atlas_kernel.AtlasBatch`).

Each start: the transient, ``samples`` = 4 x the largest period sampled and classified
(:func:`harness.dynamics.maps.classify.classify_orbit`, the atlas's tolerance); a periodic one
then runs M periods with the FMU's exact derivatives (their product: the Jacobian of the M-period
map, ln of its largest |multiplier| / M the exponent), an aperiodic one the exponent over
``n_lyap`` periods (:func:`harness.dynamics.maps.lyapunov.lyapunov_continued`). The transient is
the kernel's ``n_max`` less those samples: no early stop here.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ...config.defaults import WALLS
from ...dynamics.maps.classify import classify_orbit
from ...dynamics.maps.lyapunov import lyapunov_continued, period_jacobians
from ...dynamics.maps.sampling import sample_periods
from ...errors import FmuError
from ...fmu import atlas_kernel as ak
from ...fmu.simulator import simulator_for, tracking_derivatives
from .plane import AtlasPlane

#: Periodicity tolerance of the FMU route at least (CVODE's samples scatter by its tolerances).
FMU_TOL = 1e-5


def _spectral_log(J: np.ndarray) -> float:
    rho = float(np.max(np.abs(np.linalg.eigvals(J))))
    return float(np.log(rho)) if rho > 0 else -745.0


def _one_start(sim: Any, params: dict[str, Any], plane: AtlasPlane, z0: tuple[float, float]) -> tuple:
    """(status, period, impacts, periods run, sticks, exponent, points (m_max, 2))."""
    r = plane.run
    pts = np.full((r.m_max, 2), np.nan)
    if int(params.get("wall", 1)) == WALLS["rigid"] and (z0[0] > 0 or (z0[0] == 0 and z0[1] > 0)):
        return ak.INVALID, 0, 0, 0, False, np.nan, pts
    n_samples = 4 * r.m_max
    with tracking_derivatives(sim, True):
        try:
            sim.start(params, plane.theta, z0)
            s = sample_periods(sim, max(r.n_max - n_samples, 0), n_samples)
            if not (np.all(np.abs(s.u) < 1e12) and np.all(np.abs(s.v) < 1e12)):
                return ak.ESCAPED, 0, 0, r.n_max, False, np.nan, pts
            orbit = classify_orbit(s.u, s.v, s.impacts, max(r.tol, FMU_TOL), r.m_max)
            if orbit.periodic:
                M = orbit.period
                Js, _ = period_jacobians(sim, M)
                J = np.eye(2)
                for Jk in Js:
                    J = Jk @ J
                pts[:M, 0], pts[:M, 1] = s.u[-M:], s.v[-M:]
                sticks = bool(np.any(s.impacts[-M:] >= 8))
                return ak.PERIODIC, M, orbit.impacts, r.n_max + M, sticks, _spectral_log(J) / M, pts
            lyap = lyapunov_continued(sim, params, r.n_lyap, exact=True)
            pts[0] = s.u[-1], s.v[-1]
            return ak.APERIODIC, 0, 0, r.n_max + r.n_lyap, False, float(lyap.exponents[0]), pts
        except FmuError:
            return ak.FAILED, 0, 0, 0, False, np.nan, pts


def run_fmu_pixels(source: Any, plane: AtlasPlane, names: Sequence[str], values: np.ndarray, u0: np.ndarray,
                   v0: np.ndarray) -> ak.AtlasBatch:
    """Every pixel's starts through the FMU ``source`` (this thread's instance)."""
    sim = simulator_for(source)
    n_pix, k = u0.shape
    out = ak.AtlasBatch(np.ones(n_pix, bool), np.zeros((n_pix, k), np.int32), np.zeros((n_pix, k), np.int32),
                        np.zeros((n_pix, k), np.int32), np.zeros((n_pix, k), np.int32), np.zeros((n_pix, k), bool),
                        np.full((n_pix, k), np.nan), np.full((n_pix, k, plane.run.m_max, 2), np.nan), "")
    for p in range(n_pix):
        params = {**plane.params, **{n: float(x) for n, x in zip(names, values[p])}}
        for i in range(k):
            st, M, imp, runs, sticks, lyap, pts = _one_start(sim, params, plane, (float(u0[p, i]), float(v0[p, i])))
            out.status[p, i], out.period[p, i], out.impacts[p, i], out.periods_run[p, i] = st, M, imp, runs
            out.sticks[p, i], out.lyapunov[p, i], out.points[p, i] = sticks, lyap, pts
    return out
