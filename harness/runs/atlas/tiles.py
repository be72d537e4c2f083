"""One tile of an atlas (whole rows of the plane), run on a worker: every pixel's starts to their
attractors, on the batch kernel (the closed form in C, :mod:`harness.fmu.atlas_kernel`) or through
the FMU (CVODE, the nonlinear contact laws), each start classified and the attractors of each
pixel told apart.

A start's kind (:data:`KINDS`): a periodic orbit (period M, wall entries per orbit period), one
that sticks or chatters on the wall, chaos (aperiodic with largest Lyapunov exponent above
:data:`~.plane.CHAOS_LYAPUNOV`), aperiodic otherwise (quasi-periodic or not settled within the
periods allowed), escaped (or failed: the integration stopped), invalid (inside a rigid wall).
Within a pixel, two periodic starts reach the same attractor when their kinds, periods and
entries agree and their orbits' points lie within ``id_tol`` (relative to 1 + |u| + |v|,
Hausdorff distance) of each other; all aperiodic starts of a pixel (chaotic or not: a few
hundred periods do not tell weak chaos from a slow transient) count as one attractor, and so do
all escaped ones.

Kept free of xarray and Dask so that a worker imports only numpy and the kernel's loader.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...fmu import atlas_kernel as ak
from .plane import CHAOS_LYAPUNOV, AtlasPlane, pixel_parameters, pixel_starts

#: Kinds of a start, by code.
PERIODIC, STICKING, CHAOTIC, APERIODIC, ESCAPED, INVALID, FAILED = range(7)
KINDS = ("periodic", "sticking", "chaotic", "aperiodic", "escaped", "invalid", "failed")


@dataclass(frozen=True)
class AtlasTile:
    """Rows ``rows`` of ``plane``, run on the kernel (``route`` "kernel", ``threads`` threads) or
    through the FMU (``route`` "fmu": the source is the backend's)."""

    index: int
    plane: AtlasPlane
    rows: slice
    route: str = "kernel"
    threads: int = 1


def run_tile(tile: AtlasTile, source: Any = None, progress: Any = None) -> dict[str, Any]:
    """Run a tile (``source``: the FMU of the FMU route; ``progress`` unused).

    Returns
    -------
    dict
        ``index`` and arrays (n_rows, n_sigma, starts): ``kind``, ``period``, ``impacts``,
        ``lyapunov``, ``label`` (the pixel's attractor, -1 for invalid and failed starts),
        ``periods_run``, ``u``, ``v`` (the orbit's last point); ``error`` (the first failure).
    """
    plane = tile.plane
    names, values = pixel_parameters(plane, tile.rows)
    u0, v0 = pixel_starts(plane, tile.rows)
    if tile.route == "kernel":
        b = ak.run_atlas(plane.params, names, values, u0, v0, plane.theta, plane.run.n_min, plane.run.n_max,
                         plane.run.m_max, plane.run.tol, plane.run.n_lyap, plane.run.match_tol, threads=tile.threads)
    else:
        from .fmu_route import run_fmu_pixels

        b = run_fmu_pixels(source, plane, names, values, u0, v0)
    kind = start_kinds(b)
    label = pixel_labels(kind, b.period, b.impacts, b.points, plane.run.id_tol)
    last = np.take_along_axis(b.points, np.clip(b.period - 1, 0, None)[..., None, None], axis=2)[:, :, 0]
    shape = (tile.rows.stop - tile.rows.start, plane.sigma.size, plane.starts)
    out = {"kind": kind, "period": b.period, "impacts": b.impacts, "lyapunov": b.lyapunov, "label": label,
           "periods_run": b.periods_run, "u": last[..., 0], "v": last[..., 1]}
    return {"index": tile.index, "error": b.error, **{k: np.asarray(x).reshape(shape) for k, x in out.items()}}


def start_kinds(b: ak.AtlasBatch) -> np.ndarray:
    """The kind code of every start (n_pix, k).  A start that recurred on an orbit whose exponent
    is not negative did not reach an attractor: it sat, within the recurrence tolerance, on a
    saddle (next to a flip, where the doubled orbit lies within ~sqrt of the distance) and is
    aperiodic (not settled), not a pixel where that orbit is stable."""
    kind = np.full(b.status.shape, FAILED, dtype=np.int8)
    periodic = b.status == ak.PERIODIC
    unstable = periodic & ~b.sticks & np.isfinite(b.lyapunov) & (b.lyapunov >= 0.0)
    kind[periodic] = PERIODIC
    kind[periodic & b.sticks] = STICKING
    aper = (b.status == ak.APERIODIC) | unstable
    kind[aper] = APERIODIC
    kind[aper & (b.lyapunov > CHAOS_LYAPUNOV)] = CHAOTIC
    kind[b.status == ak.ESCAPED] = ESCAPED
    kind[b.status == ak.INVALID] = INVALID
    return kind


def pixel_labels(kind: np.ndarray, period: np.ndarray, impacts: np.ndarray, points: np.ndarray,
                 id_tol: float) -> np.ndarray:
    """The attractor of every start within its pixel (0, 1, ... in order of first appearance;
    -1: invalid or failed). Two periodic starts are on one orbit when their kinds, periods and
    entries agree and each one's last point lies within ``id_tol`` (1 + |z|) of a point of the
    other's orbit; each start takes the label of the first start it agrees with."""
    n_pix, k = kind.shape
    last = np.take_along_axis(points, np.clip(period - 1, 0, None)[..., None, None], axis=2)[:, :, 0]  # (n, k, 2)
    scale = id_tol * (1.0 + np.max(np.abs(np.nan_to_num(last)), axis=2))  # (n, k)
    # d[p, i, j]: distance from start i's last point to the nearest point of start j's orbit
    d = np.fmin.reduce(np.max(np.abs(last[:, :, None, None, :] - points[:, None, :, :, :]), axis=4), axis=3)
    close = (d <= scale[:, :, None]) & (d.transpose(0, 2, 1) <= scale[:, None, :])
    group = np.where(kind == APERIODIC, CHAOTIC, kind)  # a pixel's aperiodic starts: one attractor
    same = group[:, :, None] == group[:, None, :]
    orbit = np.isin(kind, (PERIODIC, STICKING))[:, :, None]
    same &= ~orbit | ((period[:, :, None] == period[:, None, :]) & (impacts[:, :, None] == impacts[:, None, :]) & close)
    valid = ~np.isin(kind, (INVALID, FAILED))
    same &= valid[:, :, None] & valid[:, None, :]
    same |= np.eye(k, dtype=bool)[None]
    rep = np.argmax(same, axis=2)  # the first start each agrees with (itself at the latest)
    first = (rep == np.arange(k)[None, :]) & valid
    rank = np.cumsum(first, axis=1) - 1
    label = np.take_along_axis(rank, rep, axis=1).astype(np.int16)
    label[~valid] = -1
    return label
