"""One row per orbit in the table of every window, and the scans' misclassified transients said so.

Several seeds reach one orbit: scan runs of one kind broken by a point classified otherwise, a
period-doubled child found by the scans and by branch switching at its parent's flip.  Their
windows have the same two edges, so they are one row (:func:`one_row_per_orbit`).  A seed Newton
cannot resolve, from a scan state that has not settled (critical slowing down next to a flip,
where the period-2M oscillation dies slowly), is run on from that state; where it reaches an
orbit that is listed, its row says so instead of "did not converge" (:func:`misclassified_transients`).
"""
from __future__ import annotations

import math
from typing import Any

__all__ = ["one_row_per_orbit", "misclassified_transients", "TRANSIENT_PERIODS"]

#: Periods a seed that Newton could not resolve is run on from the scan's state.
TRANSIENT_PERIODS = 2000


def _same_edge(a: Any, b: Any) -> bool:
    """Two edges located at one sigma (the located intervals' widths, at least 1e-6 (1 + |sigma|):
    CVODE's orbits locate an edge to ~1e-9, a bisection to its xtol)."""
    if a is None or b is None or a.kind != b.kind:
        return False
    if a.sigma is None or b.sigma is None:
        return a.sigma is None and b.sigma is None and a.kind == "range"
    return abs(a.sigma - b.sigma) <= max(1e-6 * (1.0 + abs(a.sigma)), a.bracket + b.bracket)


def one_row_per_orbit(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One result per orbit: families of one period and contact count whose windows have the same
    two edges are one orbit reached from several seeds (scan runs broken by a misclassified point,
    a child found by the scans and by branch switching); their ``found_by`` joined."""
    out: list[dict[str, Any]] = []
    for r in results:
        f = r["family"]
        twin = next((o for o in out if o.get("resolved") and r.get("resolved")
                     and (o["family"].M, o["family"].impacts) == (f.M, f.impacts)
                     and _same_edge(o["lower"], r["lower"]) and _same_edge(o["upper"], r["upper"])), None)
        if twin is None:
            out.append(r)
            continue
        g = twin["family"]
        g.found_by = sorted(set(g.found_by) | set(f.found_by))
        g.lo, g.hi = min(g.lo, f.lo), max(g.hi, f.hi)
    # a family Newton could not resolve from its seed, of a kind another seed resolved into a
    # window containing the seed's sigma: the same orbit (its row would only say "did not converge");
    # a child of branch switching that its shooting could not resolve: no scan saw it, nothing to say
    out = [r for r in out if r.get("resolved") or any(not b.startswith("branch switching") for b in r["family"].found_by)]
    return [r for r in out if r.get("resolved") or not any(
        o.get("resolved") and (o["family"].M, o["family"].impacts) == (r["family"].M, r["family"].impacts)
        and _inside(o, r["family"].seed_sigma) for o in out)]


def _inside(r: dict[str, Any], s: float) -> bool:
    lo, hi = r["lower"], r["upper"]
    a = -math.inf if lo is None or lo.sigma is None else lo.sigma
    b = math.inf if hi is None or hi.sigma is None else hi.sigma
    return a <= s <= b


def misclassified_transients(smap: Any, results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Each unresolved family run on :data:`TRANSIENT_PERIODS` periods from its scan state at its
    seed; where the flow then sits on a resolved window's orbit of another kind holding that sigma,
    or on no period at all, the result says so: ``transient_of`` the (M, k) reached or "not
    periodic", the row a transient the scans misclassified."""
    from ...dynamics.maps.classify import classify_orbit
    from ...dynamics.maps.sampling import strobe

    for r in results:
        if r.get("resolved"):
            continue
        f = r["family"]
        try:
            st = strobe(smap.sim, {**smap.params, "sigma": float(f.seed_sigma)}, tuple(map(float, f.seed)),
                        theta=smap.theta, n_transient=TRANSIENT_PERIODS, n_samples=48)
        except Exception:  # a run the FMU refuses: the row keeps its "did not converge"
            continue
        c = classify_orbit(st.u, st.v, st.impacts)
        if c.period <= 0:
            # Newton finds no such orbit there and the flow does not settle on any period: the
            # scans' classification was a transient (the flow there is chaotic or of a longer period)
            r["transient_of"] = "not periodic"
            r["transient_periods"] = TRANSIENT_PERIODS
            continue
        key = (int(c.period), int(c.impacts))
        if key == (f.M, f.impacts):
            continue
        if any(o.get("resolved") and (o["family"].M, o["family"].impacts) == key and _inside(o, f.seed_sigma)
               for o in results):
            r["transient_of"] = key
            r["transient_periods"] = TRANSIENT_PERIODS
    return results
