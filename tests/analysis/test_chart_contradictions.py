"""``chart``'s second routes: contradictions settled by shooting, the wall-free window, coexistence.

The case: a rigid wall with r close to 1 (nu = 1, Omega = 3.2, r = 0.99), charted over nu in
[1, 1.3] with sigma in [-0.05, 0.05].  Below grazing an impacting period-1 orbit is born in a fold
(sigma = -0.0025 at nu = 1) next to the stable wall-free orbit: bistability; the fold moves up to
sigma = 0 as nu grows.

Independent truth: the wall-free orbit (4) grazes at sigma = 0 exactly and its multipliers are the
free oscillator's, |mu| = exp(-nu/2) (docs/theory.md section 10); every other orbit is checked on
the exact closed-form flow (mapcheck's own Newton, :class:`tests.support.edges.ExactFlow`), never
against numbers this code produced.
"""
from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from harness.cli.main import main
from tests.support.edges import ExactFlow

pytestmark = pytest.mark.slow

CASE = dict(nu=1.0, Omega=3.2, r=0.99)
ARGS = ["chart", "--nu", "1.0", "--Omega", "3.2", "--r", "0.99", "--wall", "rigid", "--param2", "nu", "--range",
        "1.0:1.3", "--num", "3", "--M-max", "2", "--quick", "--sigma-range=-0.05:0.05", "--workers", "2",
        "--solver", "closed-form"]


@pytest.fixture(scope="module")
def bistable(tmp_path_factory):
    import contextlib
    import io

    out = tmp_path_factory.mktemp("chart_bistable")
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main([*ARGS, "--out", str(out)]) == 0
    (out / "stdout.txt").write_text(buf.getvalue())
    return out, json.loads((out / "chart.json").read_text())


def _flow(nu: float) -> ExactFlow:
    return ExactFlow(nu, CASE["Omega"], CASE["r"], 10.0, "rigid")


def _impacting_walk(nu: float, path) -> tuple[float, np.ndarray]:
    """The exact flow's stable period-1 orbit with one impact, settled at sigma = 0.01 and walked
    along ``path`` (decreasing sigma) while it stays so: (the last sigma, its point there)."""
    flow = _flow(nu)
    orb = flow.settle(0.01, 1, 300)
    assert orb.converged and int(np.sum(orb.contacts)) == 1
    z, last = orb.z[0], 0.01
    for s in path:
        o = flow.orbit(float(s), 1, z)
        if not (o.converged and int(np.sum(o.contacts)) == 1 and np.max(np.abs(o.multipliers)) < 1.0):
            break
        z, last = o.z[0], float(s)
    return last, z


def _fold(nu: float, near: float, tol: float = 1e-7) -> float:
    """The exact flow's fold below grazing, to ``tol``: the orbit walked down to 1e-4 above
    ``near``, then the last sigma where it is stable bisected (each try from the last good orbit)."""
    good, z = _impacting_walk(nu, np.linspace(0.01, near + 1e-4, 80))
    bad = near - 1e-4
    flow = _flow(nu)
    assert good == pytest.approx(near + 1e-4)
    o = flow.orbit(bad, 1, z)
    assert not (o.converged and int(np.sum(o.contacts)) == 1 and np.max(np.abs(o.multipliers)) < 1.0)
    while good - bad > tol:
        s = 0.5 * (good + bad)
        o = flow.orbit(s, 1, z)
        if o.converged and int(np.sum(o.contacts)) == 1 and np.max(np.abs(o.multipliers)) < 1.0:
            good, z = s, o.z[0]
        else:
            bad = s
    return good


def _exact_stable(nu: float, sigma: float, M: int, impacts: int, z) -> bool:
    o = _flow(nu).orbit(sigma, M, z)
    return bool(o.converged and int(np.sum(o.contacts)) == impacts and np.max(np.abs(o.multipliers)) < 1.0)


def test_the_wall_free_orbit_is_a_window_grazing_at_zero_with_the_free_multipliers(bistable) -> None:
    out, res = bistable
    cl = res["closes"]["1/0"]
    assert cl["label"] == "wall-free (period 1, no impact)" and cl["impacts"] == 0 and cl["closes"] is None
    graze = res["wall_free"]["curves"]["upper"]
    assert graze["p2"] == pytest.approx([1.0, 1.15, 1.3])
    for nu, s, mult in zip(graze["p2"], graze["sigma"], graze["multipliers"]):
        assert abs(s) < 1e-9  # exact: the wall-free orbit grazes at sigma = 0
        assert [abs(complex(*m)) for m in mult] == pytest.approx([math.exp(-nu / 2)] * 2, rel=1e-8)
    # the scans saw it too, at every value, apart from period 1 with an impact
    sc = res["scans"]["1/0"]
    assert sc["value"] == pytest.approx([1.0, 1.15, 1.3]) and all(k == "graze" for k in sc["kind_upper"])
    assert all(abs(h) < 1e-4 for h in sc["upper"]) and sc["label"] == cl["label"]
    report = (out / "report.md").read_text()
    assert "| 1, no impact (wall-free) |" in report


def test_coexistence_below_grazing_is_listed_per_value_and_is_the_exact_flows(bistable) -> None:
    """At nu = 1 the wall-free orbit and the impacting period-1 orbit coexist from the fold to
    sigma = 0: both routes list it, and its ends are the exact flow's fold and sigma = 0."""
    out, res = bistable
    (row,) = [c for c in res["coexistence"] if c["p2"] == pytest.approx(1.0)]
    assert row["keys"] == ["1/0", "1/1"] and row["routes"] == ["scans", "continuation"]
    fold = _fold(1.0, row["continued"][0])
    lo_cont, hi_cont = row["continued"]
    assert abs(lo_cont - fold) < 2e-6 and abs(hi_cont) < 1e-9
    assert abs(row["lo"] - fold) < 1e-5 and abs(row["hi"]) < 1e-4  # the scans', to their tolerance
    report = (out / "report.md").read_text()
    assert "## Coexisting attractors per value" in report
    assert re.search(r"\| 1 \| -0\.0025\d* \| .* \| period 1, no impact \(wall-free\); period 1, 1 impact \| scans and "
                     r"continuation", report)


def test_every_contradiction_found_is_settled_as_the_exact_flow_says(bistable) -> None:
    """Whatever the two routes disagree on, the resolution is the exact flow's: where the shooting
    found a stable orbit, the exact flow has it (same multipliers); where it found none at an edge's
    midpoint, the exact flow's orbit is lost before it.  The report puts them first; stdout counts."""
    out, res = bistable
    con = res["contradictions"]
    assert con["compared"]["values"] == 3 and "1/0" in con["compared"]["windows"]
    for c in con["found"]:
        ev, M = c["evidence"], int(c["window"].split("/")[0])
        if ev["found"]:
            o = _flow(c["p2"]).orbit(ev["sigma"], M, _point_near(res, c))
            assert o.converged and int(np.sum(o.contacts)) == (0 if c["window"] == "1/0" else 1)
            assert sorted(abs(o.multipliers)) == pytest.approx(sorted(abs(complex(*m)) for m in ev["multipliers"]),
                                                               abs=1e-6)
        elif c["type"] == "edge" and c["window"] == "1" and c["side"] == "lower":
            s_mid = ev["range"][0]  # no stable impacting orbit there: the exact flow's fold lies above it
            assert _fold(c["p2"], s_mid) > s_mid
    n = len(con["found"])
    right = sum(c["right"] == "scans" for c in con["found"])
    line = (f"contradictions between the continuation and the scans: {n} (settled by shooting: continuation right in "
            f"{n - right}, scans right in {right}" if n else "contradictions between the continuation and the scans: none")
    assert line in (out / "stdout.txt").read_text()
    report = (out / "report.md").read_text()
    sections = re.findall(r"^## (.+)$", report, flags=re.M)
    assert sections[0] == "Contradictions between the continuation and the per-value scans"
    assert report.index("## Contradictions") < report.index("Parameters:")
    # enums by name, and no None/null in the text a person reads
    assert "wall = rigid" in report and "solver = closed-form" in report
    assert not re.search(r"\bNone\b|\bnull\b", report)


def _point_near(res, c):
    """A start for the exact flow's Newton (the shooting's own orbit is not stored): the wall-free
    point, or the exact flow's impacting orbit walked down to that sigma."""
    from harness.dynamics.maps.periodic_map import wall_free_offset

    ev = c["evidence"]
    if c["window"] == "1/0":
        return wall_free_offset(ev["sigma"], 0.5)
    if c["window"] == "1":
        return _impacting_walk(c["p2"], np.linspace(0.01, ev["sigma"], 80))[1]
    return _flow(c["p2"]).settle(ev["sigma"], int(c["window"]), 300).z[0]


def test_a_window_removed_from_the_scans_is_restored_by_shooting(bistable) -> None:
    """A constructed disagreement on real runs: the scans at nu = 1 (run again here, a real
    chart_value_task) with the impacting period-1 window and its states removed, against the
    continued windows of the fixture's run: the continuation says present, the scans absent, and
    the shooting finds the stable orbit, which the exact flow confirms; the continuation is right.
    Then the other way: the continued window removed, the scans' window found by shooting."""
    from harness.analysis.chart.run import ChartProblem, chart_value_task
    from harness.analysis.chart.contradictions import contradiction_lines, contradictions
    from harness.config import default_fmu_path
    from harness.fmu.fmi import FmuModel

    _, res = bistable
    p = res["parameters"]
    params = {k: p[k] for k in ("nu", "Omega", "r", "wall", "solver")}
    grid = np.linspace(-0.05, 0.05, p["sigma_grid"][2])
    problem = ChartProblem(params, "nu", np.array([1.0]), False, 2, grid, transient=150, xtol_rel=1e-3)
    source = FmuModel(default_fmu_path(), "--fmu").source()
    task = {"params": {**params, "nu": 1.0}, "value": 1.0, "grid": grid.tolist(), "theta": 0.5, "transient": 150,
            "samples": 24, "xtol_rel": 1e-3, "xtol": None, "M_max": 2}
    scan = chart_value_task(task, source)
    assert any(e["M"] == 1 and e["impacts"] == 1 and e["resolved"] for e in scan["all"])
    windows = res["windows"] + [res["wall_free"]]
    # as run, the two routes agree at nu = 1 (both the exact flow's, test above): none, said with what was compared
    con = contradictions(source, problem, windows, [scan])
    assert con["found"] == [] and con["compared"]["presence"] == 3 and con["compared"]["edges"] >= 4
    assert contradiction_lines(con, "nu")[2].startswith("None: compared the presence of 3 windows")
    cut = {**scan, "all": [e for e in scan["all"] if not (e["M"] == 1 and e["impacts"] == 1)],
           "seeds": [s for s in scan["seeds"] if not (s["M"] == 1 and s["impacts"] == 1)]}
    con = contradictions(source, problem, windows, [cut])
    (c,) = [c for c in con["found"] if c["window"] == "1"]
    assert c["type"] == "presence" and c["continuation"] and not c["scans"] and c["right"] == "continuation"
    ev = c["evidence"]
    assert ev["found"] and ev["contacts"] == [1] and "continued" in ev["start"]["from"]
    lo, hi = c["continued"]
    assert lo < ev["sigma"] and (hi is None or ev["sigma"] < hi)
    last, z = _impacting_walk(1.0, np.linspace(0.01, ev["sigma"], 80))
    assert last == pytest.approx(ev["sigma"]) and _exact_stable(1.0, ev["sigma"], 1, 1, z)
    # the other way round: the scans have it, the continuation (its window removed) does not
    con = contradictions(source, problem, [w for w in windows if not (w["M"] == 1 and w.get("impacts", 1) == 1)],
                         [scan])
    (c,) = [c for c in con["found"] if c["window"] == "1"]
    assert c["scans"] and not c["continuation"] and c["right"] == "scans" and c["evidence"]["found"]
