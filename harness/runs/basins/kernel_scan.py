"""Basins of attraction at the scale of published figures: the batch kernel (the FMU's closed
form in C, all cores) with early stopping, in tiles, resumable, locally or on Dask.

1. *Seed*: a strided subset of the grid (a 64th, 32 to 400 starts) runs in full; its
   periodic orbits become the first attractors (stroboscopic points, wall entries per period),
   each confirmed by Newton shooting on the FMU and its tolerance balls run in full
   (:mod:`.basin_ball`).  The matching tolerance is fixed here, from the seed's samples, as
   :func:`harness.runs.basins.scan.default_match_tol` does.
2. *Tiles*: the grid in tiles of ``tile_size`` starts, each run by the kernel with the
   attractors known when it was sent: a start stops as soon as its stroboscopic state lands
   within the tolerance of a point of an attractor whose balls all reached it, or once its
   orbit comes round any attractor twice (:mod:`harness.fmu.batch_kernel`,
   :mod:`.basin_registry`); the others run the whole transient and are classified from their
   samples (:mod:`.basin_tiles`), their new attractors registered (:mod:`.basin_registry`).
   Each finished tile is checkpointed.
3. *Assembly*: labels relabelled by basin size, as :func:`harness.runs.basins.scan.run_basins`
   stores them, plus the periods each start ran and Newton's verdict per attractor.
"""
from __future__ import annotations

import json
import time
from dataclasses import replace
from typing import Any, Mapping, Sequence

import numpy as np
import xarray as xr

from ...config import SOLVERS, SamplingSpec
from ...dynamics.attractors.identity import Attractor, orbit_points
from ...errors import HarnessInputError
from ...fmu import batch_kernel as bk
from .ball import ball_checker
from .registry import CONFIRM_ROUNDS, MIN_CONFIRM, Registry, TileCheckpoint, fingerprint
from .scan import MATCH_FACTOR, check_grid, with_attractors
from .tiles import CANDIDATE, BasinTile, label_result, run_tile
from ..tasks import run_test_hook

#: Starts of the seed run (spread over the grid): SEED_SHARE of the grid, between SEED_MIN and
#: SEED_MAX.  An attractor the seed misses is found by the tiles (it only stops fewer starts).
SEED_MIN, SEED_MAX, SEED_SHARE = 32, 400, 1.0 / 64.0
#: Starts per tile (a tile's samples: tile_size x samples x 21 bytes).
DEFAULT_TILE = 32768
#: The seed of :func:`run_starts` stops a start once its samples repeat to this fraction of the
#: periodicity tolerance (1e-12 of the orbit's size for the global search's 1e-6): converged to
#: the digits the rest of its transient would give, so that the orbit's points, and what is shot
#: and continued from them, are those of the whole run (at 1e-3 of the tolerance the shooting
#: from a period-10 orbit's points missed the branch switching at its flip).
SEED_RECUR = 1e-6
#: :func:`run_starts` stops a start once its samples so far rule out every period and no attractor
#: can recognise it any more (``aperiodic_tol`` of :func:`harness.fmu.batch_kernel.run_batch`: the
#: periodicity tolerance times 1 + this many times the starts' spread, the largest of their ranges
#: in u and v).  The rest of its samples could only make it periodic by widening their range by
#: more than this many times the spread of all the starts (so far beyond every orbit the region
#: was drawn around that the start would be escaping), so it ends not periodic as its whole run
#: would, but for sticking, chatter or a failure in the periods it does not run (none of the
#: cases of bench/global_search_bench.py has any: its labels there are the whole runs').
APERIODIC_SPREAD = 10.0


def _shooter(model: Any, params: Mapping[str, Any], theta: float) -> Any:
    """``shoot(points) -> dict``: Newton on the FMU's closed-form mode (None without an FMU)."""
    if model is None:
        return None
    from ...dynamics.attractors.check import shoot_attractor
    from ...fmu.simulator import FmuSimulator

    sim = FmuSimulator(model.source() if hasattr(model, "source") else model, instance_name="basins-newton")
    run = {**params, "solver": SOLVERS["closed-form"]}

    def shoot(points: np.ndarray) -> dict[str, Any]:
        s = shoot_attractor(sim, run, theta, points)
        return {"converged": s.converged, "residual": s.residual, "multiplier": s.multiplier,
                "impacts": s.impacts, "distance": s.distance, "confirmed": s.confirmed}

    return shoot


def _seed(params: Mapping[str, Any], us: np.ndarray, vs: np.ndarray, s: SamplingSpec, threads: int,
          match_tol: float | None, shoot: Any, ball: Any) -> Registry:
    """The first attractors, from a strided subset run in full."""
    n = min(us.size, max(SEED_MIN, min(SEED_MAX, int(us.size * SEED_SHARE))))
    idx = np.unique(np.linspace(0, us.size - 1, n).round().astype(int))
    res = bk.run_batch(params, us[idx], vs[idx], s.theta, s.n_transient, s.n_samples, None, threads)
    if match_tol is None:
        finite = np.abs(np.concatenate([res.u[np.isfinite(res.u)], res.v[np.isfinite(res.v)]]))
        match_tol = MATCH_FACTOR * s.tol * (max(1.0, float(finite.max())) if finite.size else 1.0)
    reg = Registry(match_tol, shoot, ball=ball)
    reg.merge(label_result(res, s, reg.known()))
    return reg


def run_starts(params: Mapping[str, Any], us: np.ndarray, vs: np.ndarray, s: SamplingSpec, threads: int,
               match_tol: float, n_seed: int, tile_sampling: SamplingSpec | None = None) -> tuple[np.ndarray, Registry]:
    """Labels of any starts (not a grid): ``n_seed`` of them (spread over the list) run until their
    samples repeat (:data:`SEED_RECUR` x the periodicity tolerance: converged to the digits the
    whole transient gives) or in full, the others as one tile early-stopped on the seed's
    attractors with the strict rule, two rounds of each attractor's own orbit (the balls' check
    costs more than it saves on one tile); returns (labels: registry indices or the negative
    codes, the registry).  No Newton shooting: the caller shoots what it keeps.
    ``tile_sampling``: the other starts' sampling (default ``s``; a shorter transient is cheaper
    where starts do not settle, and a start that reaches a seed's attractor stops anyway).
    Every start, seed or not, also stops once its samples so far rule out a period and no
    attractor can recognise it any more (:data:`APERIODIC_SPREAD`): not periodic, as its whole
    run would say (a chaotic start: from the twelfth of 24 samples on instead of the last)."""
    idx = np.unique(np.linspace(0, us.size - 1, min(us.size, n_seed)).round().astype(int))
    aperiodic = 1.0 + APERIODIC_SPREAD * max(float(np.ptp(us)), float(np.ptp(vs)))
    reg = Registry(match_tol)
    seed = bk.run_batch(params, us[idx], vs[idx], s.theta, s.n_transient, s.n_samples, None, threads,
                        recur_tol=SEED_RECUR * s.tol, max_period=s.max_period, aperiodic_tol=aperiodic * s.tol)
    labels = np.empty(us.size, dtype=np.int32)
    labels[idx] = reg.merge(label_result(seed, s, reg.known()))
    _full_points(params, us[idx], vs[idx], labels[idx], seed.periods < s.n_transient + s.n_samples, s, reg,
                 threads)
    rest = np.setdiff1d(np.arange(us.size), idx)
    if rest.size:
        known = reg.known(strict=True)
        known = replace(known, confirm=np.maximum(MIN_CONFIRM, CONFIRM_ROUNDS * known.period).astype(np.int32))
        ts = tile_sampling or s
        res = bk.run_batch(params, us[rest], vs[rest], ts.theta, ts.n_transient, ts.n_samples, known, threads,
                           max_period=ts.max_period, aperiodic_tol=aperiodic * ts.tol)
        labels[rest] = reg.merge(label_result(res, ts, known))
    return labels, reg


def _full_points(params: Mapping[str, Any], us: np.ndarray, vs: np.ndarray, labels: np.ndarray, stopped: np.ndarray,
                 s: SamplingSpec, reg: Registry, threads: int) -> None:
    """Each attractor's points as the whole transient gives them: the seed start that registered it
    (the first labelled with it) run again in full, if it ``stopped`` early (one that ran the whole
    transient registered those points already).  What ``windows`` shoots and continues from
    an attractor's points is sensitive far below the periodicity tolerance (from points converged
    to 1e-12 instead of the whole run's, a period-2 orbit's edge came out 0.02 off), and one start
    per attractor costs little beside the seed's periods saved."""
    first = [int(np.flatnonzero(labels == j)[0]) for j in range(len(reg.found)) if np.any(labels == j)]
    first = [i for i in first if stopped[i]]
    if not first:
        return
    full = bk.run_batch(params, us[first], vs[first], s.theta, s.n_transient, s.n_samples, None, threads)
    lab = label_result(full, s, bk.KnownAttractors.none(reg.tol))
    for k, i in enumerate(first):
        j = int(labels[i])
        c = lab["candidates"][CANDIDATE - int(lab["label"][k])] if lab["label"][k] <= CANDIDATE else None
        f = reg.found[j]
        if c is not None and (c.period, c.impacts) == (f.period, f.impacts):
            f.points, f.entries, f.stuck = c.points.tolist(), [int(x) for x in c.entries], c.stuck


def _tiles(us: np.ndarray, vs: np.ndarray, size: int) -> list[tuple[int, slice]]:
    n = us.size
    return [(k, slice(a, min(a + size, n))) for k, a in enumerate(range(0, n, size))]


def _run_tiles(todo: list[tuple[int, slice]], us: np.ndarray, vs: np.ndarray, params: dict[str, Any],
               s: SamplingSpec, reg: Registry, ckpt: TileCheckpoint, be: Any, threads: int,
               on_tile: Any) -> list[str]:
    """Run the missing tiles in waves (one tile per wave locally: all threads on it; two per
    Dask worker), the registry updated between waves so that later tiles stop earlier."""
    errors: list[str] = []
    wave = 1 if be is None else max(1, 2 * be.n_workers())
    for w in range(0, len(todo), wave):
        tiles = {k: BasinTile(k, us[sl], vs[sl], params, s, reg.known(), threads if be is None else 1)
                 for k, sl in todo[w: w + wave]}
        results: dict[int, dict[str, Any]] = {}
        if be is None:
            for k, tile in tiles.items():
                run_test_hook(f"tile-{k:05d}", 0)  # tests interrupt a scan at a known tile
                results[k] = run_tile(tile)
                _finish(results[k], reg, ckpt, on_tile, errors)
        else:
            be.run(run_tile, tiles, None, lambda k, r: _finish(r, reg, ckpt, on_tile, errors))
    return errors


def _finish(result: dict[str, Any], reg: Registry, ckpt: TileCheckpoint, on_tile: Any, errors: list[str]) -> None:
    label = reg.merge(result)
    ckpt.save_registry(reg)  # before the tile: its labels name the registry's attractors
    ckpt.save_tile(result["index"], label, result["periods"])
    if result["error"]:
        errors.append(result["error"])
    on_tile(result["index"], label, result["periods"])


def run_basins_kernel(model: Any, u0: Sequence[float], v0: Sequence[float], params: Mapping[str, Any] | None = None,
                      sampling: SamplingSpec | None = None, match_tol: float | None = None, *,
                      backend: Any = None, workers: int | None = None, scheduler: str | None = None,
                      checkpoint: str | None = None, tile_size: int = DEFAULT_TILE, progress: bool = True,
                      settings: Mapping[str, Any] | None = None, stats: Any = None,
                      attractors_from: xr.Dataset | None = None) -> xr.Dataset:
    """Basins over the grid u0 x v0 (at t = theta) with the batch kernel.

    Parameters
    ----------
    model : FmuModel, FmuSource or None
        The FMU that confirms each attractor by Newton shooting (None: not confirmed).
    u0, v0, params, sampling, match_tol
        As for :func:`harness.runs.basins.scan.run_basins` (the kernel is the closed form
        whatever ``solver`` says; ``sampling.lyapunov`` and ``extend`` are not used).
    backend, workers, scheduler
        ``"serial"`` (one thread), ``"processes"`` or None (this process, ``workers`` threads,
        default all cores), ``"dask"`` with ``scheduler`` (or a ``distributed.Client``):
        tiles on the cluster's workers.
    checkpoint : str, optional
        Directory of finished tiles; a rerun resumes there.
    tile_size : int
        Starts per tile.
    attractors_from : xarray.Dataset, optional
        A basin scan whose attractors (and tolerance) this one starts from, so that its labels
        mean the same (a zoom into it).

    Returns
    -------
    xarray.Dataset
        ``attractor`` (u0, v0) and the ``attractor_*`` variables of ``run_basins`` (without the
        samples), ``periods_run`` (u0, v0), and per attractor Newton's verdict
        (``attractor_confirmed``, ``attractor_newton_residual``, ``attractor_multiplier``).
    """
    t_start = time.perf_counter()
    s = sampling or SamplingSpec()
    params = dict(params or {})
    u0, v0 = check_grid(u0, "u0"), check_grid(v0, "v0")
    if isinstance(tile_size, bool) or not isinstance(tile_size, (int, np.integer)) or tile_size < 1:
        raise HarnessInputError("tile_size", f"must be an integer >= 1, got {tile_size!r}")
    U, V = np.meshgrid(u0, v0, indexing="ij")
    us, vs = U.ravel(), V.ravel()
    be, threads = _backend(backend, workers, scheduler)
    key = fingerprint({"params": params, "u0": u0, "v0": v0, "sampling": repr(s), "tol": match_tol,
                       "tile": int(tile_size), "from": None if attractors_from is None else
                       attractors_from.attrs.get("basins.attractors")})
    ckpt = TileCheckpoint(checkpoint, key)
    shoot, ball = _shooter(model, params, s.theta), ball_checker(params, s, threads)
    reg = ckpt.registry(shoot, ball) or _start_registry(attractors_from, params, us, vs, s, threads, match_tol,
                                                        shoot, ball)
    ckpt.save_registry(reg)
    tiles = _tiles(us, vs, int(tile_size))
    grid = _Grid(us.size, dict(tiles), ckpt.done(), stats, progress)
    try:
        errors = _run_tiles([t for t in tiles if t[0] not in grid.resumed], us, vs, params, s, reg, ckpt, be,
                            threads, grid.on_tile)
    finally:
        grid.bar.close()
        if be is not None:
            be.close()
    wall = time.perf_counter() - t_start
    describe = f"batch kernel (closed form in C), {threads} threads" if be is None else \
        f"batch kernel (closed form in C) on {be.describe()}"
    fixed = 0 if attractors_from is None else int(attractors_from.sizes.get("attractor_index", 0))
    return _assemble(model, u0, v0, grid.labels.reshape(U.shape), grid.periods.reshape(U.shape), reg, s, settings,
                     describe, wall, (len(grid.resumed), len(tiles), fixed), errors)


class _Grid:
    """The scan's labels and periods as tiles finish (resumed ones first), with the progress bar
    and the statistics the command line reports after an interruption."""

    def __init__(self, n: int, slices: dict[int, slice], resumed: dict[int, dict[str, np.ndarray]], stats: Any,
                 progress: bool) -> None:
        self.labels = np.full(n, -1, dtype=np.int32)
        self.periods = np.zeros(n, dtype=np.int32)
        self.slices, self.resumed, self.stats = slices, resumed, stats
        for k, got in resumed.items():
            self.labels[slices[k]], self.periods[slices[k]] = got["label"], got["periods"]
        kept = sum(slices[k].stop - slices[k].start for k in resumed)
        self.bar = _bar(progress, n, kept)
        if stats is not None:
            stats.total_points, stats.resumed, stats.kept_points = n, len(resumed), kept

    def on_tile(self, k: int, label: np.ndarray, periods: np.ndarray) -> None:
        sl = self.slices[k]
        self.labels[sl], self.periods[sl] = label, periods
        self.bar.update(sl.stop - sl.start)
        if self.stats is not None:
            self.stats.computed += 1
            self.stats.kept_points += sl.stop - sl.start


def _backend(backend: Any, workers: int | None, scheduler: str | None) -> tuple[Any, int]:
    """(Dask backend or None for this process, threads per kernel call here)."""
    if backend == "serial":
        return None, 1
    if backend in (None, "processes") and not scheduler:
        return None, int(workers or bk.default_threads())
    from ..backends import make_backend

    return make_backend(backend, workers, scheduler), 1


def _start_registry(attractors_from: xr.Dataset | None, params: Mapping[str, Any], us: np.ndarray, vs: np.ndarray,
                    s: SamplingSpec, threads: int, match_tol: float | None, shoot: Any, ball: Any) -> Registry:
    if attractors_from is None:
        return _seed(params, us, vs, s, threads, match_tol, shoot, ball)
    from .registry import Found

    found = json.loads(attractors_from.attrs["basins.registry"])
    return Registry(float(attractors_from.attrs["basins.match_tol"]), shoot, [Found(**f) for f in found], ball)


def _bar(progress: bool, total: int, initial: int) -> Any:
    from ...io.progress import progress_bar

    return progress_bar(total, "basins", unit="start", initial=initial, disable=not progress)


def _assemble(model: Any, u0: np.ndarray, v0: np.ndarray, raw: np.ndarray, periods: np.ndarray, reg: Registry,
              s: SamplingSpec, settings: Mapping[str, Any] | None, describe: str, wall: float,
              counts_in: tuple[int, int, int], errors: list[str]) -> xr.Dataset:
    """The Dataset: labels by basin size (the first ``fixed`` attractors, those of the scan this
    one zooms into, keep their labels), attractors with Newton's verdict, provenance."""
    from ...io.results import provenance

    resumed, n_tiles, fixed = counts_in
    counts = np.bincount(raw[raw >= 0], minlength=len(reg.found))
    order = list(range(fixed)) + sorted(range(fixed, len(reg.found)), key=lambda j: (
        -counts[j], reg.found[j].period, reg.found[j].array[:, 0].min()))
    relabel = np.empty(len(reg.found), dtype=np.int64)
    relabel[order] = np.arange(len(reg.found))
    labels = raw.astype(np.int64)
    labels[raw >= 0] = relabel[raw[raw >= 0]]
    attractors = [Attractor(int(relabel[j]), reg.found[j].period, reg.found[j].impacts,
                            orbit_points(reg.found[j].array[:, 0], reg.found[j].array[:, 1], reg.found[j].period),
                            int(counts[j])) for j in order]
    ds = xr.Dataset(coords={"u0": u0, "v0": v0})
    ds = with_attractors(ds, labels, attractors, reg.tol)
    ds["periods_run"] = (("u0", "v0"), periods, {"long_name": "forcing periods each start ran (early stop: fewer)"})
    shots = [reg.found[j].shot for j in order]
    ds["attractor_confirmed"] = ("attractor_index", np.array([bool(x.get("confirmed", False)) for x in shots]),
                                 {"long_name": "Newton shooting on the FMU converged to an attracting orbit there"})
    for name, key, what in (("attractor_newton_residual", "residual", "|F^M(z) - z| at Newton's last iterate"),
                            ("attractor_multiplier", "multiplier", "largest |multiplier| of the shot orbit")):
        ds[name] = ("attractor_index", np.array([float(x.get(key, np.nan)) for x in shots]), {"long_name": what})
    ds["attractor_sticks"] = ("attractor_index", np.array([reg.found[j].stuck for j in order]),
                              {"long_name": "the orbit sticks on the wall at a sample"})
    ds["attractor_ball_inside"] = ("attractor_index", np.array([bool(reg.found[j].ball.get("inside", False))
                                                                for j in order]),
                                   {"long_name": "every start of a grid over the tolerance balls around the orbit's "
                                                 "points reached it: one period within the tolerance labels a start"})
    confirm = reg.known().confirm
    ds["attractor_confirm_periods"] = ("attractor_index", np.array([int(confirm[j]) for j in order], dtype=np.int32),
                                       {"long_name": "consecutive periods on the orbit that recognise a start "
                                                     "(the scan's last tiles)"})
    attrs = provenance(settings or {}, model if hasattr(model, "sha256") else None, describe, wall)
    attrs.update(ds.attrs)
    attrs.update({"basins.kernel": "batch", "basins.tiles": n_tiles, "basins.tiles_resumed": resumed,
                  "basins.starts_per_s": float(labels.size / wall) if wall > 0 else 0.0,
                  "basins.periods_run_mean": float(periods.mean()),
                  "basins.full_periods": int(s.n_transient + s.n_samples),
                  "basins.registry": json.dumps([vars(reg.found[j]) for j in order]),
                  "basins.first_error": errors[0] if errors else ""})
    ds.attrs = attrs
    return ds


def with_zoom(ds: xr.Dataset, zoom: xr.Dataset) -> xr.Dataset:
    """``ds`` with the scan of a sub-rectangle (run with ``attractors_from=ds``, so its labels mean
    the same): ``attractor_zoom`` and ``periods_run_zoom`` on (u0_zoom, v0_zoom); attractors the
    zoom found beyond ``ds``'s are named in ``basins.zoom_attractors``."""
    ds = ds.copy()
    ds = ds.assign_coords(u0_zoom=zoom["u0"].values, v0_zoom=zoom["v0"].values)
    ds["attractor_zoom"] = (("u0_zoom", "v0_zoom"), zoom["attractor"].values,
                            {**zoom["attractor"].attrs, "long_name": "attractor reached from the zoom's starts"})
    ds["periods_run_zoom"] = (("u0_zoom", "v0_zoom"), zoom["periods_run"].values,
                              {"long_name": "forcing periods each start of the zoom ran"})
    ds.attrs["basins.zoom_attractors"] = zoom.attrs["basins.attractors"]
    ds.attrs["basins.zoom_starts_per_s"] = zoom.attrs["basins.starts_per_s"]
    return ds
