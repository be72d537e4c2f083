"""Newton shooting on the FMU's stroboscopic map: periodic orbits and window edges.

The map (:class:`.stroboscopic_map.StroboscopicMap`) is the FMU's one-period map at the
section phase ``theta``, in coordinates w = z - p(theta) relative to the wall-free orbit.

Edges of a stable window of maximal period-M orbits (one impact per period):

* lower (flip): the largest multiplier of D(F^M) leaves the unit circle;
* upper (graze): an extra contact appears in a non-impacting period (its maximal u
  reaches 0), detected by the FMU's impact counter.

Both are bracketed by marching in sigma from inside the window and bisected on "Newton
converges to a stable maximal orbit" (:func:`window_edges`).  An edge is *measured*: it is
reported as the midpoint of a bracket [last good sigma, first bad sigma] that the shooting
itself found and bisected to ``xtol``; the march step is set by the window's width, never
by ``xtol``, and is an irrational fraction of it, so the march does not land on the
guiding map's own edges.  An edge with no bracket (the search range ended first, or no
orbit was found to start from) is reported as unresolved (``sigma`` None, with the
interval searched), never as a number.  See docs/theory.md, "How window edges are found".  Newton itself is
:func:`mapcheck.orbits.solve_periodic_orbit`: with the FMU's own derivatives when it reports
them (one run per period gives the state and the chained exact Jacobian, so the multipliers
that decide the lower edges carry no difference error), else by central differences
(restarts of the FMU from perturbed states: ~5 times the runs per Newton iteration).
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import numpy as np

from mapcheck.orbits import PeriodicOrbit, edge_kind, solve_periodic_orbit

from .periodic_map import map_accuracy
from .stroboscopic_map import StroboscopicMap
from ...errors import FmuRejectedInput

__all__ = ["StroboscopicMap", "Edge", "NEWTON", "MARCH_STEPS", "good_orbit", "window_edges", "map_guided_windows", "newton_for"]

#: Width of a guide window in march steps (the step is width / MARCH_STEPS).
MARCH_STEPS = 6.3

#: Newton settings for the FMU map in w coordinates.  Scale (1e-2, 1e-1): the size of the
#: impacting orbit's offset from p.  rel_h = 1e-4 -> difference steps (1e-6, 1e-5): the
#: FMU's one-period error (~3e-11) then costs ~3e-5 in J, and the square-root curvature
#: (x ~ 1e-3 from grazing) ~ h^2 x^(-5/2) ~ 3e-5 as well.  tol 1e-9 -> |F^M(w) - w| < 1e-10.
#: max_iter 12: from a continued or map guess Newton converges in <= 6 iterations; a
#: failing solve (beyond an edge) should not cost more than that.
NEWTON: dict[str, Any] = {"tol": 1e-9, "rel_h": 1e-4, "scale": np.array([1e-2, 1e-1]), "max_iter": 12}


@dataclass
class Edge:
    """A window edge in sigma.

    Attributes
    ----------
    sigma : float or None
        The edge: midpoint of the final bracket [``good``, ``bad``] (width <= xtol).  None
        when the edge is unresolved (no bracket: ``kind`` "range" or "unresolved").
    kind : str
        "flip"/"fold"/"torus" (stability), "graze" (a contact more or fewer), "lost"
        (Newton found nothing beyond), "range" (no edge inside the search range),
        "unresolved" (no stable maximal orbit to start from).
    bracket : float
        Width of the final bracket, |bad - good| (for "range": the distance from ``good``
        to the end of the range).
    multipliers : ndarray
        Of the orbit at ``good``.
    good : float or None
        Last sigma where the shooting found a stable maximal orbit.
    bad : float or None
        First sigma beyond it where it did not (None: not bracketed).
    state : ndarray (2,) or None
        A section point (u, v) of the orbit at the edge, where the continuation located it (a
        flip's period-doubled orbit is sought from it).
    """

    sigma: float | None
    kind: str
    bracket: float
    multipliers: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))
    good: float | None = None
    bad: float | None = None
    state: np.ndarray | None = None

    @property
    def resolved(self) -> bool:
        """True when the edge was bracketed and bisected (``sigma`` is a number)."""
        return self.sigma is not None


def _rotate_to_impact(orb: PeriodicOrbit, M: int) -> np.ndarray:
    """The orbit point right after its impacting period (the continuation's anchor)."""
    return orb.z[(int(np.argmax(orb.contacts > 0)) + 1) % M]


def good_orbit(smap: StroboscopicMap, M: int, sigma: float, guesses: list[np.ndarray | None],
               newton: Mapping[str, Any] | None = None,
               accept: Callable[[PeriodicOrbit], bool] | None = None) -> tuple[bool, PeriodicOrbit | None]:
    """Newton from each guess: True with the first stable maximal period-M orbit (or one that
    ``accept`` takes), else False with the most informative failed orbit (a converged one)."""
    step = smap.at(sigma)
    dstep = smap.at_with_jacobian(sigma)
    failed: PeriodicOrbit | None = None
    ok_orbit = accept or (lambda o: o.maximal and o.stable)
    newton = dict(newton or NEWTON)
    # the residual target (tol times the largest scale) no finer than the solver resolves: with
    # CVODE the map's own error over M periods (1e-10 to 1e-9), not the closed form's rounding
    acc = map_accuracy(getattr(smap, "params", {}), M)
    newton["tol"] = max(float(newton["tol"]), acc / float(np.max(newton["scale"])))
    for g in guesses:
        if g is None:
            continue
        try:
            orb = solve_periodic_orbit(step, g, M, **newton, dstep=dstep)
        except FmuRejectedInput:
            # a Newton step put the start inside a rigid wall: no orbit from this guess
            continue
        if ok_orbit(orb):
            return True, orb
        if failed is None or (orb.converged and not failed.converged):
            failed = orb
    return False, failed


def window_edges(smap: StroboscopicMap, M: int, sigma_in: float, w_in: np.ndarray,
                 guess_of: Callable[[float], np.ndarray | None], sigma_range: tuple[float, float],
                 dp: float, xtol: float, newton: Mapping[str, Any] | None = None,
                 geometric: bool = False, accept: Callable[[PeriodicOrbit], bool] | None = None,
                 kind_of: Callable[[PeriodicOrbit | None, int], str] | None = None,
                 sides: tuple[bool, bool] = (True, True)) -> tuple[Edge | None, Edge | None]:
    """Lower and upper sigma-edges of the stable maximal period-M window containing
    ``sigma_in``.

    Parameters
    ----------
    smap : StroboscopicMap
    M : int
    sigma_in : float
        A sigma inside the window; ``w_in`` a guess of the orbit there (w coordinates).
    guess_of : callable
        sigma -> a second guess (e.g. from the A~(sigma) map), tried when continuing the
        last good orbit fails (Newton on a square-root map can jump to another branch).
    sigma_range : (float, float)
        Search limits; an edge not found inside is reported as ``Edge(None, "range")``.
    dp : float
        Marching step (smaller than the window; choose it from the window's width, not from
        ``xtol``).
    xtol : float
        Bisection tolerance in sigma: every bracket is bisected until narrower than this.
    newton : mapping, optional
        Settings of :func:`mapcheck.orbits.solve_periodic_orbit` (default :data:`NEWTON`).
    geometric : bool
        March by the factor exp(+-dp) instead of steps +-dp (windows at sigma -> 0).
    accept : callable, optional
        orbit -> True when it belongs to the window (default: a stable maximal orbit, one
        impact per period); e.g. a stable orbit with k impacts per period.
    kind_of : callable, optional
        (orbit beyond the edge or None, wall entries of the last good orbit iterated there)
        -> the edge's kind (default: :func:`mapcheck.orbits.edge_kind`, for maximal orbits).
    sides : (bool, bool)
        Which of (lower, upper) to search; a side not searched is returned as None (the other
        was located another way, :mod:`harness.analysis.windows.located_edges`).
    """
    ok, orb = good_orbit(smap, M, sigma_in, [w_in, guess_of(sigma_in)], newton, accept)
    if not ok or orb is None:
        raise ValueError(f"no stable maximal period-{M} orbit found at sigma = {sigma_in}")
    edges = []
    for direction, limit, wanted in ((-1.0, sigma_range[0], sides[0]), (+1.0, sigma_range[1], sides[1])):
        if not wanted:
            edges.append(None)
            continue
        search = _EdgeSearch(smap, M, direction, sigma_in, orb, guess_of, newton, accept)
        if not search.march(limit, dp, geometric):
            # no bracket inside the range: unresolved, never a number
            edges.append(Edge(None, "range", abs(limit - search.s_good), search.o_good.multipliers,
                              float(search.s_good), None))
            continue
        search.bisect(xtol)
        edges.append(search.edge(kind_of))
    return edges[0], edges[1]


class _EdgeSearch:
    """The search for one edge of a window, on one side of ``sigma_in``: the last sigma with a
    good orbit and the first without, and the last two good orbits for a secant predictor.

    Parameters
    ----------
    smap, M, guess_of, newton, accept
        As in :func:`window_edges`.
    direction : float
        -1 for the lower edge, +1 for the upper.
    s_good, o_good
        A sigma inside the window and the good orbit there.
    """

    def __init__(self, smap: StroboscopicMap, M: int, direction: float, s_good: float, o_good: PeriodicOrbit,
                 guess_of: Callable[[float], np.ndarray | None], newton: Mapping[str, Any] | None,
                 accept: Callable[[PeriodicOrbit], bool] | None) -> None:
        self.smap, self.M, self.direction = smap, M, direction
        self.guess_of, self.newton, self.accept = guess_of, newton, accept
        self.s_good, self.o_good = s_good, o_good
        self.s_bad: float | None = None
        self.o_bad: PeriodicOrbit | None = None
        # last two good (sigma, anchor) for a secant predictor: near a graze another periodic
        # orbit (with the extra contact) lies ~1e-4 away, so plain continuation over a step
        # of ~1e-4 in sigma can land on it; the secant's error is O(step^2)
        self.history = [(s_good, _rotate_to_impact(o_good, M))]

    def guesses(self, s: float) -> list:
        """Newton's starts at ``s``: the secant prediction, the last good orbit, the guide's."""
        anchor = _rotate_to_impact(self.o_good, self.M)
        out = []
        if len(self.history) >= 2:
            (s1, z1), (s2, z2) = self.history[-2], self.history[-1]
            if s2 != s1:
                out.append(z2 + (z2 - z1) * (s - s2) / (s2 - s1))
        else:
            # no secant yet: the orbit scaled with the forcing amplitude 1 + sigma.  Far above
            # grazing an impacting orbit lies O(sigma) from the wall-free one (w ~ (1 + sigma) c:
            # the oscillator is nearly scale-invariant), so the last orbit unchanged, a few per cent
            # away in sigma, can miss the wall for a whole period, where the map is the free linear
            # one and Newton jumps to its fixed point, the wall-free orbit (Figure 9's period 1 at
            # Gamma = 48.9, sigma = 16: "lost")
            out.append(anchor * (1.0 + s) / (1.0 + self.s_good))
        return out + [anchor, self.guess_of(s)]

    def probe(self, s: float) -> None:
        """Shoot at ``s``: it becomes the last good sigma or the first bad one."""
        ok, o = good_orbit(self.smap, self.M, s, self.guesses(s), self.newton, self.accept)
        if ok:
            self.s_good, self.o_good = s, o
            self.history.append((s, _rotate_to_impact(o, self.M)))
            self.history.sort(key=lambda e: self.direction * e[0])  # the two nearest the edge last
            del self.history[:-2]
        else:
            self.s_bad, self.o_bad = s, o

    def march(self, limit: float, dp: float, geometric: bool) -> bool:
        """Step towards ``limit`` until a sigma without a good orbit; False when the range ends
        first (the end of the range itself is tested before giving up)."""
        while self.s_bad is None:
            s_good = self.s_good
            s = s_good * math.exp(self.direction * dp) if geometric else s_good + self.direction * dp
            if (s - limit) * self.direction > 0:
                if s_good == limit:
                    return False
                s = limit
            self.probe(s)
        return True

    def bisect(self, xtol: float) -> None:
        """Bisect the bracket [s_good, s_bad] until narrower than ``xtol``."""
        while abs(self.s_bad - self.s_good) > xtol:
            self.probe(0.5 * (self.s_good + self.s_bad))

    def edge(self, kind_of: Callable[[PeriodicOrbit | None, int], str] | None) -> Edge:
        """The edge at the bracket's midpoint (a number the bisection produced, not a march point,
        which could be a guide's edge), with its kind."""
        s_good, s_bad, o_good, o_bad, M = self.s_good, self.s_bad, self.o_good, self.o_bad, self.M
        if kind_of is not None:
            # the last good orbit run M periods beyond the edge: its wall entries decide where
            # Newton found nothing there, or fell onto another orbit (the kind checks that)
            _, n_iter = self.smap.iterate(s_bad, _rotate_to_impact(o_good, M), M)
            kind = kind_of(o_bad, n_iter)
        else:
            kind = edge_kind(o_bad) if o_bad is not None else "lost"
            kind = "graze" if kind == "no-impact" else kind  # the impact vanished: a graze
            if kind == "lost":
                # Newton found no orbit beyond the edge: iterate the last good orbit there and
                # look at its contacts (an extra one in a non-impacting period: a graze)
                _, n = self.smap.iterate(s_bad, _rotate_to_impact(o_good, M), M)
                kind = "graze" if n != 1 else "lost"  # a contact appeared or vanished
        return Edge(0.5 * (s_good + s_bad), kind, abs(s_bad - s_good), o_good.multipliers,
                    float(s_good), float(s_bad))


def newton_for(sigma: float) -> dict[str, Any]:
    """Newton settings for orbits at forcing ``sigma``: the impact velocity scales like
    sqrt(chi) ~ sqrt(sigma), so below sigma = 0.1 the scale (and with it the difference
    steps) shrinks like sqrt(10 sigma) (Figure 1's windows accumulate at sigma -> 0; the
    steps must stay below the penetration ~ sigma); the residual target stays >= 1e-9
    absolute, above the FMU's own error near grazing."""
    # |sigma|: below sigma = 0 the wall-free orbit misses the wall by -sigma, the same scale
    shrink = min(1.0, (10.0 * max(abs(sigma), 1e-10)) ** 0.5)
    scale = np.array([1e-2, 1e-1]) * shrink
    tol = NEWTON["tol"] if shrink >= 1.0 else 1e-9 / float(scale.max())
    return {**NEWTON, "scale": scale, "tol": tol}


def _shoot_window(smap: StroboscopicMap, c: Any, M: int, w: tuple[float, float | None],
                  sigma_range: tuple[float, float], xtol: float, relative: bool) -> tuple[Edge, Edge]:
    """Both edges of the FMU's period-M window, started inside the map's window ``w``."""
    from mapcheck.compare import maximal_orbit_section_guess

    lo, hi = w
    hi = hi if hi is not None else 2.0 * lo  # no upper edge: start well above the flip

    def guess(s: float) -> np.ndarray | None:
        z = maximal_orbit_section_guess(c, M, s, smap.theta, "tilde")
        return None if z is None else z - smap.offset(s)

    s0 = 0.5 * (lo + hi)
    # The march step is set by the guide's window alone (several steps inside even a narrow
    # window), never by xtol.  MARCH_STEPS is not a half-integer, so s0 +- k dp never lands on
    # the guide's own edge (with 6 steps, s0 +- 3 dp was exactly lo or hi, and an edge that
    # the bisection never moved off that point was the map's number echoed).
    if relative:  # geometric: windows accumulating at sigma -> 0
        s0 = math.sqrt(lo * hi)
        dp, tol = math.log(hi / lo) / MARCH_STEPS, xtol * lo
    else:
        dp, tol = min(0.02, (hi - lo) / MARCH_STEPS), xtol
    try:
        return window_edges(smap, M, s0, guess(s0), guess, sigma_range, dp, tol, newton_for(s0), relative)
    except ValueError:
        # no stable maximal orbit at the guide's window centre: both edges unresolved
        return (Edge(None, "unresolved", float("nan"), good=None, bad=None),
                Edge(None, "unresolved", float("nan"), good=None, bad=None))


def _shoot_window_task(source: Any, params: Mapping[str, Any], theta: float, c: Any, M: int,
                       w: tuple[float, float | None], sigma_range: tuple[float, float], xtol: float,
                       relative: bool, derivatives: str = "auto") -> tuple[int, Edge, Edge, int]:
    """:func:`_shoot_window` in a worker process, on an FMU instance of its own."""
    from ...fmu.simulator import FmuSimulator

    smap = StroboscopicMap(FmuSimulator(source, instance_name=f"shoot-M{M}"), params, theta, derivatives)
    e_lo, e_hi = _shoot_window(smap, c, M, w, sigma_range, xtol, relative)
    return M, e_lo, e_hi, smap.evaluations


def map_guided_windows(smap: StroboscopicMap, c: Any, guide: Mapping[int, Any], sigma_range: tuple[float, float],
                       xtol: float | Mapping[int, float], relative: bool = False, workers: int = 1) -> dict[str, Any]:
    """ODE windows on the FMU for every period in ``guide`` (the map's windows).

    Newton shooting starts inside each map window from the map's own maximal orbit
    (:func:`mapcheck.compare.maximal_orbit_section_guess`: A~(sigma) variant, coefficients
    ``c``, the state at the FMU's section after the impact), and follows the orbit to both
    edges (:func:`window_edges`).  ``relative``: ``xtol`` is relative to the map window's
    lower edge and the marching is geometric (windows that accumulate at sigma -> 0, as in
    Figure 1).  ``xtol`` may be a mapping {M: xtol} (one tolerance per window, e.g. a
    fraction of its width).  ``workers`` > 1 shoots the windows in that many processes (the windows are
    independent; each process opens the FMU of ``smap``'s simulator).

    Returns
    -------
    dict
        ``windows`` {M: (lo, hi)} with each edge the midpoint of its bisected bracket, or
        None where unresolved (``windows[M]`` is None when neither edge is resolved);
        ``kinds`` {M: (kind_lo, kind_hi)}; ``brackets`` {M: (width_lo, width_hi)};
        ``intervals`` {M: ((good, bad), (good, bad))} the brackets themselves (bad None:
        not bracketed, the edge lies beyond ``good``); ``unresolved`` {M: [which edges]};
        ``multipliers_at_lower_edge``; ``fmu_periods`` (one-period FMU runs used).
    """
    out: dict[str, Any] = {"windows": {}, "kinds": {}, "brackets": {}, "intervals": {}, "unresolved": {},
                           "multipliers_at_lower_edge": {}}
    todo = {M: w for M, w in guide.items() if w is not None}
    tols = {M: float(xtol[M]) if isinstance(xtol, Mapping) else float(xtol) for M in todo}
    results: dict[int, tuple[Edge, Edge]] = {}
    evaluations = 0
    if workers > 1 and len(todo) > 1:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        # spawn, as the sweep pool does: the parent holds a loaded FMU library
        ctx = multiprocessing.get_context("spawn")
        from ...io.children import init_child_process
        from ...io.main_guard import require_main_guard

        require_main_guard("workers")  # before any worker re-imports an unguarded script

        # workers die with this process (SIGKILL included) and clean their temp folders
        with ProcessPoolExecutor(max_workers=min(workers, len(todo)), mp_context=ctx,
                                 initializer=init_child_process, initargs=(os.getpid(),)) as pool:
            futures = [pool.submit(_shoot_window_task, smap.sim.source, smap.params, smap.theta, c, M, w,
                                   sigma_range, tols[M], relative, smap.derivatives) for M, w in todo.items()]
            for f in futures:
                M, e_lo, e_hi, n = f.result()
                results[M] = (e_lo, e_hi)
                evaluations += n
    else:
        for M, w in todo.items():
            results[M] = _shoot_window(smap, c, M, w, sigma_range, tols[M], relative)
    for M, w in guide.items():
        if w is None:
            out["windows"][M] = None
            continue
        e_lo, e_hi = results[M]
        out["windows"][M] = None if not (e_lo.resolved or e_hi.resolved) else (e_lo.sigma, e_hi.sigma)
        out["kinds"][M] = (e_lo.kind, e_hi.kind)
        out["brackets"][M] = (e_lo.bracket, e_hi.bracket)
        out["intervals"][M] = ((e_lo.good, e_lo.bad), (e_hi.good, e_hi.bad))
        missing = [side for side, e in (("lower", e_lo), ("upper", e_hi)) if not e.resolved]
        if missing:
            out["unresolved"][M] = missing
        out["multipliers_at_lower_edge"][M] = e_lo.multipliers
    out["fmu_periods"] = smap.evaluations + evaluations
    out["derivatives"] = smap.derivatives  # "exact" (the FMU's) or "fd" (central differences)
    return out
