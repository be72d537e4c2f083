"""Global search: the attractors of one parameter set found afresh, not followed from a neighbour.

A scan carries one state from parameter value to value, so it finds the attractors its path
crosses; an attractor whose basin it never enters stays invisible (a period-7 orbit just below
grazing that takes 99 % of the basin, next to the wall-free orbit a scan started on).  Here, at
each parameter set, fresh starts spread over the state region the attractors occupy
(:class:`Region`: a grid plus random starts, :data:`DEFAULT_STARTS` by default) are iterated to
their attractors with the basin scans' machinery (:mod:`.kernel_scan`, :mod:`.registry`): a seed
run until its samples repeat or in full, the attractors it finds told apart by their stroboscopic
point sets (:func:`harness.dynamics.attractors.identity.hausdorff`), then the other starts with the
early stop on them, two rounds of each orbit, every start also stopping once its samples rule out a
period and no attractor can recognise it any more (docs/basins.md).  Each attractor found comes back
with its basin share: the fraction of the starts that reached it.

Two paths, as in ``basins``:

- ``"batch"``: the batch kernel (the FMU's closed form in C, all cores), for the linear contact
  law.  The closed form is the exact flow of the same ODE, so it finds the ODE's attractors
  whatever solver the caller shoots them with afterwards.
- ``"fmu"``: every start through the FMU (the caller's solver: CVODE, the nonlinear contact
  laws) in tiles on a process backend (no early stop), labelled by the same rules.

``"auto"`` takes the kernel where it applies (linear contact law) and the FMU otherwise.
The starts at a parameter set depend only on that set (the random generator is seeded from the
values), so two runs over different ranges search a common value alike.
"""
from __future__ import annotations

import hashlib
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from ...config import SamplingSpec
from ...dynamics.attractors.identity import ESCAPED, INVALID, NOT_PERIODIC, STICKING
from ...errors import HarnessInputError
from ...fmu import batch_kernel as bk
from .tiles import BasinTile, label_result

#: Fresh starts per parameter set (at least this many: the grid's side is rounded up).
DEFAULT_STARTS = 1000
#: Share of the starts on the grid (the rest uniformly at random in the region).
GRID_SHARE = 0.5
#: Starts per tile on the FMU path (one task of the process backend).
FMU_TILE = 50
#: Default matching tolerance, relative to the orbits' scale max(1, |u|, |v|): two periodic
#: orbits are one attractor when their point sets lie within it (Hausdorff, max norm).
MATCH_REL = 1e-2
#: Starts of the seed run in full (the attractors it finds stop the other starts early).
SEED_STARTS = 32
PATHS = ("auto", "batch", "fmu")
#: On the kernel, the seed runs the whole transient and the other starts a quarter of it (at least
#: this many periods): most of them stop early on the seed's attractors, and the ones that do
#: not (chaos, long transients) cost the transient each.
SHORT_TRANSIENT = 50


@dataclass(frozen=True)
class Region:
    """A rectangle of the state plane (u, v) at the section, where the starts are spread."""

    u_lo: float
    u_hi: float
    v_lo: float
    v_hi: float

    def __post_init__(self) -> None:
        if not (all(math.isfinite(x) for x in (self.u_lo, self.u_hi, self.v_lo, self.v_hi))
                and self.u_lo < self.u_hi and self.v_lo < self.v_hi):
            raise HarnessInputError("region", f"needs finite u_lo < u_hi and v_lo < v_hi, got {self}")

    @classmethod
    def around_orbits(cls, sigma: float, theta: float, rigid: bool, points: np.ndarray | None = None,
                      widen: float = 1.5) -> "Region":
        """The wall-free orbit's range at ``sigma`` (u in [-2 - sigma, sigma], v within
        2 pi (1 + sigma)), widened ``widen`` times about its centre, and grown to hold
        ``points`` (the attractors seen there, (n, 2)) with a tenth of their extent to spare.
        A rigid wall keeps the starts outside it (u < 0)."""
        a = 1.0 + abs(sigma)
        u_lo, u_hi, v_lo, v_hi = -1.0 - widen * a, -1.0 + widen * a, -widen * 2.0 * math.pi * a, widen * 2.0 * math.pi * a
        if points is not None and len(points):
            p = np.asarray(points, dtype=float).reshape(-1, 2)
            p = p[np.all(np.isfinite(p), axis=1)]
            if p.size:
                pad = 0.1 * np.maximum(p.max(axis=0) - p.min(axis=0), 1e-3)
                u_lo, v_lo = min(u_lo, p[:, 0].min() - pad[0]), min(v_lo, p[:, 1].min() - pad[1])
                u_hi, v_hi = max(u_hi, p[:, 0].max() + pad[0]), max(v_hi, p[:, 1].max() + pad[1])
        if rigid:
            u_hi = min(u_hi, -1e-9)  # a start inside the rigid wall is refused
        return cls(float(u_lo), float(u_hi), float(v_lo), float(v_hi))


def seed_of(params: Mapping[str, Any]) -> int:
    """The random generator's seed: a hash of the parameter values, so that a parameter set is
    searched from the same starts whichever range it was asked within."""
    text = repr(sorted((str(k), float(v)) for k, v in params.items() if isinstance(v, (int, float))))
    return int.from_bytes(hashlib.sha256(text.encode()).digest()[:8], "little")


def spread_starts(region: Region, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` or a few more starts: a square grid over the region (``GRID_SHARE`` of them, its
    edges half a cell inside) and uniform random ones."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise HarnessInputError("starts", f"must be an integer >= 1, got {n!r}")
    side = max(1, int(math.ceil(math.sqrt(GRID_SHARE * n))))
    cu = region.u_lo + (np.arange(side) + 0.5) * (region.u_hi - region.u_lo) / side
    cv = region.v_lo + (np.arange(side) + 0.5) * (region.v_hi - region.v_lo) / side
    U, V = np.meshgrid(cu, cv, indexing="ij")
    rest = max(0, n - side * side)
    rng = np.random.default_rng(seed)
    ru = rng.uniform(region.u_lo, region.u_hi, rest)
    rv = rng.uniform(region.v_lo, region.v_hi, rest)
    return np.concatenate([U.ravel(), ru]), np.concatenate([V.ravel(), rv])


@dataclass
class FoundAttractor:
    """A periodic attractor the search reached: period, wall entries per period, its points in
    time order (the last sample last), the wall entries of the period ending on each point,
    whether it sticks, and its basin: starts that reached it and their share of all starts."""

    period: int
    impacts: int
    points: np.ndarray
    entries: list[int]
    stuck: bool
    starts: int
    share: float

    @property
    def key(self) -> str:
        return f"{self.period}/{self.impacts}"


@dataclass
class SearchResult:
    """The search at one parameter set: its attractors by basin share, and the other starts."""

    params: dict[str, Any]
    n_starts: int
    region: Region
    attractors: list[FoundAttractor]
    other: dict[str, int] = field(default_factory=dict)
    match_tol: float = 0.0
    path: str = "batch"
    wall_s: float = 0.0


def choose_path(path: str, params: Mapping[str, Any]) -> str:
    """"batch" or "fmu" for ``path`` ("auto": the kernel unless the contact law is nonlinear)."""
    if path not in PATHS:
        raise HarnessInputError("path", f"must be one of {', '.join(PATHS)}, got {path!r}")
    nonlinear = int(float(params.get("contact", 0) or 0)) != 0
    if path == "batch" and nonlinear:
        raise HarnessInputError("path", "the batch kernel is the closed form of the linear contact law; "
                                "a nonlinear contact law needs the fmu path")
    if path == "auto":
        return "fmu" if nonlinear else "batch"
    return path


def _fmu_tile(tile: BasinTile, source: Any, progress: Any = None) -> dict[str, Any]:
    """A tile of starts through the FMU (any solver, any contact law), labelled as a kernel
    tile is (:func:`.tiles.label_result`): run in full, no early stop."""
    from ...dynamics.maps.sampling import sample_periods
    from ...errors import FmuRejectedInput
    from ...fmu.simulator import simulator_for

    s, n = tile.sampling, tile.u0.size
    sim = simulator_for(source)
    res = bk.BatchResult(np.full(n, -1, np.int32), np.zeros(n, np.int32), np.zeros(n, np.int32),
                         np.full((n, s.n_samples), np.nan), np.full((n, s.n_samples), np.nan),
                         np.full((n, s.n_samples), -1, np.int32), np.zeros((n, s.n_samples), np.uint8), "")
    for i in range(n):
        try:
            sim.start(tile.params, s.theta, (float(tile.u0[i]), float(tile.v0[i])))
            got = sample_periods(sim, s.n_transient, s.n_samples)
        except FmuRejectedInput:
            res.status[i] = bk.INVALID
            continue
        res.u[i], res.v[i], res.impacts[i] = got.u, got.v, got.impacts
        res.periods[i] = s.n_transient + s.n_samples
    return {"index": tile.index, **label_result(res, s, tile.known)}


def _run_fmu(params: dict[str, Any], us: np.ndarray, vs: np.ndarray, s: SamplingSpec, match_tol: float,
             fmu: Any, workers: int | None) -> tuple[np.ndarray, Any]:
    from ..backends import make_backend
    from .registry import Registry

    if fmu is None:
        raise HarnessInputError("fmu", "the fmu path of the global search needs an FMU")
    reg = Registry(match_tol)
    tiles = {k: BasinTile(k, us[a: a + FMU_TILE], vs[a: a + FMU_TILE], params, s, reg.known(), 1)
             for k, a in enumerate(range(0, us.size, FMU_TILE))}
    labels = np.full(us.size, NOT_PERIODIC, dtype=np.int32)
    be = make_backend("serial" if workers == 1 else "processes", workers)
    source = fmu.source() if hasattr(fmu, "source") else fmu

    def done(k: int, result: dict[str, Any]) -> None:
        a = k * FMU_TILE
        labels[a: a + FMU_TILE] = reg.merge(result)

    try:
        be.run(_fmu_tile, tiles, source, done)
    finally:
        be.close()
    return labels, reg


def global_search(params: Mapping[str, Any], sampling: SamplingSpec, region: Region,
                  n_starts: int = DEFAULT_STARTS, *, path: str = "auto", fmu: Any = None,
                  workers: int | None = None, match_tol: float | None = None,
                  seed: int | None = None) -> SearchResult:
    """The attractors reached from fresh starts over ``region`` at one parameter set.

    Parameters
    ----------
    params : mapping
        FMU parameters (sigma included).
    sampling : SamplingSpec
        Section phase, transient, samples and periodicity tolerance of each start.
    region : Region
        Where the starts are spread (:meth:`Region.around_orbits`).
    n_starts : int
        Starts (a grid plus random ones; the grid's side is rounded up).
    path : {"auto", "batch", "fmu"}
        The batch kernel (linear contact law) or every start through ``fmu`` (the solver in
        ``params``) on ``workers`` processes; "auto": the kernel where it applies.
    match_tol : float, optional
        Largest Hausdorff distance between two orbits of one attractor; default
        :data:`MATCH_REL` x the region's scale.
    seed : int, optional
        Of the random starts; default :func:`seed_of` the parameters.

    Returns
    -------
    SearchResult
        Attractors by decreasing basin share (shares of all starts), and the counts of starts
        that reached no periodic orbit (``other``: not periodic, sticking or chatter, invalid,
        escaped or failed).
    """
    t0 = time.perf_counter()
    params = dict(params)
    chosen = choose_path(path, params)
    us, vs = spread_starts(region, n_starts, seed_of(params) if seed is None else int(seed))
    scale = max(1.0, abs(region.u_lo), abs(region.u_hi), abs(region.v_lo), abs(region.v_hi)) / 1.5
    tol = float(match_tol) if match_tol is not None else MATCH_REL * scale
    if not (math.isfinite(tol) and tol > 0):
        raise HarnessInputError("match_tol", f"must be a finite number > 0, got {match_tol!r}")
    if chosen == "batch":
        from .kernel_scan import run_starts

        short = SamplingSpec(theta=sampling.theta, n_transient=max(SHORT_TRANSIENT, sampling.n_transient // 4),
                             n_samples=sampling.n_samples, tol=sampling.tol, max_period=sampling.max_period)
        labels, reg = run_starts(params, us, vs, sampling, workers or bk.default_threads(), tol, SEED_STARTS,
                                 short if sampling.n_transient > SHORT_TRANSIENT else sampling)
    else:
        labels, reg = _run_fmu(params, us, vs, sampling, tol, fmu, workers)
    counts = np.bincount(labels[labels >= 0], minlength=len(reg.found))
    found = [FoundAttractor(f.period, f.impacts, f.array, list(f.entries), bool(f.stuck), int(counts[j]),
                            float(counts[j] / us.size)) for j, f in enumerate(reg.found) if counts[j] > 0]
    found.sort(key=lambda a: (-a.starts, a.period, a.impacts))
    other = {name: int(np.sum(labels == code)) for code, name in (
        (NOT_PERIODIC, "not periodic"), (STICKING, "sticking or chatter"), (INVALID, "invalid"),
        (ESCAPED, "escaped or failed"))}
    return SearchResult(params, int(us.size), region, found, other, tol, chosen, time.perf_counter() - t0)


def global_search_over(name: str, values: Sequence[float], params: Mapping[str, Any], sampling: SamplingSpec,
                       region_of: Callable[[float], Region], n_starts: int = DEFAULT_STARTS, *,
                       path: str = "auto", fmu: Any = None, workers: int | None = None,
                       progress: bool = False) -> list[SearchResult]:
    """:func:`global_search` at every value of the parameter ``name`` (the others fixed), each
    over ``region_of(value)``: the global search of ``windows`` (over sigma) and of ``chart``
    (at each value of its second parameter, call :func:`global_search` per parameter set)."""
    from ...io.progress import progress_bar

    out = []
    bar = progress_bar(len(values), "global search", unit="value", disable=not progress)
    try:
        for x in values:
            out.append(global_search({**params, name: float(x)}, sampling, region_of(float(x)), n_starts, path=path,
                                     fmu=fmu, workers=workers))
            bar.update(1)
    finally:
        bar.close()
    return out


def search_parameter_set(params: Mapping[str, Any], theta: float, n_starts: int = DEFAULT_STARTS, *,
                         transient: int = 300, samples: int = 40, tol: float = 1e-6,
                         points: np.ndarray | None = None, path: str = "auto", fmu: Any = None,
                         workers: int | None = None) -> SearchResult:
    """:func:`global_search` with the defaults ``windows`` uses, for any parameter set (``chart``
    at a value of its second parameter): the region around the wall-free orbit at ``params``'
    sigma and the orbits ``points`` seen there, outside a rigid wall (``wall`` 2)."""
    sigma = float(params.get("sigma", 0.0))
    rigid = int(float(params.get("wall", 1))) == 2
    s = SamplingSpec(theta=theta, n_transient=transient, n_samples=samples, tol=tol)
    return global_search(params, s, Region.around_orbits(sigma, theta, rigid, points), n_starts, path=path, fmu=fmu,
                         workers=workers)
