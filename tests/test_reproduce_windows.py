"""``impact-harness windows``: map vs ODE window edges for a parameter set not in the paper.

(alpha, gamma) = (0.5, 0.05), r = 0.8, compliant wall Gamma = 10.  Independent truth: the 2D
map with A~(sigma) (closed-form maximal orbits, mapcheck) near its lower edges, where the
orbit is closest to grazing; the FMU's own up/down scans (plain simulation, no Newton).
"""
from __future__ import annotations

import json
import math

import pytest

from harness.cli.main import main
from harness.reproduce.windows import WindowProblem, default_settings

ARGS = ["--alpha", "0.5", "--gamma", "0.05", "--r", "0.8", "--wall", "compliant", "--Gamma", "10"]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("windows")
    assert main(["windows", *ARGS, "--M-max", "3", "--quick", "--workers", "2", "--no-progress",
                 "--out", str(out)]) == 0
    return out, json.loads((out / "windows.json").read_text())


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
    assert "impact-harness windows --nu" in report  # the footer gives a command that reruns it


def test_ode_edges_measured_and_near_the_A_tilde_map(run) -> None:
    """Each ODE edge is the midpoint of its own bisected bracket (never the map's number);
    the flip (lower) edges lie within 5 % of the window's width of the A~ map's, the
    period-1 window has no upper edge (unresolved: no bracket below 4x the flip)."""
    _, res = run
    ode, mt = res["windows"]["ode"], res["windows"]["map_A_tilde"]
    for M in ("2", "3"):
        (lo, hi), (mlo, mhi) = ode[M], mt[M]
        assert lo < hi
        assert abs(lo - mlo) < 0.05 * (mhi - mlo), M
        for e, (good, bad), m in zip(ode[M], res["ode_edge_intervals"][M], mt[M]):
            assert bad is not None and e == pytest.approx(0.5 * (good + bad), abs=1e-15)
            assert abs(bad - good) <= res["parameters"]["shooting_xtol"][M] and e != m
        assert res["edge_kinds"]["ode"][M] == ["flip", "graze"]
    assert ode["1"][1] is None and res["ode_unresolved"]["1"] == ["upper"]
    assert res["edge_kinds"]["ode"]["1"] == ["flip", "range"]


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
        if cf["scan_upper"] is not None:
            assert cf["scan_upper"] <= hi * (1 + h) + 1e-12, (M, cf)


@pytest.mark.parametrize("extra", [["--nu", "3.0"], ["--r", "1.5"], ["--Gamma", "-1"], ["--wall", "soft"],
                                   ["--map", "soft"]])
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

