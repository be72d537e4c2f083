"""``impact-harness windows``: map vs ODE window edges for a parameter set not in the paper.

(alpha, gamma) = (0.5, 0.05), r = 0.8, compliant wall Gamma = 10.  Independent truths: every
ODE edge against the exact closed-form flow (mapcheck.exact, Newton of mapcheck.orbits; no
harness, no FMU), which must change from a stable maximal orbit to none across the reported
bracket for the reported reason (tests/support/edges.py); the 2D map with A~(sigma) (closed-form
maximal orbits, mapcheck) near its lower edges, where the orbit is closest to grazing; the FMU's
own up/down scans (plain simulation, no Newton), whose periods the test recomputes from the
samples.
"""
from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from harness.cli.main import main
from harness.analysis.windows.compare_windows import WindowProblem, default_settings
from tests.support.edges import ExactFlow, dominant, edge_sides, good

ARGS = ["--alpha", "0.5", "--gamma", "0.05", "--r", "0.8", "--wall", "compliant", "--Gamma", "10"]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("windows")
    # 250 fresh starts per sigma: the search's coverage at its default is test_global_search_windows'
    assert main(["windows", *ARGS, "--M-max", "3", "--quick", "--workers", "2", "--no-progress",
                 "--global-starts", "250", "--out", str(out)]) == 0
    return out, json.loads((out / "windows.json").read_text())


@pytest.mark.slow  # the module's windows run (Figure 9's parameters under CVODE)
def test_outputs_in_fig9_format(run) -> None:
    out, res = run
    for name in ("report.md", "windows.json", "windows_map.png", "windows_ode.png", "windows_windows.png",
                 "windows_ode_scans.nc"):
        assert (out / name).stat().st_size > 0, name
    assert set(res["windows"]) == {"ode", "theory_64", "map", "map_A_tilde"}
    for table in res["windows"].values():
        assert set(table) == {"1", "2", "3"}
    p = res["parameters"]
    assert p["alpha"] == pytest.approx(0.5, abs=1e-12) and p["gamma"] == pytest.approx(0.05, abs=1e-12)
    assert (p["r"], p["wall"], p["Gamma"]) == (0.8, "compliant", 10.0)
    report = (out / "report.md").read_text()
    assert "(alpha, gamma) = (0.5, 0.05), r = 0.8, compliant wall, Gamma = 10" in report
    # the footer gives the command that reruns it, as typed (recorded the one way of every command)
    assert "Run: `impact-harness windows --alpha 0.5 --gamma 0.05 --r 0.8 --wall compliant --Gamma 10 " in report


def _numbers(obj):
    """Every number in a JSON document (bools excluded)."""
    if isinstance(obj, dict):
        for v in obj.values():
            yield from _numbers(v)
    elif isinstance(obj, list):
        for v in obj:
            yield from _numbers(v)
    elif isinstance(obj, (int, float)) and not isinstance(obj, bool):
        yield obj


def _table(report: str, heading: str) -> list[list[str]]:
    """The cells of the markdown table under ``heading`` (header and separator dropped)."""
    lines = report.split(heading, 1)[1].splitlines()
    first = next(i for i, ln in enumerate(lines) if ln.startswith("|"))
    rows = []
    for ln in lines[first + 2:]:
        if not ln.startswith("|"):
            break
        rows.append([c.strip() for c in ln.strip("|").split("|")])
    return rows


def _window_cell(cell: str) -> tuple[float | None, float | None]:
    lo, hi = cell.strip("[]").split(", ")
    return tuple(None if x.startswith(("above", "beyond", "none")) else float(x) for x in (lo, hi))


@pytest.mark.slow  # the module's windows run (Figure 9's parameters under CVODE)
def test_json_numbers_are_finite_and_the_report_shows_them(run) -> None:
    """windows.json holds only finite numbers; report.md's tables show the JSON's numbers (to the
    digits they print): the window table of every source, the scans' confirmation, the map-minus-ODE
    differences and their maxima."""
    out, res = run
    nums = list(_numbers(res))
    assert len(nums) > 50 and all(math.isfinite(x) for x in nums)
    report = (out / "report.md").read_text()
    rows = _table(report, "## Stable windows of maximal orbits")
    assert [r[0].split(" ")[0] for r in rows] == ["ODE", "(64),", "2D", "2D"]
    def same_window(cell: str, window: list) -> None:
        for shown, value in zip(_window_cell(cell), window):
            assert (shown is None) == (value is None), cell
            if value is not None:
                assert shown == pytest.approx(value, abs=5.01e-7), cell  # 6 decimals

    for row, (name, table) in zip(rows, res["windows"].items()):
        for M, cell in zip(("1", "2", "3"), row[1:]):
            same_window(cell, table[M])
    confirmation = _table(report, "## Confirmation by the up/down scans")
    assert [r[0] for r in confirmation] == ["1", "2", "3"]
    for row in confirmation:
        M, cf = row[0], res["scan_confirmation"][row[0]]
        same_window(row[1], res["windows"]["ode"][M])
        assert float(row[2].split(" ")[0]) == pytest.approx(cf["scan_lower"], abs=5.01e-7)
        if cf["scan_upper"] is not None:
            assert float(row[3].split(" ")[0]) == pytest.approx(cf["scan_upper"], abs=5.01e-7)
    diffs = _table(report, "## Where the maps and the ODE disagree")
    assert len(diffs) == len(res["differences_to_ode"])
    for row, (name, d) in zip(diffs, res["differences_to_ode"].items()):
        for M, cell in zip(("1", "2", "3"), row[1:]):
            for shown, value in zip(cell.split(", "), d[M]):
                assert (shown == "-") == (value is None)
                if value is not None:
                    assert float(shown) == pytest.approx(value, rel=5.01e-4)  # 4 significant digits
        assert float(row[-1]) == pytest.approx(res["max_abs_difference_to_ode"][name], rel=5.01e-4)
        assert res["max_abs_difference_to_ode"][name] == pytest.approx(
            max(abs(x) for pair in d.values() for x in pair if x is not None), rel=1e-12)


def _recomputed_period(u: np.ndarray, v: np.ndarray, tol: float, max_period: int) -> int:
    """The smallest shift under which the samples repeat within tol (1 + their range): the
    definition of the scans' period, written out here (0: none up to max_period)."""
    threshold = tol * (1.0 + max(np.ptp(u), np.ptp(v)))
    for p in range(1, max_period + 1):
        if max(np.abs(u[p:] - u[:-p]).max(), np.abs(v[p:] - v[:-p]).max()) <= threshold:
            return p
    return 0


@pytest.mark.slow  # the module's windows run (Figure 9's parameters under CVODE)
def test_scans_netcdf_has_the_grid_dims_and_the_periods_of_its_samples(run) -> None:
    """windows_ode_scans.nc: (direction, sigma, sample) samples on the JSON's geometric grid, one
    period apart at the section phase, finite; each point's period is the one its samples show
    (recomputed here) with the impacts of its last period; the JSON's scan windows are maximal
    runs of one-impact points of that period on the grid."""
    from harness import read_netcdf

    out, res = run
    ds = read_netcdf(out / "windows_ode_scans.nc")
    p = res["parameters"]
    g0, g1, n = p["sigma_grid"]
    for name in ("u", "v", "impacts", "t"):
        assert ds[name].dims == ("direction", "sigma", "sample"), name
    for name in ("period", "orbit_impacts", "dynamics"):
        assert ds[name].dims == ("direction", "sigma"), name
    assert list(ds["direction"].values) == ["up", "down"]
    np.testing.assert_allclose(ds["sigma"].values, np.geomspace(g0, g1, n), rtol=1e-12)
    assert ds.sizes["sample"] == p["samples"]
    u, v, t = ds["u"].values, ds["v"].values, ds["t"].values
    assert np.all(np.isfinite(u)) and np.all(np.isfinite(v))
    np.testing.assert_allclose(np.diff(t, axis=-1), 1.0, atol=1e-9)
    np.testing.assert_allclose(np.mod(t, 1.0), p["theta"], atol=1e-9)
    period, orbit_impacts, imp = ds["period"].values, ds["orbit_impacts"].values, ds["impacts"].values
    tol, limit = float(ds.attrs["sampling.tol"]), p["M_scan_limit"]
    assert np.count_nonzero(period) > 100  # most points periodic: the comparison is not empty
    for d in range(2):
        for k in range(n):
            P = _recomputed_period(u[d, k], v[d, k], tol, limit)
            assert int(period[d, k]) == P, (d, k)
            if P:
                assert int(orbit_impacts[d, k]) == int(imp[d, k, -P:].sum()), (d, k)
    sig = ds["sigma"].values
    for d, direction in enumerate(("up", "down")):
        for M, (lo, hi) in res["scan_windows"][direction].items():
            i, j = int(np.argmin(np.abs(sig - lo))), int(np.argmin(np.abs(sig - hi)))
            assert sig[i] == lo and sig[j] == hi
            run_ = (period[d, i:j + 1] == int(M)) & (orbit_impacts[d, i:j + 1] == 1)
            assert run_.all(), (direction, M)
            for edge in (i - 1, j + 1):
                if 0 <= edge < n:
                    assert not (period[d, edge] == int(M) and orbit_impacts[d, edge] == 1), (direction, M)


@pytest.mark.slow  # the module's windows run (Figure 9's parameters under CVODE)
def test_ode_edges_measured_and_near_the_A_tilde_map(run) -> None:
    """Each ODE edge is the midpoint of its own located interval (the continuation's location, in a
    --quick run too; never the map's number): a flip's narrower than 1e-8, a graze's (the fit's
    interval of its defining quantity, which holds its own error) narrower than 1e-7;
    the flip (lower) edges lie within 5 % of the window's width of the A~ map's, the
    period-1 window has no upper edge (unresolved: no bracket below 4x the flip)."""
    _, res = run
    ode, mt = res["windows"]["ode"], res["windows"]["map_A_tilde"]
    for M in ("2", "3"):
        (lo, hi), (mlo, mhi) = ode[M], mt[M]
        assert lo < hi
        assert abs(lo - mlo) < 0.05 * (mhi - mlo), M
        for e, (good, bad), m, kind in zip(ode[M], res["ode_edge_intervals"][M], mt[M], ("flip", "graze")):
            assert bad is not None and e == pytest.approx(0.5 * (good + bad), abs=1e-15)
            assert abs(bad - good) <= (1e-8 if kind == "flip" else 1e-7) and e != m
        assert res["edge_kinds"]["ode"][M] == ["flip", "graze"]
        row = next(r for r in res["ode_windows_all"] if r["M"] == int(M) and r["impacts"] == 1)
        assert [h.split(" (")[0] for h in row["located"]] == ["continuation", "continuation"], row["located"]
    assert ode["1"][1] is None and res["ode_unresolved"]["1"] == ["upper"]
    assert res["edge_kinds"]["ode"]["1"] == ["flip", "range"]


@pytest.mark.slow  # the module's windows run (Figure 9's parameters under CVODE)
def test_scans_confirm_the_shooting(run) -> None:
    """The up/down scans see each ODE window with M >= 2, inside the shooting's edges up to
    one (relative) grid step: the scans never find a stable maximal orbit where the
    shooting finds none."""
    _, res = run
    h = res["scan_grid_step"]
    assert res["scan_grid_geometric"]
    for M in ("2", "3"):
        lo, hi = res["windows"]["ode"][M]
        cf = res["scan_confirmation"][M]
        assert cf["scan_lower"] is not None and cf["scan_lower"] >= lo * (1 - h) - 1e-12, (M, cf)
        # both windows are seen by the up scan here: the upper check is never skipped
        assert cf["scan_upper"] is not None and cf["scan_upper"] <= hi * (1 + h) + 1e-12, (M, cf)


EDGES = [("1", 0), ("2", 0), ("2", 1), ("3", 0), ("3", 1)]

#: How far beyond each end of an edge's interval the exact flow must be on the edge's two sides.
TOL = 1e-8


@pytest.fixture(scope="module")
def exact(run):
    """The exact flow at the run's (nu, Omega, r, Gamma), strobed at its phase, and for each
    resolved one-impact window its stable maximal orbit, settled on from p(theta) at the sigma the
    harness seeded Newton at (a value of sigma only: no state is taken from the harness)."""
    _, res = run
    p = res["parameters"]
    flow = ExactFlow(p["nu"], p["Omega"], p["r"], p["Gamma"], p["wall"], p["theta"])
    seeds = {}
    for e in res["ode_windows_all"]:
        if e["impacts"] == 1 and e["resolved"]:
            M = e["M"]
            orb = flow.settle(e["seed_sigma"], M)
            assert good(orb) and orb.contacts.sum() == 1, (M, orb)
            seeds[str(M)] = (e["seed_sigma"], orb)
    return flow, seeds


@pytest.mark.slow  # the module's windows run (Figure 9's parameters under CVODE)
@pytest.mark.parametrize("M,side", EDGES, ids=[f"M{M}-{'lower' if s == 0 else 'upper'}" for M, s in EDGES])
def test_each_ode_edge_is_an_edge_of_the_exact_flow_of_its_kind(run, exact, M, side) -> None:
    """Every ODE edge the run reports (its interval (good, bad), located by the continuation on the
    FMU) is an edge of the exact flow to 1e-8: TOL inside the interval, the orbit continued on the
    closed form from the window's interior is stable and maximal; TOL outside it is not, for the
    reported reason.  Flip: the dominant multiplier is real, in (-1, -0.99) inside and below -1
    outside, where the orbit still converges with the same single impact.  Graze: inside, the
    loss is not a flip (|multiplier| < 0.9) and the largest u of the orbit's free steps,
    extrapolated to 0 from two inside points, vanishes within the bracket; outside, Newton finds
    no maximal orbit and the inside orbit's point meets the wall twice in M periods."""
    _, res = run
    flow, seeds = exact
    kind = res["edge_kinds"]["ode"][M][side]
    good_s, bad_s = res["ode_edge_intervals"][M][side]
    assert res["windows"]["ode"][M][side] == pytest.approx(0.5 * (good_s + bad_s), abs=1e-15)
    w = abs(bad_s - good_s)
    assert 0 < w <= res["parameters"]["shooting_xtol"][M]
    s_seed, seed = seeds[M]
    # the edge is located on the FMU's flow to ~1e-9 (an interval of its test function or defining
    # quantity); the exact flow is asked TOL beyond each end of that interval (the FMU's flow and
    # the exact one differ by more than the interval's width)
    es = edge_sides(flow, int(M), seed, s_seed, kind, good_s, bad_s, TOL)
    assert good(es.inside) and es.inside.contacts.sum() == 1
    m_in = dominant(es.inside.multipliers)
    if kind == "flip":
        m_out = dominant(es.outside.multipliers)
        assert es.outside.converged and es.outside.maximal and not es.outside.stable
        assert np.array_equal(es.outside.contacts, es.inside.contacts)
        assert abs(m_in.imag) < 1e-12 and abs(m_out.imag) < 1e-12
        assert -1.0 < m_in.real < -0.99 and -1.01 < m_out.real < -1.0, (m_in, m_out)
    else:
        assert kind == "graze"
        assert abs(m_in) < 0.9
        assert not (es.outside.converged and es.outside.maximal)
        assert es.contacts_out == 2
        lo, hi = sorted((good_s, bad_s))
        assert lo - TOL <= es.graze_root <= hi + TOL, (es.graze_root, good_s, bad_s)


@pytest.mark.parametrize("extra", [["--nu", "3.0"], ["--r", "1.5"], ["--Gamma", "-1"], ["--wall", "soft"],
                                   ["--map", "soft"], ["--global-starts", "-1"], ["--global-path", "gpu"]])
def test_bad_parameters_are_input_errors(extra, tmp_path) -> None:
    """One line on stderr, exit status 2 (argparse's choices, or the harness's input check),
    and nothing run."""
    try:
        rc = main(["windows", *ARGS, *extra, "--quick", "--out", str(tmp_path / "w")])
    except SystemExit as exc:
        rc = exc.code
    assert rc == 2
    assert not (tmp_path / "w" / "windows.json").exists()


def test_rigid_wall_problem() -> None:
    """A rigid wall uses the coefficients (39) and the FMU's rigid contact; the scan grid holds
    the base range [1e-3, 3] and the A~ map's windows; the tolerance is relative to sigma."""
    pr = WindowProblem.from_alpha_gamma(0.5, 0.05, r=0.8, wall="rigid", M_max=3)
    assert pr.fmu_params()["wall"] == 2 and "Gamma" not in pr.fmu_params()
    assert pr.coefficient_eq() == "(39)"
    a, g = pr.alpha_gamma
    assert math.isclose(a, 0.5, rel_tol=1e-12) and math.isclose(g, 0.05, rel_tol=1e-12)
    st = default_settings(pr, quick=True)
    assert st.sigma_range[0] < st.scan_grid[0] < st.scan_grid[-1] < st.sigma_range[1]
    assert st.xtol is None and 0 < st.xtol_rel <= 1e-3
    from mapcheck.compare import predicted_windows

    guide = predicted_windows(pr.coefficients(), 3, st.table_grid)["map_A_tilde"]
    for w in guide.values():
        if w is not None and w[0] is not None:
            assert st.scan_grid[0] <= w[0] <= st.scan_grid[-1]
    assert st.scan_grid[0] <= 1e-3 and st.scan_grid[-1] >= 3.0


def test_map_coefficients_follow_the_wall_or_are_chosen() -> None:
    """By default the maps take the wall's coefficients ((48) compliant, (39) rigid); --map
    compliant-high takes (39) for a stiff compliant wall (high-velocity impacts): then rho per
    sigma is the rigid wall's, smaller by (1 - r)^2 / (1 + r)^2."""
    from mapcheck.coeffs import coefficients

    soft = WindowProblem.from_alpha_gamma(0.5, 0.05, r=0.8)
    stiff = WindowProblem.from_alpha_gamma(0.5, 0.05, r=0.8, map_wall="compliant-high", Gamma=1e4)
    rigid = WindowProblem.from_alpha_gamma(0.5, 0.05, r=0.8, wall="rigid")
    assert (soft.coefficient_eq(), stiff.coefficient_eq(), rigid.coefficient_eq()) == ("(48)", "(39)", "(39)")
    assert stiff.fmu_params()["wall"] == 1 and stiff.fmu_params()["Gamma"] == 1e4
    ratio = stiff.coefficients().rho_per_sigma / soft.coefficients().rho_per_sigma
    assert ratio == pytest.approx((1 - 0.8) ** 2 / (1 + 0.8) ** 2, rel=1e-12)
    assert stiff.coefficients().rho_per_sigma == coefficients(stiff.nu, stiff.Omega, 0.8, "rigid").rho_per_sigma

