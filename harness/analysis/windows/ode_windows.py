"""Windows of the ODE found from the ODE: attractors seen anywhere in the scanned sigma range,
each continued by Newton shooting on the FMU to both of its edges.

The maps play no part in where the ODE is examined, except as *additional* starts: a map window
that the scans did not see (narrower than the scan grid) is tried with the map's orbit as a
Newton guess, and a family found that way says so (``found_by = ["map-guided start"]``).

1. :func:`families_from_scans`: up and down scans of the FMU over the whole sigma grid give
   runs of grid points classified as period M with k impacts per period (k >= 1); runs of the
   same (M, k) that overlap are one family; the scan's state in the middle of the run is its seed.
2. :func:`shoot_family`: Newton on F^M(w) = w from the seed; an orbit belongs to the family when
   it converges, is stable, has exactly k wall entries per M periods and minimal period M.  The
   orbit is continued in sigma both ways (:mod:`.located_edges`, the walk of ``continue``) and the
   first event on each side that ends the window is its edge: a flip/fold on its test function,
   a graze on its defining quantity, to ~1e-9 in quick and full runs alike (``located`` says
   "continuation").  A side the continuation cannot settle (the branch lost, or stability or
   contacts changing without a located event) falls back on a march and bisection to ``xtol``
   (:func:`harness.dynamics.maps.shooting.window_edges`), and ``located`` says "bisection (why)".
3. :func:`orbit_edge_kind`: the fallback's kind: flip/fold/torus (a multiplier leaves the unit
   circle), graze (a wall entry more or fewer), period-halving (the orbit collapses
   onto a shorter period), lost (Newton found nothing, or an orbit of another period and contact
   count: the last good orbit iterated beyond says more).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from mapcheck.compare import equal_runs
from mapcheck.orbits import PeriodicOrbit

__all__ = ["Family", "families_from_scans", "minimal_period", "orbit_edge_kind", "shoot_family",
           "shoot_families"]


@dataclass
class Family:
    """Stable periodic orbits of period M with k impacts per period, seen over [lo, hi].

    Attributes
    ----------
    M, impacts : int
    lo, hi : float
        The sigma range in which the scans (or the start) saw it.
    seed_sigma : float
    seed : ndarray (2,)
        A state (u, v) at the section, on (or near) the orbit at ``seed_sigma``.
    found_by : list of str
    """

    M: int
    impacts: int
    lo: float
    hi: float
    seed_sigma: float
    seed: np.ndarray
    found_by: list[str] = field(default_factory=list)
    #: (sigma, (u, v)) of every scan point classified as this family: Newton guesses near it
    track: list[tuple[float, np.ndarray]] = field(default_factory=list)
    #: the scans' grid was geometric (sigma > 0); else evenly spaced (any sign of sigma)
    geometric: bool = True

    def guess(self, sigma: float, offset: Any, step: float) -> np.ndarray | None:
        """The scan's state nearest to ``sigma`` (in w = z - p(theta) coordinates); None outside
        the range the scans saw the family in (widened by one grid step: a ratio on a geometric
        grid, a difference on an even one): beyond it the state would belong to another sigma
        and Newton could land on a coexisting orbit."""
        inside = (self.lo / step <= sigma <= self.hi * step if self.geometric
                  else self.lo - step <= sigma <= self.hi + step)
        if not self.track or not inside:
            return None
        dist = (lambda t: abs(math.log(t[0] / sigma))) if self.geometric else (lambda t: abs(t[0] - sigma))
        s_k, z_k = min(self.track, key=dist)
        return np.asarray(z_k) - offset(s_k)

    @property
    def key(self) -> str:
        return f"{self.M}/{self.impacts}"


def families_from_scans(grid: np.ndarray, ds: Any, M_max: int | None = None,
                        geometric: bool = True) -> list[Family]:
    """Families of periodic attractors in the up/down scans (one per (M, k) and run), the
    wall-free orbit (k = 0 impacts, sigma < 0) included: a window like any other.

    Parameters
    ----------
    grid : ndarray
        The scans' sigma grid.
    ds : xarray.Dataset
        :func:`harness.runs.sweeps.run_sweep`'s result (``period``, ``orbit_impacts``, ``u``, ``v``
        over (sigma, direction, sample)).
    M_max : int, optional
        Highest period kept.
    geometric : bool
        Whether ``grid`` is geometric (the families' Newton guesses are looked up by ratio).
    """
    runs: list[Family] = []
    for d in [str(x) for x in ds["direction"].values]:
        sel = ds.sel(direction=d)
        per = np.asarray(sel["period"].values)
        imp = np.asarray(sel["orbit_impacts"].values)
        u, v = np.asarray(sel["u"].values), np.asarray(sel["v"].values)
        keep = (per > 0) & (imp >= 0) & ((per <= M_max) if M_max else True)
        for k, j in equal_runs(keep, per, imp):
            mid = (k + j) // 2
            runs.append(Family(int(per[k]), int(imp[k]), float(grid[k]), float(grid[j]), float(grid[mid]),
                               np.array([u[mid, 0], v[mid, 0]], dtype=float), [d],
                               [(float(grid[i]), np.array([u[i, 0], v[i, 0]], dtype=float)) for i in range(k, j + 1)],
                               geometric))
    merged: list[Family] = []
    for f in sorted(runs, key=lambda f: (f.M, f.impacts, f.lo)):
        last = merged[-1] if merged else None
        if last is not None and (last.M, last.impacts) == (f.M, f.impacts) and f.lo <= last.hi:
            if f.hi - f.lo > last.hi - last.lo:  # seed from the longer run
                last.seed_sigma, last.seed = f.seed_sigma, f.seed
            last.hi = max(last.hi, f.hi)
            last.track += f.track
            last.found_by = sorted(set(last.found_by) | set(f.found_by))
        else:
            merged.append(f)
    return merged


def minimal_period(orb: PeriodicOrbit, rtol: float = 1e-6) -> int:
    """The smallest d dividing M with z_{k+d} = z_k (an orbit of F^M may be one of F^d)."""
    z = np.asarray(orb.z)
    M = len(z)
    scale = max(1e-12, float(np.max(np.abs(z))))
    for d in range(1, M):
        if M % d == 0 and np.max(np.abs(np.roll(z, -d, axis=0) - z)) <= rtol * scale:
            return d
    return M


def orbit_edge_kind(orb: PeriodicOrbit | None, iterated_entries: int, M: int, impacts: int) -> str:
    """Why the family (period M, ``impacts`` per period) ends at an edge.

    ``orb`` is Newton's result just beyond the edge (None or not converged: nothing found;
    then ``iterated_entries``, the wall entries of the last good orbit run M periods there,
    says whether a contact appeared or vanished: a graze).
    """
    if orb is None or not orb.converged:
        if iterated_entries >= 0 and iterated_entries != impacts:
            return "graze"  # a contact appeared or vanished
        return "lost"
    n = int(np.sum(orb.contacts))
    if n != impacts and minimal_period(orb) < M:
        # Newton fell onto an orbit of a shorter period with other contacts (Figure 9's unstable
        # period-1 orbit, 2 impacts per 2 periods, reached from the period-2 window at sigma = 0.526,
        # Gamma = 48.9): not this family's continuation, so not a graze; the flow decides
        return orbit_edge_kind(None, iterated_entries, M, impacts)
    if n != impacts:
        return "graze"  # a contact appeared or vanished: its gap or entry velocity reached 0
    if minimal_period(orb) < M:
        return "period-halving"
    m = orb.multipliers[int(np.argmax(np.abs(orb.multipliers)))]
    if abs(m.imag) > 1e-9:
        return "torus"
    return "flip" if m.real < 0 else "fold"


def impact_velocity(smap: Any, orb: PeriodicOrbit, sigma: float) -> float | None:
    """v_c = sqrt(chi) of the orbit's (first) impact: the state at the section before the
    impacting period, propagated without the wall to t = n (the virtual state of the maps),
    chi = v^2 - 2 A~ u with A~ = (1 + sigma) A + sigma Omega^2 (docs/theory.md sections 3, 5)."""
    from mapcheck.coeffs import grazing_acceleration
    from mapcheck.compare import free_flight

    if not np.any(np.asarray(orb.contacts) > 0):
        return None  # the wall-free orbit: no impact
    j = int(np.argmax(np.asarray(orb.contacts) > 0))
    z = np.asarray(orb.z[j]) + smap.offset(sigma)
    nu, Om = float(smap.params["nu"]), float(smap.params["Omega"])
    u, v = free_flight(z, sigma, nu, Om, smap.theta, 1.0)
    chi = v * v - 2.0 * float(grazing_acceleration(sigma, Om, "tilde")) * u
    return math.sqrt(chi) if chi > 0 else 0.0


def _accept(M: int, impacts: int):
    def accept(orb: PeriodicOrbit) -> bool:
        return bool(orb.converged and orb.stable and int(np.sum(orb.contacts)) == impacts
                    and minimal_period(orb) == M)
    return accept


def shoot_family(smap: Any, fam: Family, sigma_range: tuple[float, float], xtol_rel: float,
                 grid_ratio: float, relative: bool = True, c: Any = None) -> dict[str, Any]:
    """Both edges of the family's window by Newton shooting on the FMU (a geometric march on a
    geometric grid, even steps on an even one: ``fam.geometric``).

    ``xtol_rel`` is relative to the seed's |sigma| (absolute when ``relative`` is False); the march
    step is a fraction of the window the scans saw (at least the scan grid's step ``grid_ratio``:
    a ratio or a difference), never the tolerance.
    """
    from ...dynamics.maps.shooting import MARCH_STEPS, window_edges, newton_for

    from ...dynamics.maps.shooting import good_orbit

    w0 = fam.seed - smap.offset(fam.seed_sigma)
    # Newton's steps are capped at its scale: near grazing the orbit lies within ~1e-2 of the
    # wall-free orbit (newton_for's scale), but an orbit far from grazing (an underdamped
    # oscillator at sigma ~ 2) is O(1) away and must be reachable in a few steps
    newton = newton_for(fam.seed_sigma)
    newton = {**newton, "scale": np.maximum(newton["scale"], np.abs(w0))}
    ok, orb = good_orbit(smap, fam.M, fam.seed_sigma, [w0], newton, _accept(fam.M, fam.impacts))
    if not ok or orb is None:
        return {"family": fam, "lower": None, "upper": None, "resolved": False}
    w0 = orb.z[0]
    from .located_edges import located_edges

    # the edges located by the continuation from the seed orbit (the same walk as ``continue``)
    (c_lo, c_hi), how, n_cont = located_edges(smap, fam.M, fam.impacts, fam.seed_sigma,
                                              w0 + smap.offset(fam.seed_sigma), sigma_range)
    base = {"family": fam, "resolved": True, "multipliers": orb.multipliers, "fmu_periods_continuation": n_cont,
            "v_c": impact_velocity(smap, orb, fam.seed_sigma), "located": how,
            "seed_state": [float(x) for x in w0 + smap.offset(fam.seed_sigma)]}
    if c_lo is not None and c_hi is not None:
        return {**base, "lower": c_lo, "upper": c_hi}
    sides = (c_lo is None, c_hi is None)
    if fam.geometric:
        width, step = math.log(max(fam.hi / fam.lo, grid_ratio)), math.log(grid_ratio)
    else:
        width, step = max(fam.hi - fam.lo, grid_ratio), grid_ratio
    # at most half a scan step: a larger step near an edge can jump onto a coexisting orbit
    dp = min(width / MARCH_STEPS, 0.5 * step)
    try:
        # the scans' own states are the fallback guesses: continuation near a graze can land on a
        # neighbouring orbit, and a state the scan reached on the family is a better start
        def guess_of(s: float) -> np.ndarray | None:
            # a maximal orbit of the A~ map (where it has one) first: near an orbit with one more
            # contact, Newton from it stayed on the maximal orbit where the scans' states did not
            # (Figure 9, M = 2 at sigma ~ 0.52); the ODE still decides (Newton on the FMU)
            if c is not None and fam.impacts == 1:
                from mapcheck.compare import maximal_orbit_section_guess

                z = maximal_orbit_section_guess(c, fam.M, s, smap.theta, "tilde")
                if z is not None and np.all(np.isfinite(z)):
                    return z - smap.offset(s)
            return fam.guess(s, smap.offset, grid_ratio)

        e_lo, e_hi = window_edges(smap, fam.M, fam.seed_sigma, w0, guess_of, sigma_range, dp,
                                  xtol_rel * (abs(fam.seed_sigma) if relative else 1.0), newton, fam.geometric,
                                  accept=_accept(fam.M, fam.impacts),
                                  kind_of=lambda o, n: orbit_edge_kind(o, n, fam.M, fam.impacts), sides=sides)
    except ValueError:
        return {"family": fam, "lower": None, "upper": None, "resolved": False}
    # a side the continuation did not locate: the march and bisection's edge, said so
    how = [h if e is not None else f"bisection ({h})" for h, e in zip(how, (c_lo, c_hi))]
    return {**base, "lower": c_lo if c_lo is not None else e_lo, "upper": c_hi if c_hi is not None else e_hi,
            "located": how}


def _shoot_task(source: Any, params: Mapping[str, Any], theta: float, fams: Sequence[Family],
                sigma_range: tuple[float, float], xtol_rel: float, grid_ratio: float,
                relative: bool, c: Any = None) -> tuple[list, int]:
    from ...dynamics.maps.shooting import StroboscopicMap
    from ...fmu.simulator import FmuSimulator

    smap = StroboscopicMap(FmuSimulator(source, instance_name="ode-windows"), params, theta)
    out = [shoot_family(smap, f, sigma_range, xtol_rel, grid_ratio, relative, c) for f in fams]
    return out, smap.evaluations + _continued_periods(out)


def _continued_periods(results: Sequence[Mapping[str, Any]]) -> int:
    """FMU periods the continuation ran (on its own map, beside the shooting's)."""
    return int(sum(r.get("fmu_periods_continuation", 0) for r in results))


def shoot_families(smap: Any, fams: Sequence[Family], sigma_range: tuple[float, float], xtol_rel: float,
                   grid_ratio: float, workers: int = 1, relative: bool = True,
                   c: Any = None) -> tuple[list[dict[str, Any]], int]:
    """:func:`shoot_family` for every family (in ``workers`` processes); returns (results,
    one-period FMU runs)."""
    if workers <= 1 or len(fams) <= 1:
        res = [shoot_family(smap, f, sigma_range, xtol_rel, grid_ratio, relative, c) for f in fams]
        return res, smap.evaluations + _continued_periods(res)
    import multiprocessing
    import os
    from concurrent.futures import ProcessPoolExecutor

    from ...io.children import init_child_process

    chunks = [list(fams[i::workers]) for i in range(workers)]
    results: list[dict[str, Any]] = []
    n = 0
    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                             initializer=init_child_process, initargs=(os.getpid(),)) as pool:
        futs = [pool.submit(_shoot_task, smap.sim.source, smap.params, smap.theta, ch, sigma_range, xtol_rel,
                            grid_ratio, relative, c) for ch in chunks if ch]
        for f in futs:
            r, k = f.result()
            results += r
            n += k
    results.sort(key=lambda r: (r["family"].M, r["family"].impacts, r["family"].lo))
    return results, n


def _map_started_families(smap: Any, c: Any, guide: Mapping[int, Any], seen: set[tuple[int, int]],
                          M_cap: int) -> list[Family]:
    """Families of maximal orbits the scans did not see, found by Newton from the map's orbit
    at the centre of the map's window (an extra start; the ODE decides whether it is there)."""
    from mapcheck.compare import maximal_orbit_section_guess

    from ...dynamics.maps.shooting import good_orbit, newton_for

    out = []
    for M, w in guide.items():
        if w is None or (M, 1) in seen or M > M_cap or w[0] is None:
            continue
        hi = w[1] if w[1] is not None else 2.0 * w[0]
        s0 = math.sqrt(w[0] * hi)
        z = maximal_orbit_section_guess(c, M, s0, smap.theta, "tilde")
        if z is None or not np.all(np.isfinite(z)):
            continue
        ok, orb = good_orbit(smap, M, s0, [z - smap.offset(s0)], newton_for(s0), _accept(M, 1))
        if ok and orb is not None:
            out.append(Family(M, 1, s0, s0, s0, orb.z[0] + smap.offset(s0), ["map-guided start"]))
    return out


def measure(smap: Any, grid: np.ndarray, ds: Any, sigma_range: tuple[float, float], xtol_rel: float,
            M_max: int | None, guide: Mapping[int, Any] | None = None, c: Any = None,
            workers: int = 1, relative: bool = True, routes: Any = None) -> dict[str, Any]:
    """The ODE's windows: families from the scans (plus map-guided starts for windows the
    scans missed), each continued to its edges (:mod:`.located_edges`; a side the continuation
    cannot settle is marched and bisected to ``xtol_rel``, and says so).

    Returns
    -------
    dict
        ``windows`` {M: (lo, hi)} of the maximal orbits (one impact per period; the widest
        window per M), ``kinds``, ``brackets`` (widths of the located intervals), ``intervals``
        ((inside end, outside end) per edge), ``unresolved``, ``multipliers_at_lower_edge``,
        ``xtol`` {M: absolute tolerance of the fallback bisection}, ``all``: every family's
        window (any number of impacts) as a list of dicts, each with ``located`` [lower, upper]
        ("continuation", or "bisection (why the continuation did not)"), ``fmu_periods``.
    """
    geometric = bool(grid[0] > 0)  # an even grid reaching sigma <= 0 is marched in even steps
    # ``routes`` (:class:`.routes.Routes`): every route's orbits told apart by their points
    fams = families_from_scans(grid, ds, M_max, geometric) if routes is None else routes.families(geometric)
    if guide:
        cap = M_max or max([f.M for f in fams if f.impacts == 1] + [0]) + 2
        # a kind only the global search saw may be an orbit Newton does not confirm: the map's start still runs
        for f in _map_started_families(smap, c, guide, {(f.M, f.impacts) for f in fams
                                                        if f.found_by != ["global search"]}, cap):
            if sigma_range[0] <= f.seed_sigma <= sigma_range[1]:
                f.geometric = geometric  # marched like the scans' families
                fams.append(f)
    ratio = float(np.max(grid[1:] / grid[:-1])) if geometric else float(np.max(np.diff(grid)))
    results, n = shoot_families(smap, fams, sigma_range, xtol_rel, ratio, workers, relative, c)
    if routes is not None:  # tracks seen beyond their windows shot afresh, one orbit's families merged
        results, n = routes.refine(results, n, lambda fs: shoot_families(smap, fs, sigma_range, xtol_rel, ratio,
                                                                         workers, relative, c), xtol_rel)
    from .flip_children import with_flip_children
    from .orbit_rows import misclassified_transients, one_row_per_orbit

    results, n = with_flip_children(smap, results, n, sigma_range, M_max, Family, lambda fs: shoot_families(
        smap, fs, sigma_range, xtol_rel, ratio, 1, relative, c))

    results = misclassified_transients(smap, one_row_per_orbit(results))
    out: dict[str, Any] = {"windows": {}, "kinds": {}, "brackets": {}, "intervals": {}, "unresolved": {},
                           "multipliers_at_lower_edge": {}, "xtol": {}, "all": []}
    best: dict[int, dict[str, Any]] = {}
    for r in results:
        f, lo, hi = r["family"], r["lower"], r["upper"]
        entry = {"M": f.M, "impacts": f.impacts, "seen": [f.lo, f.hi], "found_by": f.found_by,
                 "seed_sigma": f.seed_sigma, "resolved": r["resolved"]}
        if routes is not None:
            entry["basin_share"] = routes.share(r)
        if r.get("transient_of"):  # not an orbit: the scans' state had not settled (.orbit_rows)
            entry["transient_of"] = r["transient_of"] if isinstance(r["transient_of"], str) else list(r["transient_of"])
            entry["transient_periods"] = r["transient_periods"]
        if r["resolved"]:
            entry.update({"lo": lo.sigma, "hi": hi.sigma, "kinds": [lo.kind, hi.kind],
                          "intervals": [[lo.good, lo.bad], [hi.good, hi.bad]],
                          "multipliers_inside": r.get("multipliers"), "v_c": r.get("v_c"),
                          "multipliers_near_lower_edge": lo.multipliers,
                          "multipliers_near_upper_edge": hi.multipliers,
                          "located": r.get("located"), "seed_state": r.get("seed_state"),
                          "xtol": xtol_rel * (abs(f.seed_sigma) if relative else 1.0)})
        out["all"].append(entry)
        if f.impacts == 1 and r["resolved"]:
            width = (hi.good if hi.good is not None else 0.0) - (lo.good if lo.good is not None else 0.0)
            if f.M not in best or width > best[f.M]["width"]:
                best[f.M] = {"width": width, "r": r}
    for M in sorted(best):
        lo, hi = best[M]["r"]["lower"], best[M]["r"]["upper"]
        out["windows"][M] = (lo.sigma, hi.sigma)
        out["kinds"][M] = (lo.kind, hi.kind)
        out["brackets"][M] = (lo.bracket, hi.bracket)
        out["intervals"][M] = ((lo.good, lo.bad), (hi.good, hi.bad))
        missing = [side for side, e in (("lower", lo), ("upper", hi)) if not e.resolved]
        if missing:
            out["unresolved"][M] = missing
        out["multipliers_at_lower_edge"][M] = lo.multipliers
        out["xtol"][M] = xtol_rel * (abs(best[M]["r"]["family"].seed_sigma) if relative else 1.0)
    out["fmu_periods"] = n
    out["derivatives"] = smap.derivatives
    return out


def period_adding_stop(windows: Mapping[int, Any], M_limit: int) -> int | None:
    """The first M >= 1 with no stable maximal window at M and M + 1 (period adding has
    truncated there), or None when it did not truncate up to ``M_limit``."""
    for M in range(1, M_limit):
        if windows.get(M) is None and windows.get(M + 1) is None:
            return M
    return None
