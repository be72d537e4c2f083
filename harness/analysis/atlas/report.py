"""report.md of an atlas: what was run, the classes and where each is stable, multistability and
chaos, and, with the chart's curves, where the two disagree and why."""
from __future__ import annotations

from typing import Any, Mapping

#: What each reason of a disagreement means (harness.analysis.atlas.curves).
REASONS = {
    "narrow": "another edge of the same window passes within the probe's reach: the window is narrower than "
              "the probe there (or the curve runs into a corner or turning point), so both probes fall outside it",
    "both sides": "the window's orbit is stable on both sides: the atlas puts the edge elsewhere by more than the "
                  "probe's offset (a curve continued wrongly, or one drawn between its points across a bend), or "
                  "an orbit of the same class other than the one continued is stable beyond it",
    "neither side": "the window's orbit is stable on neither side: the starts of the pixel inside went to other "
                    "attractors (its basin missed by every start; see 'multistable'), or the orbit is stable in a band "
                    "thinner than the probe",
}


def _range(r: Any) -> str:
    return "-" if r is None else f"[{r[0]:.6g}, {r[1]:.6g}]"


def atlas_report(res: Mapping[str, Any], command: str | None = None) -> str:
    """The report's text."""
    g, c, t = res["grid"], res["counts"], res["timing"]
    lines = ["# Atlas", "", f"`{command}`" if command else "", "",
             f"{g['p2'][2]} x {g['sigma'][2]} pixels: {res['param2']} in [{g['p2'][0]:.6g}, {g['p2'][1]:.6g}]"
             f"{' (geometric)' if g['p2_log'] else ''} x sigma in [{g['sigma'][0]:.6g}, {g['sigma'][1]:.6g}]"
             f"{' (geometric)' if g['sigma_log'] else ''}; {g['starts']} starts per pixel (half on a grid over the "
             f"wall-free orbit's box, half random, seed {g['seed']}); {res['route']}.", "",
             f"Each start ran until its stroboscopic orbit repeated (period M <= {res['run']['m_max']}, tolerance "
             f"{res['run']['tol']:g} x (1 + |u| + |v|)) or at most {res['run']['n_max']} periods; a periodic orbit's "
             "exponent is ln|mu|/M of its M-period map's exact Jacobian (the closed form's sensitivities), an "
             f"aperiodic start's that of a tangent vector over its last {res['run']['n_lyap']} periods, chaos above "
             f"{res['run']['chaos_lyapunov']:g} per period.", "",
             f"Wall time {t['wall_s']:.1f} s ({t['starts_per_s'] or 0:,.0f} starts/s, {t['periods_per_start']:.0f} "
             f"periods per start on average; {t['tiles']} tiles, {t['tiles_resumed']} resumed).", "",
             "## Classes", "", "| class | M | impacts | pixels stable | dominant | multistable | p2 range | sigma range |",
             "|---|---|---|---|---|---|---|---|"]
    for s in res["classes"]:
        lines.append(f"| {s['name']} | {s['M'] or '-'} | {'-' if s['impacts'] is None else s['impacts']} | {s['pixels']} "
                     f"| {s['dominant_pixels']} | {s['multistable_pixels']} | {_range(s['p2_range'])} | "
                     f"{_range(s['sigma_range'])} |")
    k = c["starts_by_kind"]
    lines += ["", f"Multistable pixels: {c['multistable_pixels']} of {c['pixels']} (at most {c['max_attractors']} "
              f"attractors in a pixel). Starts: {k['periodic']} periodic, {k['sticking']} sticking/chattering, "
              f"{k['chaotic']} chaotic, {k['aperiodic']} aperiodic without chaos, {k['escaped']} escaped, "
              f"{k['invalid']} invalid (inside a rigid wall), {k['failed']} failed."]
    if res.get("errors"):
        lines += ["", "First failures: " + "; ".join(res["errors"])]
    if "curves" in res:
        lines += _curve_lines(res["curves"])
    return "\n".join(lines) + "\n"


def _curve_lines(cv: Mapping[str, Any]) -> list[str]:
    lines = ["", "## The chart's curves against the atlas", "",
             f"{cv['count']} continued edge curves from `{cv['file']}`. Along each, every pixel, the atlas was probed "
             f"{cv['probe_offset_pixels']} pixels to either side across the curve: a curve agrees where its window's "
             "class (M, one impact; the wall-free orbit: period 1, no impact) is stable on exactly one side.", "",
             f"**{cv['disagree']} of {cv['checked']} probes disagree.** ({cv['past_closing']} pixels of curves continued "
             "past their window's closing in the chart were not probed: there they bound no stable orbit.)"]
    for why, n in sorted(cv["by_reason"].items(), key=lambda x: -x[1]):
        lines.append(f"- {why}: {n} -- {REASONS[why]}")
    if cv["disagreements"]:
        lines += ["", "| M | impacts | edge | p2 | sigma | why | one side | other side | multistable |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for d in cv["disagreements"][:60]:
            lines.append(f"| {d['M']} | {d['impacts']} | {d['side']} {d['kind']} | {d['p2']:.6g} | {d['sigma']:.6g} | "
                         f"{d['why']} | {', '.join(d['classes_one_side']) or '-'} | "
                         f"{', '.join(d['classes_other_side']) or '-'} | {'yes' if d['multistable'] else 'no'} |")
        if len(cv["disagreements"]) > 60:
            lines.append(f"\n({len(cv['disagreements']) - 60} more in atlas.json, `curves.disagreements`.)")
    return lines
