"""Edges that theory says coincide: a period-doubled orbit is born at the flip of its parent.

The shooting finds each window's edges on its own, so the period-2M orbit's edge where it
collapses onto its parent ("period-halving") and the parent's flip are two bisections of one
point, each to its own tolerance; printed side by side they differ in the last digits, and the
coexistence table shows a spurious sliver between them.  :func:`reconcile` locates the point
once: where the two brackets overlap, both windows take the parent's flip (the bisection of the
multiplier -1, the sharper of the two); where they do not, both numbers stay and a warning
says by how much they differ and what their tolerances were.
"""
from __future__ import annotations

from typing import Any, Sequence

__all__ = ["reconcile", "warnings"]


def _bracket(row: dict[str, Any], side: int) -> tuple[float, float] | None:
    iv = (row.get("intervals") or [None, None])[side]
    if not iv or None in iv:
        return None
    return min(iv), max(iv)


def _pairs(rows: Sequence[dict[str, Any]]):
    """(parent, its flip side, child, the child's collapsing side) for each parent M/k with a
    flip and each window 2M/2k with a period-halving edge on the side facing it."""
    ok = [r for r in rows if r.get("resolved") and r.get("kinds")]
    for p in ok:
        for side in (0, 1):
            if p["kinds"][side] != "flip" or p[("lo", "hi")[side]] is None:
                continue
            for c in ok:
                if (c["M"], c["impacts"]) == (2 * p["M"], 2 * p["impacts"]) and c["kinds"][1 - side] == "period-halving":
                    yield p, side, c, 1 - side


def reconcile(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Give a period-doubled window's birth the parent's flip, or flag the two when they differ.

    ``rows`` is the table of every window (``ode_windows_all``), changed in place: a child's
    edge that matches takes the parent's value (``located_by`` says so).  Returns one record per
    pair: ``parent``, ``child`` ("M/k"), ``sigma`` (the flip), ``difference`` (child's own edge
    minus the flip), ``tolerance`` (the two brackets' half-widths together), ``agree``.
    """
    out = []
    for p, ps, c, cs in _pairs(rows):
        key = ("lo", "hi")
        flip, own = p[key[ps]], c[key[cs]]
        if own is None:
            continue
        bp, bc = _bracket(p, ps), _bracket(c, cs)
        tol = sum(0.5 * (b[1] - b[0]) for b in (bp, bc) if b is not None) or 0.0
        agree = bool(bp and bc and bp[0] <= bc[1] and bc[0] <= bp[1]) or abs(own - flip) <= tol
        rec = {"parent": f"{p['M']}/{p['impacts']}", "child": f"{c['M']}/{c['impacts']}", "sigma": flip,
               "difference": own - flip, "tolerance": tol, "agree": agree}
        if agree:
            c[key[cs]] = flip
            c.setdefault("located_by", {})[key[cs]] = f"the flip of period {p['M']} ({rec['parent']})"
        out.append(rec)
    return out


def warnings(records: Sequence[dict[str, Any]]) -> list[str]:
    """The report's warnings: coincident edges that differ by more than their tolerances."""
    return [f"Warning: the period-{r['child'].split('/')[0]} window ({r['child']}) should be born at the flip of "
            f"{r['parent']} (sigma = {r['sigma']:.8g}), but its own edge differs by {r['difference']:+.2g}, more than "
            f"the two tolerances together ({r['tolerance']:.2g}): one of the two brackets is wrong; rerun with a "
            "smaller --xtol." for r in records if not r["agree"]]
