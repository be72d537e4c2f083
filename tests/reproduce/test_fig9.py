"""``reproduce fig9 --quick``: window edges of the ODE (the real FMU) against the maps.

Independent truths: the 2D map with A~(sigma) (closed-form maximal orbits, mapcheck),
and the FMU's own up/down scans (plain simulation, no Newton).
"""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from harness.cli.main import main
from harness.reproduce import run_target

pytestmark = pytest.mark.slow  # reproduces the paper's Figure 9

FMU = Path(__file__).resolve().parents[2] / "build" / "fmu" / "ImpactOscillator.fmu"


@pytest.fixture(scope="module")
def fig9(tmp_path_factory):
    assert FMU.is_file(), f"build the FMU first ({FMU} missing)"
    out = tmp_path_factory.mktemp("fig9")
    run_target("fig9", out, quick=True, workers=2, progress=False)
    return out, json.loads((out / "fig9.json").read_text())


def test_outputs_and_four_window_tables(fig9) -> None:
    out, res = fig9
    for name in ("report.md", "fig9.json", "fig9_map.png", "fig9_ode.png", "fig9_windows.png"):
        assert (out / name).stat().st_size > 0, name
    w = res["windows"]
    assert set(w) == {"ode", "theory_64", "map", "map_A_tilde"}
    for table in w.values():
        assert set(table) == {"1", "2", "3", "4"}
        assert table["1"][1] is None  # period 1 has no upper edge
    assert {"alpha", "gamma", "r", "Gamma"} <= set(res["parameters"])
    report = (out / "report.md").read_text()
    assert "Verdict" in report and "disagree" in report


def test_ode_edges_match_the_A_tilde_map(fig9) -> None:
    """The A~(sigma) map is the near-grazing expansion with the exact grazing acceleration;
    what it leaves out is higher order in the distance to grazing.  0.01 in sigma is 100x
    the shooting bisection tolerance (1e-4), a quarter of the smallest gap between
    neighbouring windows (M = 3 -> M = 2: 0.04), so each ODE window is matched with the right
    map window, and 30x smaller than the shift of the linear-rho maps (~0.37)."""
    _, res = fig9
    ode, mt = res["windows"]["ode"], res["windows"]["map_A_tilde"]
    for M in ("1", "2", "3", "4"):
        assert ode[M][0] == pytest.approx(mt[M][0], abs=0.01), M
        if M != "1":
            assert ode[M][1] == pytest.approx(mt[M][1], abs=0.01), M
            assert ode[M][0] < ode[M][1]
    assert res["best_variant"] == "map_A_tilde"
    # the paper's linear rho(sigma): |A~|/|A| = 1 + sigma (1 - Omega^2/4pi^2) ~ 1.8 at the
    # period-1 flip, so its edges sit at about half the sigma
    for name in ("theory_64", "map"):
        assert res["windows"][name]["1"][0] < 0.7 * ode["1"][0]


def test_edge_kinds(fig9) -> None:
    """Lower edges: the orbit loses stability (flip); upper edges: an extra contact."""
    kinds = fig9[1]["edge_kinds"]["ode"]
    for M, (lo, hi) in kinds.items():
        assert lo == "flip", M
        assert hi == ("range" if M == "1" else "graze"), M


def test_scans_confirm_shooting(fig9) -> None:
    """Up/down scans (grid step h = 0.01) never see a stable maximal period-M orbit more than
    one step outside the shooting window.  Inside, upper (graze) edges are seen within two
    steps (a jump of h may knock the orbit onto a coexisting attractor), lower (flip) edges
    within 0.05: near a flip the multiplier is ~ -1 + k d (k ~ 1 per unit sigma), and the
    200 transient periods reduce the period-2M oscillation by e^(-200 k d), which falls below
    the classification tolerance (1e-4 against ~1e-2 after a jump) only for d > ~0.025."""
    _, res = fig9
    h = res["scan_grid_step"]
    for M, cf in res["scan_confirmation"].items():
        if M == "4":
            continue  # 0.0016 wide: narrower than the quick grid
        assert cf["lower_minus_shooting"] is not None, M
        assert -h - 1e-9 <= cf["lower_minus_shooting"] <= 0.05, (M, cf)
        if cf["upper_minus_shooting"] is not None:
            assert -2 * h - 1e-9 <= cf["upper_minus_shooting"] <= h + 1e-9, (M, cf)


def test_unknown_target_is_bad_input(capsys) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["reproduce", "fig99", "--quick"])
    assert exc.value.code == 2
