"""``windows --sigma-range`` below sigma = 0: the wall-free orbit is a window grazing at sigma = 0,
coexisting attractors are listed, and every summary line is derived from the tables.  Checked
against the exact flow (mapcheck.exact) and against the JSON tables the report prints."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from harness.cli.main import main
from tests.support.edges import ExactFlow

pytestmark = pytest.mark.slow  # four quick windows runs

CASES = {
    # rigid wall, r close to 1: a period-2 orbit (1 impact) coexists with the wall-free one below 0
    "rigid": ["--nu", "0.8", "--Omega", "2.5", "--r", "0.95", "--wall", "rigid", "--sigma-range=-0.3:0.3"],
    # underdamped, compliant wall: a period-3 orbit born below sigma = 0
    "soft": ["--nu", "0.3", "--Omega", "1.2", "--r", "0.8", "--wall", "compliant", "--Gamma", "10",
             "--sigma-range=-0.3:0.3"],
    # no maximal window at all in this range (nothing coexists: 250 fresh starts per sigma, where
    # the default 1000 took 6 of the run's 9 s, and as many again in its rerun below)
    "none": ["--nu", "0.3", "--Omega", "1.2", "--r", "0.8", "--wall", "compliant", "--Gamma", "10",
             "--global-starts", "250", "--sigma-range=-0.3:-0.1"],
}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Each case's windows run, once for the module: its JSON, report, arguments, folder, and per
    figure it wrote, whether each of its axes holds something (recorded as it is saved)."""
    from matplotlib.figure import Figure

    out = {}
    save = Figure.savefig
    for name, args in CASES.items():
        d = tmp_path_factory.mktemp(name)
        m_max = "auto" if name == "soft" else "4"  # auto: its summary line is checked too
        panels: dict[str, list[bool]] = {}

        def inspect(fig, path, *a, **kw):
            panels[str(path).rsplit("/", 1)[-1]] = [
                bool(ax.lines or ax.collections or ax.images or ax.patches or ax.texts) for ax in fig.axes]
            return save(fig, path, *a, **kw)

        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(Figure, "savefig", inspect)
            assert main(["windows", *args, "--M-max", m_max, "--quick", "--solver", "closed-form", "--workers", "1",
                         "--no-progress", "--out", str(d)]) == 0
        out[name] = (json.loads((d / "windows.json").read_text()), (d / "report.md").read_text(), args, d, panels)
    return out


def _flow(args: list[str]) -> ExactFlow:
    a = dict(zip(args[::2], args[1::2]))
    return ExactFlow(float(a["--nu"]), float(a["--Omega"]), float(a["--r"]), float(a.get("--Gamma", 10.0)), a["--wall"])


@pytest.mark.parametrize("case", list(CASES))
def test_the_wall_free_orbit_is_a_window_that_grazes_at_zero(runs, case) -> None:
    res, _, args, folder, _ = runs[case]
    free = [r for r in res["ode_windows_all"] if r["impacts"] == 0 and r["resolved"]]
    assert len(free) == 1 and free[0]["M"] == 1 and free[0]["lo"] is None
    # its multipliers are the free oscillator's over one period: modulus exp(-nu/2)
    nu = float(args[args.index("--nu") + 1])
    mods = [abs(complex(*m)) for m in free[0]["multipliers_inside"]]
    assert mods == pytest.approx([math.exp(-nu / 2)] * 2, rel=1e-6)
    if case == "none":  # the range ends below 0: no upper edge inside it
        assert free[0]["hi"] is None
        return
    assert free[0]["kinds"][1] == "graze" and abs(free[0]["hi"]) <= free[0]["xtol"]
    flow = _flow(args)  # the exact flow: no contact just below, contacts just above
    for s, n in ((-1e-3, 0), (1e-3, 1)):
        orb = flow.orbit(s, 1, flow.settle(s, 1, 0).z[0] if n == 0 else [-(1 + s) - 1.0, 0.0])
        assert (int(np.sum(orb.contacts)) > 0) == bool(n) or not orb.converged


@pytest.mark.parametrize("case", ["rigid", "soft"])
def test_coexisting_attractors_exist_and_are_stable_on_the_exact_flow(runs, case) -> None:
    """At the middle of every coexistence interval, each listed attractor is a stable orbit of the
    exact flow with its period and impacts (Newton from the scans' nearest state of it)."""
    import xarray as xr

    res, _, args, folder, _ = runs[case]
    assert res["coexistence"], "the case was chosen for its bistability below sigma = 0"
    flow = _flow(args)
    ds = xr.open_dataset(folder / res["files"][-1])  # the scans' NetCDF
    for c in res["coexistence"]:
        lo = c["lo"] if c["lo"] is not None else res["parameters"]["shooting_sigma_range"][0]
        hi = c["hi"] if c["hi"] is not None else res["parameters"]["shooting_sigma_range"][1]
        mid = 0.5 * (lo + hi)
        for key in c["keys"]:
            M, k = (int(x) for x in key.split("#")[0].split("/"))  # "2/1#2": the second orbit of a kind
            orb = _exact_orbit_at(flow, ds, res, M, k, mid)
            assert orb is not None and orb.converged and orb.stable, (key, mid)
            assert int(np.sum(orb.contacts)) == k and len(orb.z) == M


def _exact_orbit_at(flow: ExactFlow, ds, res, M: int, k: int, s: float):
    """The exact flow's period-M orbit with k contacts at s: Newton from the scans' state of it
    nearest s (inside its window), then marched to s in small steps (Newton at each)."""
    if k == 0:
        return flow.orbit(s, M, [(1 + s) * math.cos(math.pi) - 1.0, 0.0])  # the wall-free orbit at t = 1/2
    row = next(r for r in res["ode_windows_all"] if (r["M"], r["impacts"]) == (M, k) and r["resolved"])
    lo, hi = (-math.inf if row["lo"] is None else row["lo"]), (math.inf if row["hi"] is None else row["hi"])
    per = ds["period"].transpose("sigma", "direction").values
    imp = ds["orbit_impacts"].transpose("sigma", "direction").values
    u = ds["u"].transpose("sigma", "direction", ...).values
    v = ds["v"].transpose("sigma", "direction", ...).values
    sig = ds["sigma"].values
    hits = sorted((abs(sig[i] - s), i, j) for i in range(len(sig)) for j in range(per.shape[1])
                  if per[i, j] == M and imp[i, j] == k and lo < sig[i] < hi)
    assert hits, f"{M}/{k} not in the scans inside its window"
    _, i, j = hits[0]
    z, s0 = np.array([u[i, j, 0], v[i, j, 0]]), float(sig[i])
    orb, prev = None, None
    # steps of at most 2e-4 in sigma, at most 20 of them: the scans' nearest state lies within a
    # grid step (5e-3) of s or so, often 1e-3 and less, where fewer Newton solves lead as surely
    n = min(21, 2 + int(math.ceil(abs(s - s0) / 2e-4)))
    for sk in np.linspace(s0, s, n):
        # a secant prediction from the last two orbits: near a graze the orbit with one more contact
        # lies close by, and Newton from the last orbit unchanged falls onto it (soft case, 8/3 at
        # sigma = -0.2763, 3e-4 from its graze: an unstable orbit with 4 impacts)
        guess = z if prev is None else 2.0 * z - prev
        orb = flow.orbit(float(sk), M, guess)
        if not orb.converged:
            return orb
        prev, z = z, orb.z[0]
    return orb


@pytest.mark.parametrize("case", list(CASES))
def test_every_summary_line_follows_from_its_table(runs, case) -> None:
    res, report, _, _, _ = runs[case]
    verdict = report.split("## Verdict", 1)[1]
    ode = {int(M): w for M, w in res["windows"]["ode"].items()}
    top = max([M for M, w in ode.items() if w is not None], default=None)
    assert f"ODE M = {top}" in verdict if top else "ODE none" in verdict
    if top is None:
        assert "no stable maximal" in verdict
    for line in res["summary"]:
        assert f"- {line}" in verdict
    # the coexistence lines: the listed attractors' windows all cover the interval, no other does
    rows = [r for r in res["ode_windows_all"] if r["resolved"]]
    for c in res["coexistence"]:
        a = c["lo"] if c["lo"] is not None else -math.inf
        b = c["hi"] if c["hi"] is not None else math.inf
        mid = 0.5 * (max(a, -1.0) + min(b, 1e3))
        covering = {f"{r['M']}/{r['impacts']}" for r in rows
                    if (r["lo"] is None or r["lo"] < mid) and (r["hi"] is None or mid < r["hi"])}
        assert covering == {k.split("#")[0] for k in c["keys"]}
    import re

    for line in res["summary"]:  # where period adding stops, against the ODE row of the table
        has = {M for M, w in ode.items() if w is not None}
        if m := re.search(r"truncates at M = (\d+)", line):
            stop = int(m.group(1))
            assert not has & {stop, stop + 1} and not {M for M in has if M > stop}
        if m := re.search(r"but at M = ([\d, ]+):", line):
            assert {int(x) for x in m.group(1).split(",")} <= has
        if "does not start" in line:
            assert not has
    n_lines = sum(line.startswith("Coexisting attractors") for line in res["summary"])
    assert n_lines == len(res["coexistence"])
    if case == "none":  # no maximal window, yet a two-impact period-4 orbit beside the wall-free one
        assert top is None and "no stable maximal" in verdict
    if not res["coexistence"]:
        assert "No two stable attractors coexist" in verdict


def test_the_run_line_reproduces_the_json(runs, tmp_path) -> None:
    """Running the report's "Run:" line again (into another folder) gives the same windows,
    coexistence, summary and parameters."""
    import re
    import shlex

    res, report, _, _, _ = runs["none"]
    line = re.search(r"Run: `impact-harness (.+?)`", report).group(1)
    argv = shlex.split(line)
    argv[argv.index("--out") + 1] = str(tmp_path / "again")
    assert main([*argv, "--workers", "1", "--no-progress"]) == 0
    again = json.loads((tmp_path / "again" / "windows.json").read_text())
    for key in ("windows", "ode_windows_all", "coexistence", "summary", "edge_kinds"):
        assert again[key] == res[key], key
    same = {k: v for k, v in res["parameters"].items() if k != "fmu_periods_shooting"}
    assert {k: again["parameters"][k] for k in same} == same


@pytest.mark.parametrize("case", list(CASES))
def test_every_figure_panel_holds_data_or_says_why(runs, case) -> None:
    """Each axes of each figure `windows` writes has drawn data (lines, bars, points, arrows) or
    a text saying why it has none; a figure with nothing to show is not written."""
    res, _, _, _, seen = runs[case]
    assert {"windows_ode.png", "windows_windows.png"} <= set(seen)
    assert all(all(panels) for panels in seen.values()), seen
    assert sorted(f for f in res["files"] if f.endswith(".png")) == sorted(seen)
