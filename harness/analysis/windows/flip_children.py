"""Period-doubled orbits found at their parents' flips (branch switching), as windows' seeds.

A window whose edge is a flip gives birth there to the period-2M orbit with twice its contacts
(supercritical: stable next to the flip, on the far side of it).  The scans see that orbit only
where it is wide enough and its transients die fast enough; the flip's eigenvector finds it
always: :func:`harness.dynamics.continuation.continue_orbit.doubled_orbit` solves it with its
amplitude along the eigenvector fixed, a little beyond the flip.  Each child that is stable there
and not already a window of the scans becomes a family of its own (``found_by`` says "branch
switching at the flip of M/k"), shot and continued to its edges like every other.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

__all__ = ["children_at_flips"]


def _has_child(results: Sequence[dict[str, Any]], M: int, k: int, flip: float, tol: float) -> bool:
    """A resolved window of period 2M with 2k contacts already has an edge at the flip."""
    for r in results:
        f = r["family"]
        if (f.M, f.impacts) != (2 * M, 2 * k) or not r.get("resolved"):
            continue
        if any(e is not None and e.sigma is not None and abs(e.sigma - flip) <= tol for e in (r["lower"], r["upper"])):
            return True
    return False


def children_at_flips(smap: Any, results: Sequence[dict[str, Any]], sigma_range: tuple[float, float],
                      M_max: int | None, family_type: Any, tried: set | None = None) -> list[Any]:
    """Families of the stable period-doubled orbits born at the flips of ``results`` (the shot
    families) that no window of ``results`` already starts at; ``family_type`` builds one
    (:class:`.ode_windows.Family`).  ``tried`` (updated) holds the flips already tried: each is
    tried once over the generations of a cascade."""
    tried = set() if tried is None else tried
    from ...dynamics.continuation.continue_orbit import doubled_orbit
    from ...dynamics.maps.periodic_map import PeriodMap, refine_orbit

    out = []
    for r in results:
        f = r["family"]
        if not r.get("resolved") or (M_max and 2 * f.M > M_max):
            continue
        for edge, outward in ((r["lower"], -1.0), (r["upper"], 1.0)):
            if edge is None or edge.kind != "flip" or edge.sigma is None or edge.state is None:
                continue
            s_f = float(edge.sigma)
            tol = 1e-6 * (1.0 + abs(s_f))
            if (f.M, f.impacts, round(s_f, 8)) in tried:
                continue
            tried.add((f.M, f.impacts, round(s_f, 8)))
            if _has_child(results, f.M, f.impacts, s_f, tol) or not sigma_range[0] <= s_f <= sigma_range[1]:
                continue
            pmap = PeriodMap(smap.sim, smap.params, "sigma", smap.theta)
            w, ev, ok, _ = refine_orbit(pmap, np.asarray(edge.state) - pmap.offset(s_f), s_f, f.M)
            if not ok:
                continue
            vals, vecs = np.linalg.eig(ev.J)
            e = np.real(vecs[:, int(np.argmin(np.abs(vals + 1.0)))])
            found = doubled_orbit(pmap, w, s_f, e / np.linalg.norm(e), f.M, 2 * f.impacts)
            if found is None:
                continue
            w2, s2 = found
            if (s2 - s_f) * outward <= 0.0:
                continue  # subcritical: the child lives where its parent is stable, itself unstable
            # a little further from the flip, where the child's multipliers are clear of +1
            s_in = s2 + outward * min(1e-3 * (1.0 + abs(s_f)), 100.0 * abs(s2 - s_f) + 1e-6)
            w3, ev3, ok3, _ = refine_orbit(pmap, w2, s_in, 2 * f.M)
            if not ok3 or not np.all(np.abs(np.linalg.eigvals(ev3.J)) < 1.0 - 1e-6):
                continue  # not stable there: no window to seed
            if int(ev3.contacts.sum()) != 2 * f.impacts:
                continue
            z = w3 + pmap.offset(s_in)
            child = family_type(2 * f.M, 2 * f.impacts, s_in, s_in, s_in, z,
                                [f"branch switching at the flip of {f.M}/{f.impacts}"], [(s_in, z)], f.geometric)
            child.born_at = (edge, "lower" if outward > 0 else "upper")  # its parent's flip, and the side facing it
            out.append(child)
    return out


def born_at_parent_flip(r: dict[str, Any]) -> dict[str, Any]:
    """A child's edge facing its parent is its birth at the parent's flip (the period-doubled
    orbit collapses onto its parent there): where the continuation of that side ended anywhere
    else (it ran on along the doubled parent, past the flip), that edge is the parent's flip,
    with the parent's bracket, and ``located`` says so."""
    born = getattr(r["family"], "born_at", None)
    if born is None or not r.get("resolved"):
        return r
    flip, side = born
    e = r[side]
    tol = 10.0 * max(abs((flip.bad if flip.bad is not None else flip.sigma) - flip.sigma), 1e-9 * (1.0 + abs(flip.sigma)))
    if e is not None and e.sigma is not None and e.kind == "period-halving" and abs(e.sigma - flip.sigma) <= tol:
        return r
    from dataclasses import replace

    r = dict(r)
    r[side] = replace(flip, kind="period-halving", good=flip.bad, bad=flip.good, state=None,
                      multipliers=np.full(2, np.nan))
    located = list(r.get("located") or ["continuation", "continuation"])
    located[0 if side == "lower" else 1] = "the parent's flip (born there by branch switching)"
    r["located"] = located
    return r


def with_flip_children(smap: Any, results: list[dict[str, Any]], n: int, sigma_range: tuple[float, float],
                       M_max: int | None, family_cls: Any, shoot: Any) -> tuple[list[dict[str, Any]], int]:
    """``results`` with the stable period-doubled orbits born at their flips that no window
    starts at yet, shot like the others (``shoot(families) -> (results, n)``), generation after
    generation of a cascade (up to ``M_max``, at most 4 generations)."""
    tried: set = set()
    for _ in range(4):
        kids = children_at_flips(smap, results, sigma_range, M_max, family_cls, tried)
        if not kids:
            break
        more, k = shoot(kids)
        results, n = results + [born_at_parent_flip(r) for r in more], n + k
    results.sort(key=lambda r: (r["family"].M, r["family"].impacts, r["family"].lo))
    return results, n
