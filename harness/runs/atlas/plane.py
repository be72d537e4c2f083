"""The parameter plane of an atlas: the grid over (sigma, a second parameter), the starts of each
pixel, how long each start runs, and the plane cut into tiles of whole rows (one value of the
second parameter per row).

The starts of a pixel (``starts`` of them) lie in the box the wall-free orbit p(t) = (1 + sigma)
cos(2 pi t) - 1 spans, widened by a fifth: u in [-1 - 1.2 A, 0.2 A] (up to the wall, u <= 0, on a
rigid one), v in [-2.4 pi A, 2.4 pi A], A = |1 + sigma|: half of them (rounded up) at the centres
of a regular grid over the box, the rest uniformly random from a generator seeded with the seed
and the pixel's index, so that a tile run again (a resumed scan, another worker) has the same
starts.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...config.defaults import WALLS
from ...errors import HarnessInputError

#: Second parameters of an atlas: the model's physical parameters besides sigma.
PARAM2 = ("Gamma", "nu", "Omega", "r", "alpha", "gamma")
#: Largest exponent (per forcing period) of an aperiodic start that is not counted as chaos:
#: above it the start is chaotic; a tangent vector over a few hundred periods of a quasi-periodic
#: orbit or a slow transient scatters by about this much around zero or below.
CHAOS_LYAPUNOV = 0.02


@dataclass(frozen=True)
class RunLength:
    """How long a start runs: periods before the periodicity test (``n_min``), at most
    (``n_max``), the largest period (``m_max``), the test's tolerance (relative to 1 + |u| + |v|),
    the tolerance of a start recognised on an earlier start's orbit (``match_tol``) and two
    orbits told apart (``id_tol``), and the exponent's periods of an aperiodic start."""

    n_min: int = 0
    n_max: int = 500
    m_max: int = 12
    tol: float = 1e-8
    match_tol: float = 1e-4
    id_tol: float = 1e-3
    n_lyap: int = 200


@dataclass(frozen=True)
class AtlasPlane:
    """The plane: ``p2`` values (rows) x ``sigma`` values (columns), ``starts`` per pixel.

    ``params`` are the FMU parameters every pixel shares (the wall by its number); ``param2`` is
    set per row, ``sigma`` per column. ``alpha`` and ``gamma`` as second parameter are the
    free-flight propagator's trace and determinant (docs/theory.md section 2): the pixel's nu and
    Omega follow from them, the other of the two held at the value ``params``' nu and Omega give.
    """

    params: dict[str, Any] = field(hash=False)
    param2: str
    p2: np.ndarray = field(hash=False)
    sigma: np.ndarray = field(hash=False)
    starts: int = 8
    theta: float = 0.0
    seed: int = 0
    run: RunLength = RunLength()

    @property
    def shape(self) -> tuple[int, int]:
        return self.p2.size, self.sigma.size

    def rows_per_tile(self, pixels: int = 4096) -> int:
        """Whole rows per tile, about ``pixels`` pixels."""
        return max(1, pixels // max(1, self.sigma.size))

    def tiles(self, pixels: int = 4096) -> list[tuple[int, slice]]:
        """(index, rows) of every tile."""
        n = self.rows_per_tile(pixels)
        return [(k, slice(a, min(a + n, self.p2.size))) for k, a in enumerate(range(0, self.p2.size, n))]

    def fingerprint(self) -> dict[str, Any]:
        """Everything that decides a tile's results (a checkpoint holds only the same plane's)."""
        return {"params": self.params, "param2": self.param2, "p2": self.p2, "sigma": self.sigma,
                "starts": self.starts, "theta": self.theta, "seed": self.seed, "run": vars(self.run)}


def pixel_parameters(plane: AtlasPlane, rows: slice) -> tuple[tuple[str, ...], np.ndarray]:
    """The parameters set per pixel of ``rows`` (names, values (n_pix, n)), row-major."""
    p2 = plane.p2[rows]
    S, P = np.meshgrid(plane.sigma, p2)  # (rows, columns)
    if plane.param2 in ("alpha", "gamma"):
        nu, Om = nu_omega(plane.params, plane.param2, P.ravel())
        return ("sigma", "nu", "Omega"), np.column_stack([S.ravel(), nu, Om])
    return ("sigma", plane.param2), np.column_stack([S.ravel(), P.ravel()])


def nu_omega(params: dict[str, Any], name: str, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(nu, Omega) with the propagator's alpha or gamma set to ``values`` and the other as
    ``params`` give it; underdamped, on the branch of psi nearest the base oscillator's
    (mapcheck.linear.invert_alpha_gamma)."""
    from mapcheck.linear import alpha_gamma, invert_alpha_gamma, underdamped_branches

    nu0, om0 = float(params["nu"]), float(params["Omega"])
    alpha0, gamma0 = alpha_gamma(nu0, om0)
    psi0 = math.sqrt(max(4.0 * om0 * om0 - nu0 * nu0, 0.0)) / 2.0
    nus, oms = [], []
    for x in np.asarray(values, float):
        a, g = (float(x), gamma0) if name == "alpha" else (alpha0, float(x))
        try:
            if g > 0 and a * a < 4.0 * g:  # underdamped: the branch nearest the base's psi
                psis = underdamped_branches(a, g, int(psi0 / math.pi) * 2 + 4)
                inv = invert_alpha_gamma(a, g, int(np.argmin([abs(p - psi0) for p in psis])))
            else:
                inv = invert_alpha_gamma(a, g)
        except (ValueError, ZeroDivisionError) as exc:
            other = f"gamma = {g:g}" if name == "alpha" else f"alpha = {a:g}"
            raise HarnessInputError("range", f"{name} = {x:g} with {other} is no oscillator: {exc}") from None
        nus.append(inv.nu)
        oms.append(inv.Omega)
    return np.asarray(nus), np.asarray(oms)


def pixel_starts(plane: AtlasPlane, rows: slice) -> tuple[np.ndarray, np.ndarray]:
    """The starts (u0, v0) of every pixel of ``rows``, arrays (n_pix, starts)."""
    n_rows = rows.stop - rows.start
    n_pix = n_rows * plane.sigma.size
    A = np.abs(1.0 + np.tile(plane.sigma, n_rows))[:, None]
    rigid = int(plane.params.get("wall", 1)) == WALLS["rigid"]
    k = plane.starts
    g = (k + 1) // 2
    nu_ = max(1, int(round(math.sqrt(g))))
    nv_ = int(math.ceil(g / nu_))
    cu = (np.arange(nu_) + 0.5) / nu_
    cv = (np.arange(nv_) + 0.5) / nv_
    CU, CV = (x.ravel()[:g] for x in np.meshgrid(cu, cv, indexing="ij"))
    fu = np.empty((n_pix, k))
    fv = np.empty((n_pix, k))
    fu[:, :g], fv[:, :g] = CU, CV
    first = rows.start * plane.sigma.size
    for i in range(n_pix):
        rng = np.random.default_rng([plane.seed, first + i])
        fu[i, g:], fv[i, g:] = rng.random(k - g), rng.random(k - g)
    u_lo, u_hi = -1.0 - 1.2 * A, (0.0 if rigid else 0.2) * A
    u0 = u_lo + fu * (u_hi - u_lo)
    if rigid:
        u0 = np.minimum(u0, -1e-12)  # a start on the wall moving in is refused like one inside it
    v0 = (2.0 * fv - 1.0) * 2.4 * math.pi * A
    return u0, v0


def check_plane(plane: AtlasPlane) -> AtlasPlane:
    """One-line errors for a plane no run can use."""
    if plane.param2 not in PARAM2:
        raise HarnessInputError("param2", f"must be one of {', '.join(PARAM2)}, got {plane.param2!r}")
    if not 1 <= plane.starts <= 256:
        raise HarnessInputError("starts", f"must be in 1..256, got {plane.starts}")
    for name, x in (("sigma", plane.sigma), ("p2", plane.p2)):
        if x.ndim != 1 or x.size < 1 or not np.all(np.isfinite(x)):
            raise HarnessInputError(name, "needs at least one finite value")
    if np.any(plane.sigma <= -1.0):
        raise HarnessInputError("sigma_range", "sigma must be > -1 (sigma = -1: no forcing)")
    if not 1 <= plane.run.m_max <= 64:
        raise HarnessInputError("m_max", f"must be in 1..64, got {plane.run.m_max}")
    return plane
