"""Edges that theory says coincide: a period-doubled orbit is born at the flip of its parent, and
the wall-free orbit (1 + sigma) cos(2 pi t) - 1 grazes the wall at sigma = 0 exactly.

The shooting finds each window's edges on its own, so the period-2M orbit's edge where it
collapses onto its parent ("period-halving") and the parent's flip are two bisections of one
point, each to its own tolerance; printed side by side they differ in the last digits, and the
coexistence table shows a spurious sliver between them.  :func:`reconcile` locates the point
once: where the two brackets overlap, both windows take the parent's flip (the bisection of the
multiplier -1, the sharper of the two), and the wall-free window's graze becomes 0 where its
bracket holds 0; where not, the numbers stay and a warning says by how much they differ and what
their tolerances were.
"""
from __future__ import annotations

from typing import Any, Sequence

__all__ = ["reconcile", "warnings"]

#: Round-off of the march and bisection in sigma (an even march from -0.3 lands on 1.4e-16, not 0):
#: two brackets this close still hold the same point.
_ROUND_OFF = 1e-12


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


def reconcile(rows: Sequence[dict[str, Any]], accuracy: float = 0.0) -> list[dict[str, Any]]:
    """Give a period-doubled window's birth the parent's flip, and the wall-free window's graze
    sigma = 0, or flag the two numbers when they differ by more than their tolerances.

    ``rows`` is the table of every window (``ode_windows_all``), changed in place: an edge that
    matches takes the shared value (``located_by`` says so).  Returns one record per pair:
    ``what`` (in words), ``edge`` ("M/k lo|hi"), ``sigma`` (the shared value), ``difference``
    (the edge's own bisection minus it), ``tolerance`` (the brackets' half-widths together),
    ``agree``.  ``accuracy`` (in sigma) is added to every tolerance: the location error of the
    solver's orbits (0 for the closed form; CVODE's ~1e-9 moves a root by that much whatever the
    width of its bracket), so a birth at its parent's flip is one point under both solvers.
    """
    key = ("lo", "hi")
    out = []
    for p, ps, c, cs in _pairs(rows):
        flip, own = p[key[ps]], c[key[cs]]
        if own is None:
            continue
        bp, bc = _bracket(p, ps), _bracket(c, cs)
        slack = _ROUND_OFF + accuracy
        tol = sum(0.5 * (b[1] - b[0]) for b in (bp, bc) if b is not None) + slack
        agree = bool(bp and bc and bp[0] <= bc[1] + slack and bc[0] <= bp[1] + slack) or abs(own - flip) <= tol
        out.append(_settle(c, cs, flip, own, tol, agree,
                           f"the flip of period {p['M']} ({p['M']}/{p['impacts']})"))
    for r in rows:  # the wall-free orbit (1 + sigma) cos(2 pi t) - 1 touches the wall at sigma = 0
        if r.get("resolved") and r["impacts"] == 0 and r["hi"] is not None and r["kinds"][1] == "graze":
            b = _bracket(r, 1)
            tol = (0.5 * (b[1] - b[0]) if b else 0.0) + _ROUND_OFF + accuracy
            slack = _ROUND_OFF + accuracy
            agree = bool(b and b[0] - slack <= 0.0 <= b[1] + slack) or abs(r["hi"]) <= tol
            out.append(_settle(r, 1, 0.0, r["hi"], tol, agree, "sigma = 0, where the wall-free orbit grazes"))
    return out


def _settle(row: dict[str, Any], side: int, value: float, own: float, tol: float, agree: bool,
            what: str) -> dict[str, Any]:
    """Record one coincidence; where it holds, the edge takes the shared value."""
    name = ("lo", "hi")[side]
    if agree:
        row[name] = value
        row.setdefault("located_by", {})[name] = what
    return {"what": what, "edge": f"{row['M']}/{row['impacts']} {name}", "sigma": value, "difference": own - value,
            "tolerance": tol, "agree": agree}


def warnings(records: Sequence[dict[str, Any]]) -> list[str]:
    """The report's warnings: coincident edges that differ by more than their tolerances."""
    return [f"Warning: the {'lower' if r['edge'].endswith('lo') else 'upper'} edge of window {r['edge'].split()[0]} "
            f"should be {r['what']} (sigma = {r['sigma']:.8g}), but its own bisection differs by "
            f"{r['difference']:+.2g}, more than the tolerances together ({r['tolerance']:.2g}): one bracket is wrong; "
            "rerun with a smaller --xtol." for r in records if not r["agree"]]
