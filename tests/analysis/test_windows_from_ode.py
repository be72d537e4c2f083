"""``impact-harness windows`` finds the ODE's windows from the ODE.

Two reproductions, an underdamped oscillator that is not the paper's (nu = 0.8,
Omega = 2.5, r = 0.8: alpha ~ -1.05): with a rigid wall, and with a compliant wall Gamma = 100.
Each edge the tool reports is checked by brute force on the independent closed form
(:class:`mapcheck.exact.ExactOscillator`): just inside the edge the exact flow settles on the
reported orbit (its period), just outside it does not.  The closed-form solver mode keeps the runs
short, and one worker process: two spawned workers cost more in start-up than they save on these
runs (same windows, edges and brackets; 11 s against 15 s of CPU per run on 2 loaded cores), and
test_reproduce_windows runs the two-worker path.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from harness.cli.main import main
from mapcheck.exact import ExactOscillator

pytestmark = pytest.mark.slow

OSC = ["--nu", "0.8", "--Omega", "2.5", "--r", "0.8"]
#: Fresh starts of the global search per sigma: the edges checked here are those of the windows
#: every route finds; the search's own coverage (1000 starts, the default) is
#: test_global_search_windows' subject.  At the default it took 7 of the rigid run's 24 s of CPU.
GLOBAL_STARTS = 250


def _run(tmp_path_factory, name: str, wall: list[str]):
    out = tmp_path_factory.mktemp(name)
    assert main(["windows", *OSC, *wall, "--quick", "--solver", "closed-form", "--workers", "1", "--no-progress",
                 "--global-starts", str(GLOBAL_STARTS), "--out", str(out)]) == 0
    return json.loads((out / "windows.json").read_text()), (out / "report.md").read_text()


@pytest.fixture(scope="module")
def rigid(tmp_path_factory):
    return _run(tmp_path_factory, "rigid", ["--wall", "rigid"])


@pytest.fixture(scope="module")
def soft(tmp_path_factory):
    return _run(tmp_path_factory, "g100", ["--wall", "compliant", "--Gamma", "100"])


def exact_period(sigma: float, wall: str, Gamma: float = 10.0, n_transient: int = 400,
                 n: int = 17) -> tuple[int, int] | None:
    """(period <= 8, wall entries per period) of the attractor the exact flow reaches from near the
    wall-free orbit at ``sigma`` (strobed at t = n + 1/2), or None if not periodic."""
    osc = ExactOscillator(0.8, 2.5, sigma, 0.8, Gamma, wall)
    z0 = (-(1.0 + sigma) - 1.0 + 1e-3, 0.0)  # p(1/2), nudged off the symmetric start
    times = 0.5 + np.arange(n_transient, n_transient + n)
    s, counts = osc.strobe(z0[0], z0[1], times, t0=0.5)
    for p in range(1, 9):
        if np.max(np.abs(s[p:] - s[:-p])) < 1e-6 * (1.0 + sigma):
            return p, int(counts[p] - counts[0])
    return None


def test_rigid_period_one_window_is_measured_not_none(rigid) -> None:
    """The stable one-impact period-1 orbit seen from sigma ~ 1.64 up is reported, with
    a flip lower edge and multipliers inside the unit circle; the exact flow confirms the edge."""
    res, report = rigid
    lo, hi = res["windows"]["ode"]["1"]
    assert 1.5 < lo < 1.7 and hi is None  # no upper edge within the search range
    assert res["edge_kinds"]["ode"]["1"] == ["flip", "range"]
    (good, bad), _ = res["ode_edge_intervals"]["1"]
    assert abs(good - bad) <= res["parameters"]["shooting_xtol"]["1"]
    entry = next(e for e in res["ode_windows_all"] if e["M"] == 1 and e["impacts"] == 1)
    mult = np.array([complex(*m) for m in entry["multipliers_inside"]])
    assert np.all(np.abs(mult) < 1.0)
    assert exact_period(lo * 1.03, "rigid") == (1, 1)
    assert exact_period(lo * 0.97, "rigid") != (1, 1)
    assert "fmu_periods_shooting" in res["parameters"] and res["parameters"]["fmu_periods_shooting"] > 0


def test_rigid_report_says_why_maps_do_not_apply(rigid) -> None:
    """alpha <= 0: (64) does not apply, with the reason; no empty tolerance, no empty table, no
    runaway map values; --M-max auto says where it stopped; multi-impact windows are listed."""
    res, report = rigid
    assert res["parameters"]["alpha"] < 0
    assert "alpha = -1.048 <= 0" in res["map_applicability"]["theory_64"]
    assert "does not apply" in report
    assert "xtol ()" not in report and "bisected to xtol" in report
    assert "period adding truncates at M = 2" in report
    for line in report.splitlines():
        assert "e+" not in line or "Run:" in line  # no 1e196 anywhere
    multi = [e for e in res["ode_windows_all"] if e["impacts"] > 1 and e["resolved"]]
    assert multi and "| 2 | 2 |" in report  # the two-impact period-2 orbit below the flip
    # the period-2 two-impact window ends where period 1 begins: the flip that creates it
    e2 = next(e for e in multi if e["M"] == 2 and e["impacts"] == 2)
    assert e2["hi"] == pytest.approx(res["windows"]["ode"]["1"][0], rel=5e-3)


def test_soft_wall_period_two_window_beyond_the_maps_range(soft) -> None:
    """Gamma = 100: the one-impact period-2 orbit continues to sigma ~ 0.15 (a scan range taken
    from the map would cut it at 0.023); its upper edge is a flip, and the up scan agrees."""
    res, report = soft
    lo, hi = res["windows"]["ode"]["2"]
    assert hi is not None and 0.1 < hi < 0.2
    assert res["edge_kinds"]["ode"]["2"][1] == "flip"
    # brute force across the edge: the quasi-static up scan (state carried from point to point)
    # holds the one-impact period-2 orbit up to within a grid step of the edge, never beyond it
    h = res["scan_grid_step"]
    up_hi = res["scan_windows"]["up"]["2"][1]
    assert 0.1 < up_hi <= hi * (1 + h)
    assert res["map_applicability"]["map_A_tilde"] is None  # the 2D map applies; (64) does not
    assert res["map_applicability"]["theory_64"] is not None
    assert "highest window is M = 0" not in report and math.isfinite(res["parameters"]["sigma_grid"][1])


def test_alpha_messages_match_nu_omega(tmp_path) -> None:
    """--alpha -1.05 with gamma = exp(-0.8) is the same underdamped oscillator: it asks for the
    psi branch instead of refusing alpha < 0; a gamma outside (0, 1) is refused with the reason."""
    rc = main(["windows", "--alpha", "-1.05", "--gamma", str(math.exp(-0.8)), "--quick", "--out", str(tmp_path)])
    assert rc == 2
    rc = main(["windows", "--alpha", "0.5", "--gamma", "1.5", "--quick", "--out", str(tmp_path)])
    assert rc == 2


def test_underdamped_alpha_gamma_with_a_branch_is_the_nu_omega_oscillator() -> None:
    """(alpha, gamma) of nu = 0.8, Omega = 2.5 with --branch 0 gives back that oscillator."""
    from harness.analysis.windows.compare_windows import WindowProblem
    from mapcheck.linear import alpha_gamma

    a, g = alpha_gamma(0.8, 2.5)
    pr = WindowProblem.from_alpha_gamma(a, g, 0, r=0.8, wall="rigid")
    assert (pr.nu, pr.Omega) == (pytest.approx(0.8, rel=1e-12), pytest.approx(2.5, rel=1e-12))
