"""What ``windows`` says in words, derived from the tables it prints and nowhere else: the
coexisting attractors (:func:`coexistence`, from the table of every window), the facts a summary
states (:func:`facts`: the highest period per source, where period adding stops, the closest map
and by how much) and the sentences (:func:`summary_lines`).

A summary written separately from its table drifts from it (a verdict that "the maps miss
windows" above identical rows); here each sentence is a format of one fact, and each fact a
function of the tables' data, so that a test can recompute every one from the report's JSON.
"""
from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

__all__ = ["attractor_label", "coexistence", "facts", "summary_lines", "highest_period", "fmt_sigma"]


def fmt_sigma(x: float | None, open_side: str = "") -> str:
    """A sigma for people: 6 significant digits, a tiny round-off shown as 0, None as the side of
    the search range it lies beyond."""
    if x is None:
        return f"{open_side} the search range".strip() if open_side else "beyond the search range"
    return "0" if abs(x) < 1e-13 else f"{x:.6g}"


def attractor_label(M: int, impacts: int) -> str:
    """'period 1, no impact (wall-free)', 'period 3, 1 impact', ..."""
    if impacts == 0:
        return f"period {M}, no impact (wall-free)"
    return f"period {M}, {impacts} impact{'s' if impacts > 1 else ''}"


def coexistence(rows: Sequence[Mapping[str, Any]], search: tuple[float, float]) -> list[dict[str, Any]]:
    """The sigma intervals where two or more of the ODE's stable windows overlap.

    Parameters
    ----------
    rows : list of dict
        The table of every window (``ode_windows_all``: M, impacts, lo, hi, resolved); an edge
        None lies beyond the search range.
    search : (float, float)
        The shooting's search range (where an open window is taken to end).

    Returns
    -------
    list of dict
        ``{"lo", "hi", "attractors": [labels], "keys": ["M/k", ...]}``, in increasing sigma; an
        end None: the overlap goes on beyond the search range.
    """
    wins = _windows(rows)
    ends = sorted({search[0], search[1], *[x for w in wins for x in w[:2] if x is not None]})
    out: list[dict[str, Any]] = []
    for a, b in zip(ends[:-1], ends[1:]):
        mid = 0.5 * (a + b)
        here = [w for w in wins if (w[0] is None or w[0] < mid) and (w[1] is None or mid < w[1])]
        keys = sorted({w[2] for w in here}, key=lambda k: tuple(int(x) for x in k.replace("#", "/").split("/")))
        if len(keys) < 2:
            continue
        labels = [next(w[3] for w in here if w[2] == k) for k in keys]
        if out and out[-1]["keys"] == keys and out[-1]["hi"] == a:
            out[-1]["hi"] = b
        else:
            out.append({"lo": a, "hi": b, "keys": keys, "attractors": labels})
    for c in out:  # an overlap reaching the search range's end goes on beyond it
        c["lo"] = None if c["lo"] == search[0] and _open_below(wins, c["keys"]) else c["lo"]
        c["hi"] = None if c["hi"] == search[1] and _open_above(wins, c["keys"]) else c["hi"]
    return out


def _windows(rows: Sequence[Mapping[str, Any]]) -> list[tuple]:
    """(lo, hi, key, label) per resolved window: an attractor each, so that two orbits of one kind
    (period, impacts) are two keys ("2/1#1", "2/1#2") and two labels ("..., orbit 1")."""
    res = [r for r in rows if r.get("resolved")]
    kinds = [f"{r['M']}/{r['impacts']}" for r in res]
    out, seen = [], {}
    for r, k in zip(res, kinds):
        label = attractor_label(r["M"], r["impacts"])
        if kinds.count(k) > 1:
            seen[k] = seen.get(k, 0) + 1
            k, label = f"{k}#{seen[k]}", f"{label}, orbit {seen[k]}"
        out.append((r["lo"], r["hi"], k, label))
    return out


def _open_below(wins: list, keys: list[str]) -> bool:
    return all(any(w[2] == k and w[0] is None for w in wins) for k in keys)


def _open_above(wins: list, keys: list[str]) -> bool:
    return all(any(w[2] == k and w[1] is None for w in wins) for k in keys)


def highest_period(windows: Mapping[int, Any]) -> int | None:
    """The highest M with a window in the table (any window shown, open ends included)."""
    Ms = [int(M) for M, w in windows.items() if w is not None]
    return max(Ms) if Ms else None


def facts(res: Mapping[str, Any], variants: Sequence[str]) -> dict[str, Any]:
    """Every fact the summary states, computed from the result's tables.

    ``highest``: source -> highest period with a stable maximal window (None: no window);
    ``stop``: where period adding stops (None: not before the scan limit, or not asked);
    ``closest``: the applicable map variant with the smallest largest edge difference, ``gap`` that
    difference, ``width`` the narrowest ODE window it was compared on (an agreement is a gap far
    below it); ``coexistence`` as :func:`coexistence`.
    """
    applies = res.get("map_applicability", {})
    wins = res["windows"]
    highest = {k: highest_period(w) for k, w in wins.items()}
    score = {k: v for k, v in res.get("max_abs_difference_to_ode", {}).items() if applies.get(k) is None}
    finite = {k: v for k, v in score.items() if v is not None and math.isfinite(v)}
    closest = min(finite, key=finite.get) if finite else None
    widths = [w[1] - w[0] for w in wins["ode"].values() if w is not None and None not in (w[0], w[1])]
    return {"highest": highest, "stop": res.get("period_adding_stop"),
            "closest": closest, "gap": finite.get(closest) if closest else None,
            "width": min(widths) if widths else None, "applies": [k for k in variants if applies.get(k) is None],
            "coexistence": res.get("coexistence", []), "M_auto": res["parameters"].get("M_max") == "auto",
            "M_limit": res["parameters"].get("M_scan_limit")}


def summary_lines(res: Mapping[str, Any], labels: Mapping[str, str], variants: Sequence[str]) -> list[str]:
    """The summary, one sentence per fact of :func:`facts`."""
    f = facts(res, variants)
    h = f["highest"]
    lines = [_closest_line(f, labels, res)]
    lines.append("Highest period with a stable maximal window (one impact per period): ODE "
                 + (f"M = {h['ode']}" if h["ode"] else "none") + "".join(
                     f", {labels[k]} " + (f"M = {h[k]}" if h[k] else "none") if k in f["applies"] else
                     f", {labels[k]} n/a" for k in variants) + ".")
    above = sorted(int(M) for M, w in res["windows"]["ode"].items() if w is not None and f["stop"] is not None
                   and int(M) > f["stop"] + 1)
    if f["M_auto"] and above:  # windows beyond the gap: the gap is not where period adding ends
        lines.append(f"--M-max auto: no stable maximal window at M = {f['stop']} and M = {f['stop'] + 1}, but at M = "
                     f"{', '.join(map(str, above))}: the periods of the windows are not consecutive here.")
    elif f["M_auto"]:
        stop = f["stop"]
        lines.append("--M-max auto: period adding does not start: no stable maximal window at M = 1 or 2 in the "
                     "searched range." if stop == 1 else
                     f"--M-max auto: period adding truncates at M = {stop}: no stable maximal window at M = {stop} "
                     f"and M = {stop + 1}." if stop is not None else
                     f"--M-max auto: period adding did not truncate up to the scan's limit M = {f['M_limit']}.")
    for c in f["coexistence"]:
        lines.append(f"Coexisting attractors for sigma in ({fmt_sigma(c['lo'], 'below')}, "
                     f"{fmt_sigma(c['hi'], 'above')}): " + "; ".join(c["attractors"]) + ".")
    if not f["coexistence"]:
        lines.append("No two stable attractors coexist in the searched range (as far as the scans saw).")
    from .edge_coincidence import warnings

    return lines + warnings(res.get("coincident_edges", []))


def _closest_line(f: Mapping[str, Any], labels: Mapping[str, str], res: Mapping[str, Any]) -> str:
    """Which map comes closest to the ODE, and whether that is agreement (its largest edge
    difference under a tenth of the narrowest ODE window compared), or why none was compared."""
    ode = res["windows"]["ode"]
    if not any(w is not None for w in ode.values()):
        return "The ODE has no stable maximal (one impact per period) window in the searched range; maps not compared."
    if not f["applies"]:
        return "No map applies to this oscillator (reasons above); ODE windows only."
    if f["closest"] is None:
        return ("No applicable map has a window at every period where the ODE has one (a missing window counts as "
                "an infinite difference).")
    gap, width, name = f["gap"], f["width"], labels[f["closest"]]
    if gap == 0.0:  # the same edges to the last digit: agreement, whatever the windows' widths
        return f"{name} agrees best with the ODE: its edges equal the ODE's (largest edge difference 0 in sigma)."
    if width is not None and gap <= 0.1 * width:
        return (f"{name} agrees best with the ODE: largest edge difference {gap:.2g} in sigma, under a tenth of "
                f"the narrowest ODE window compared ({width:.2g}).")
    return (f"{name} is the closest map, but does not agree: its largest edge difference to the ODE is {gap:.2g} "
            f"in sigma" + (f", more than a tenth of the narrowest ODE window ({width:.2g})." if width else "."))
