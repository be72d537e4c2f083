"""Basins of attraction: a grid of initial states (u0, v0) at the section phase theta, each
followed to the attractor it reaches, the attractors told apart by their stroboscopic orbits
(:mod:`harness.dynamics.attractors.identity`).

The grid runs as a fresh 2D sweep over the initial state (:func:`harness.runs.sweeps.run_sweep`),
so it is parallel, runs on Dask when asked and resumes from its checkpoint like any sweep.
"""
from __future__ import annotations

import json
from typing import Any, Mapping, Sequence

import numpy as np
import xarray as xr

from ...config import SamplingSpec, SweepSpec
from ...dynamics.attractors.identity import (
    ESCAPED,
    INVALID,
    NOT_PERIODIC,
    STICKING,
    Attractor,
    identify_attractors,
)
from ...errors import HarnessInputError
from ..sweeps import SweepStats, run_sweep

#: Default orbit-matching tolerance, in units of the sampling tolerance times the orbit scale:
#: 1000 x 1e-5 = 1 % of the orbit's size.  Orbits of one attractor converge to the sampling
#: tolerance; distinct coexisting orbits lie much further apart.
MATCH_FACTOR = 1e3


def default_match_tol(ds: xr.Dataset, tol: float) -> float:
    """``MATCH_FACTOR * tol * max(1, largest |u|, |v| sampled)``: relative like the sampling tol."""
    finite = np.concatenate([np.abs(ds["u"].values[np.isfinite(ds["u"].values)]),
                             np.abs(ds["v"].values[np.isfinite(ds["v"].values)])])
    scale = max(1.0, float(finite.max())) if finite.size else 1.0
    return MATCH_FACTOR * tol * scale


def run_basins(fmu: Any, u0: Sequence[float], v0: Sequence[float], params: Mapping[str, Any] | None = None,
               sampling: SamplingSpec | None = None, match_tol: float | None = None, *,
               backend: Any = None, workers: int | None = None, scheduler: str | None = None,
               checkpoint: str | None = None, progress: bool = True, settings: Mapping[str, Any] | None = None,
               stats: SweepStats | None = None) -> xr.Dataset:
    """Start from every (u0, v0) of the grid at t = theta and label the attractor reached.

    Parameters
    ----------
    fmu : FmuModel, path or Simulator
        As for :func:`harness.run_sweep`.
    u0, v0 : sequence of float
        The grid of initial states (at least one value each, distinct).
    params : mapping, optional
        FMU parameters (sigma, wall, ...).
    sampling : SamplingSpec, optional
        Transient, samples, periodicity tolerance, section phase theta.
    match_tol : float, optional
        Largest distance between two orbits of one attractor (see
        :func:`harness.dynamics.attractors.identity.identify_attractors`); default :func:`default_match_tol`.
    backend, workers, scheduler, checkpoint, progress, settings, stats
        As for :func:`harness.run_sweep` (parallel by default; resumable from ``checkpoint``).

    Returns
    -------
    xarray.Dataset
        The sweep's variables on dims (u0, v0[, sample]) plus ``attractor`` (u0, v0): the label,
        -1 not periodic, -2 invalid start; and per attractor ``attractor_period``,
        ``attractor_impacts``, ``attractor_starts`` and ``attractor_points`` (attractor, point,
        coordinate), NaN-padded.
    """
    sampling = sampling or SamplingSpec()
    u0, v0 = check_grid(u0, "u0"), check_grid(v0, "v0")
    spec = SweepSpec("u0", u0, ("fresh",), "v0", v0)
    ds = run_sweep(fmu, spec, params, (float(u0[0]), float(v0[0])), sampling, backend=backend, workers=workers,
                   scheduler=scheduler, checkpoint=checkpoint, progress=progress, settings=settings, stats=stats)
    ds = ds.isel(direction=0, drop=True)
    tol = default_match_tol(ds, sampling.tol) if match_tol is None else float(match_tol)
    if not (np.isfinite(tol) and tol > 0):
        raise HarnessInputError("match_tol", f"must be a finite number > 0, got {match_tol!r}")
    labels, attractors = identify_attractors(ds["u"].values, ds["v"].values, ds["period"].values,
                                             ds["orbit_impacts"].values, tol)
    return with_attractors(ds, labels, attractors, tol)


def check_grid(values: Sequence[float], name: str) -> np.ndarray:
    """One axis of the grid of starts: one or more finite, distinct values."""
    grid = np.asarray(values, dtype=float)
    if grid.ndim != 1 or grid.size < 1 or not np.all(np.isfinite(grid)):
        raise HarnessInputError(name, "expected one or more finite values")
    if np.unique(grid).size != grid.size:
        raise HarnessInputError(name, "values must be distinct")
    return grid


def with_attractors(ds: xr.Dataset, labels: np.ndarray, attractors: list[Attractor], tol: float) -> xr.Dataset:
    """``ds`` with the variables and attributes of :func:`run_basins`'s result."""
    ds = ds.copy()
    ds["attractor"] = (("u0", "v0"), labels, {
        "long_name": "attractor reached from (u0, v0) at t = theta",
        "flag_values": np.array([ESCAPED, STICKING, INVALID, NOT_PERIODIC], dtype=np.int64),
        "flag_meanings": "escaped_or_failed sticking_or_chatter invalid_start not_periodic",
        "comment": ">= 0: index of the periodic attractor (attractor_* variables); -1: samples not periodic "
                   "(chaotic, quasi-periodic or not converged: see dynamics); -2: start refused by the FMU "
                   "(inside a rigid wall); -3 (batch kernel): not periodic, sticking or chattering at its "
                   "samples; -4 (batch kernel): escaped or failed"})
    n = len(attractors)
    width = max([a.period for a in attractors], default=1)
    points = np.full((n, width, 2), np.nan)
    for a in attractors:
        points[a.label, : a.period] = a.points
    ds = ds.assign_coords(attractor_index=np.arange(n), point=np.arange(width), coordinate=["u", "v"])
    ds["attractor_period"] = ("attractor_index", np.array([a.period for a in attractors], dtype=np.int64),
                              {"long_name": "period of the attractor's stroboscopic orbit"})
    ds["attractor_impacts"] = ("attractor_index", np.array([a.impacts for a in attractors], dtype=np.int64),
                               {"long_name": "wall entries per orbit period"})
    ds["attractor_starts"] = ("attractor_index", np.array([a.starts for a in attractors], dtype=np.int64),
                              {"long_name": "grid points in the basin"})
    ds["attractor_points"] = (("attractor_index", "point", "coordinate"), points,
                              {"long_name": "stroboscopic points of the attractor at t = n + theta (NaN-padded)"})
    ds.attrs["basins.match_tol"] = tol
    ds.attrs["basins.attractors"] = json.dumps([a.name for a in attractors])
    ds.attrs["basins.not_periodic_starts"] = int(np.sum(labels == NOT_PERIODIC))
    ds.attrs["basins.invalid_starts"] = int(np.sum(labels == INVALID))
    ds.attrs["basins.sticking_starts"] = int(np.sum(labels == STICKING))
    ds.attrs["basins.escaped_starts"] = int(np.sum(labels == ESCAPED))
    return ds


