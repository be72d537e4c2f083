"""Two-parameter continuation of the windows' edges against independent truth.

Truth: mapcheck's closed-form flow (:class:`mapcheck.exact.ExactOscillator`) with mapcheck's own Newton
shooting and finite-difference multipliers (:func:`mapcheck.orbits.solve_periodic_orbit`): it shares
nothing with the FMU, its sensitivities, the extended system or the graze location.  Along Figure 9's
curves in (sigma, Gamma):

* every point of a flip curve is an orbit of the exact flow with a multiplier -1;
* every point of a graze curve is an orbit of the exact flow whose free passage touches the wall
  (its largest u over the free period, on a dense grid of the exact flow, is 0);
* the turning point that closes the period-2 window is a brute-force fact: just below it in Gamma
  the orbit there is stable, just above it is not;
* period 3 closes where its flip meets its graze: the flip curve's end and the graze curve's loss of
  stability, two different routes, give the same point;
* period 1's flip runs off to large sigma as Gamma -> ~1632: a one-parameter continuation in Gamma at
  fixed sigma (another algorithm) finds the flip on the curve.
"""
from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from harness.dynamics.attractors.scans import find_attractors
from harness.dynamics.continuation.continue_orbit import continue_orbit
from harness.dynamics.curves.event_curves import continue_event
from harness.dynamics.curves.graze_curves import continue_graze
from harness.analysis.chart.edge_curves import window_closing
from tests.support.edges import ExactFlow

ROOT = Path(__file__).resolve().parents[2]
FIG9 = tomllib.loads((ROOT / "harness" / "experiments" / "fig9.toml").read_text())["model"]
THETA = 0.5
SIGMA_RANGE = (5e-3, 4000.0)


def exact_orbit(p: dict, sigma: float, Gamma: float, z0, M: int):
    """mapcheck's own shooting on the exact flow (tests/support/edges.py)."""
    flow = ExactFlow(p["nu"], p["Omega"], p["r"], Gamma, "compliant", THETA)
    return flow, flow.orbit(sigma, M, z0)


def free_passage_max_u(flow: ExactFlow, sigma: float, orb) -> float:
    """Largest u over the orbit's periods without contact (exact flow, brentq on v = 0)."""
    top = flow.max_u_per_step(sigma, orb.z[0], len(orb.z))
    return float(np.max(top[np.asarray(orb.contacts) == 0]))


@pytest.fixture(scope="module")
def fig9(model) -> dict:
    return {**model.defaults(), **FIG9, "wall": 1, "solver": 1, "Gamma": 10.0}


def _edges(sim, p, sigma, M):
    scan = find_attractors(sim, p, [sigma], M_max=4, transient=300)
    (a,) = [a for a in scan.attractors if a.period == M and a.impacts == 1]
    down = continue_orbit(sim, p, M, sigma, a.points[0], "sigma", (0.05, 5.0), -1.0)
    up = continue_orbit(sim, p, M, sigma, a.points[0], "sigma", (0.05, 5.0), 1.0)
    return down.events[0], up.events[0]


@pytest.fixture(scope="module")
def m2(sim, fig9):
    flip, graze = _edges(sim, fig9, 0.5, 2)
    assert (flip.kind, graze.kind) == ("flip", "graze")
    fc = continue_event(sim, fig9, "flip", 2, flip.value, flip.point, "Gamma", (10.0, 1e4), True, 1.0,
                        sigma_range=(5e-3, 50.0), max_points=80)
    gc = continue_graze(sim, fig9, 2, graze.value, graze.point, graze.value * (1 + 1e-6), "Gamma", (10.0, 1e4), True,
                        1.0, max_points=30, sigma_range=(5e-3, 3.0))
    return fc, gc


@pytest.mark.slow
def test_flip_curve_points_are_flips_of_the_exact_flow(m2, fig9) -> None:
    fc, _ = m2
    assert fc.kind == "flip" and fc.M == 2 and fc.impacts == 1
    assert np.all(np.diff(fc.p2[:10]) > 0)  # started upward in Gamma
    idx = [int(np.argmin(np.abs(np.log(fc.p2) - np.log(G)))) for G in (100.0, 1000.0, 1600.0)]
    idx.append(int(np.argmax(fc.p2)))  # near the turning point
    for i in idx:
        sig, G = float(fc.sigma[i]), float(fc.p2[i])
        z = fc.multipliers[i]  # the FMU's multipliers on the curve: one is -1 by construction
        assert np.min(np.abs(z + 1.0)) < 1e-8
        # the exact flow, started from the FMU orbit's neighbourhood but solved on its own
        ex, orb = exact_orbit(fig9, sig, G, _point(fc, i), 2)
        assert orb.converged and int(np.sum(orb.contacts)) == 1, (sig, G)
        assert np.min(np.abs(orb.multipliers + 1.0)) < 2e-4, (sig, G, orb.multipliers)


def _point(curve, i):
    """The FMU's stroboscopic point of the curve's orbit: only a start for the exact flow's Newton."""
    return curve.points[i]


@pytest.mark.slow  # two-parameter continuations of Figure 9's edges
def test_turning_point_closes_the_period_2_window(m2, fig9) -> None:
    fc, _ = m2
    closing = window_closing({"lower": fc.as_dict(), "upper": None}, (10.0, 1e4), SIGMA_RANGE)
    (turn,) = [t for t in fc.turns if t["side"] == "max"]
    assert closing["closes"] == pytest.approx(turn["p2"]) and "turns back" in closing["how"]
    assert 1500.0 < turn["p2"] < 1800.0 and 1.0 < turn["sigma"] < 3.0
    # brute force in the exact flow at the turning point's sigma: stable 1 % below in Gamma,
    # unstable 1 % above (no sigma near it is stable there: the window is gone)
    i = int(np.argmax(fc.p2))
    for factor, stable in ((0.99, True), (1.01, False)):
        for ds in (0.97, 1.0, 1.03):
            ex, orb = exact_orbit(fig9, turn["sigma"] * ds, turn["p2"] * factor, _point(fc, i), 2)
            assert orb.converged and int(np.sum(orb.contacts)) == 1
            assert bool(np.all(np.abs(orb.multipliers) < 1.0)) == stable or (stable and ds != 1.0), (factor, ds)


@pytest.mark.slow  # two-parameter continuations of Figure 9's edges
def test_graze_curve_points_graze_in_the_exact_flow(m2, fig9) -> None:
    _, gc = m2
    assert gc.kind == "graze" and len(gc.sigma) >= 5
    assert np.all(np.abs(gc.gaps) < 1e-6 * (1.0 + gc.sigma))
    for i in (0, len(gc.sigma) // 2, len(gc.sigma) - 1):
        sig, G = float(gc.sigma[i]), float(gc.p2[i])
        flow, orb = exact_orbit(fig9, sig * (1.0 - 1e-7), G, _point(gc, i), 2)
        assert orb.converged and int(np.sum(orb.contacts)) == 1, (sig, G)
        assert abs(free_passage_max_u(flow, sig * (1.0 - 1e-7), orb)) < 1e-5 * (1.0 + sig), (sig, G)
        # beyond the graze the free passage would cross the wall: the exact flow's orbit with one
        # impact per two periods no longer exists there
        flow2, orb2 = exact_orbit(fig9, sig * 1.01, G, orb.z[0], 2)
        assert not (orb2.converged and int(np.sum(orb2.contacts)) == 1
                    and free_passage_max_u(flow2, sig * 1.01, orb2) < 0.0)


@pytest.mark.slow
def test_period_3_closes_where_flip_meets_graze(sim, fig9) -> None:
    flip, graze = _edges(sim, fig9, 0.2, 3)
    assert (flip.kind, graze.kind) == ("flip", "graze")
    fc = continue_event(sim, fig9, "flip", 3, flip.value, flip.point, "Gamma", (10.0, 1e4), True, 1.0,
                        sigma_range=(5e-3, 50.0), max_points=80)
    gc = continue_graze(sim, fig9, 3, graze.value, graze.point, graze.value * (1 + 1e-6), "Gamma", (10.0, 1e4), True,
                        1.0, max_points=60, sigma_range=(5e-3, 1.0))
    assert fc.end["reason"] == "graze"
    (loss,) = [t for t in gc.turns if t["side"] == "loses"]
    assert loss["p2"] == pytest.approx(fc.end["p2"], rel=1e-3)
    assert loss["sigma"] == pytest.approx(fc.end["sigma"], rel=1e-3)
    closing = window_closing({"lower": fc.as_dict(), "upper": gc.as_dict()}, (10.0, 1e4), SIGMA_RANGE)
    # the exactly located route (the grazing orbit's multiplier through -1) is the one reported
    assert closing["closes"] == pytest.approx(loss["p2"]) and "loses stability" in closing["how"]


@pytest.mark.slow  # two-parameter continuations of Figure 9's edges
def test_period_1_flip_runs_off_to_large_sigma(sim, fig9) -> None:
    flip, _ = _edges(sim, fig9, 1.0, 1)
    assert flip.kind == "flip"
    fc = continue_event(sim, fig9, "flip", 1, flip.value, flip.point, "Gamma", (10.0, 1e6), True, 1.0,
                        sigma_range=(5e-3, 400.0), max_points=200)
    assert fc.end["reason"] == "range" and fc.sigma[-1] > 400.0 and not fc.turns
    assert np.all(np.diff(fc.p2) > 0) and np.all(np.diff(fc.sigma) > 0)
    closing = window_closing({"lower": fc.as_dict(), "upper": None}, (10.0, 1e6), (5e-3, 400.0))
    assert "runs off to large sigma" in closing["how"]
    # another algorithm: at fixed sigma, a one-parameter continuation in Gamma from a stable period-1
    # orbit finds the flip where the curve passes that sigma (100), and far beyond the range
    # charted (sigma = 1e4) near the curve's extrapolated asymptote (c / sigma ~ 0.04 away)
    G_curve = float(np.exp(np.interp(np.log(100.0), np.log(fc.sigma), np.log(fc.p2))))
    for sigma, expected, rel in ((100.0, G_curve, 1e-4), (1e4, closing["closes"], 1e-4)):
        p = {**fig9, "sigma": sigma, "Gamma": 1000.0}
        scan = find_attractors(sim, p, [1000.0], "Gamma", M_max=2, transient=300)
        (a,) = [a for a in scan.attractors if a.period == 1]
        # arclength in (w, Gamma): the orbit grows like sigma, so do the steps
        br = continue_orbit(sim, p, 1, 1000.0, a.points[0], "Gamma", (500.0, 3000.0), 1.0, ds=1.0,
                            ds_max=20.0 * (1.0 + sigma / 100.0))
        flips = [e.value for e in br.events if e.kind == "flip"]
        assert flips and flips[0] == pytest.approx(expected, rel=rel), sigma


@pytest.mark.slow
def test_period_4_closes_at_the_tip_of_its_thin_window(sim, fig9) -> None:
    """Figure 9's period-4 window (0.0016 wide at Gamma = 10) closes where its graze edge meets its
    flip edge; checked by one-parameter continuation in sigma at fixed Gamma on both sides."""
    flip, graze = _edges(sim, fig9, 0.1235, 4)
    assert (flip.kind, graze.kind) == ("flip", "graze")
    assert flip.value == pytest.approx(0.12223, abs=1e-4) and graze.value == pytest.approx(0.12379, abs=1e-4)
    gc = continue_graze(sim, fig9, 4, graze.value, graze.point, graze.value * (1 + 1e-6), "Gamma", (10.0, 1e3), True,
                        1.0, max_points=60, sigma_range=(5e-3, 1.0))
    (loss,) = [t for t in gc.turns if t["side"] == "loses"]
    assert 100.0 < loss["p2"] < 130.0
    i = int(np.argmin(np.abs(gc.p2 - loss["p2"])))
    near = slice(max(0, i - 3), i + 4)
    for factor, present in ((0.999, True), (1.001, False)):
        p = {**fig9, "Gamma": loss["p2"] * factor}
        # just below the graze edge at this Gamma (the window lies below it, ~1e-4 of sigma wide here)
        s0 = float(np.interp(p["Gamma"], gc.p2[near], gc.sigma[near])) * (1 - 3e-6)
        ok = []
        for d in (-1.0, 1.0):
            br = continue_orbit(sim, p, 4, s0, gc.points[i], "sigma", (0.1, 0.15), d, ds_max=0.002)
            ok.append(bool(br.stable_intervals()))
        assert any(ok) == present, factor


@pytest.mark.slow  # two-parameter continuations of Figure 9's edges
def test_the_period_2_closing_is_the_same_with_cvode(m2, sim, fig9) -> None:
    """The FMU's other solver (CVODE, located crossings and variational equations) continues the flip
    from a point of the closed-form curve below the turn and finds the same turning point."""
    fc, _ = m2
    (turn,) = [t for t in fc.turns if t["side"] == "max"]
    i = int(np.argmax(fc.p2 > 0.97 * turn["p2"]))
    p = {**fig9, "solver": 0, "Gamma": float(fc.p2[i])}
    cv = continue_event(sim, p, "flip", 2, float(fc.sigma[i]), fc.points[i], "Gamma", (10.0, 1e4), True, 1.0,
                        sigma_range=(5e-3, 50.0), max_points=12)
    (t_cv,) = [t for t in cv.turns if t["side"] == "max"]
    assert t_cv["p2"] == pytest.approx(turn["p2"], rel=1e-7)
    assert t_cv["sigma"] == pytest.approx(turn["sigma"], rel=1e-3)


def test_noise_turns_are_dropped_and_real_ones_kept() -> None:
    """CVODE's tolerance makes p2 wiggle by ~1e-4 where a curve runs parallel to the sigma axis
    (measured on period 2's graze near its asymptote at Gamma ~ 1100); those are not turns."""
    from harness.dynamics.curves.curve import significant_turns

    t = lambda p2, side: {"p2": p2, "side": side, "sigma": 1.0}  # noqa: E731
    wiggles = [t(1100.444, "max"), t(1100.431, "min"), t(1100.619, "max"), t(1100.496, "min"), t(1100.73, "max")]
    assert significant_turns(wiggles, 1100.66) == []
    real = [t(1652.58, "max"), t(1575.04, "min"), t(1575.0418, "max"), {"p2": 1600.0, "side": "loses", "sigma": 2.0}]
    kept = significant_turns(real, 1574.93)
    assert [x["side"] for x in kept] == ["max", "loses"] and kept[0]["p2"] == 1652.58


@pytest.mark.slow  # two-parameter continuations of Figure 9's edges
def test_a_flip_curve_in_r_on_a_linear_axis(sim, fig9) -> None:
    """Any FMU parameter as the second one, on a linear axis: Figure 9's period-2 flip continued in
    the restitution coefficient r; its points are flips of the exact flow at their r."""
    flip, _ = _edges(sim, fig9, 0.5, 2)
    fc = continue_event(sim, fig9, "flip", 2, flip.value, flip.point, "r", (0.5, 0.95), False, -1.0,
                        sigma_range=(5e-3, 50.0), max_points=15, ds_max=0.05)
    # the flip moves fast in sigma as r drops (rho of (48) goes like 1 / (1 - r)^2)
    assert fc.p2[0] == pytest.approx(0.9) and np.all(np.diff(fc.p2) < 0) and fc.p2[-1] < 0.89
    assert fc.sigma[-1] > 1.5 * fc.sigma[0]
    for i in (len(fc.p2) // 2, len(fc.p2) - 1):
        p = {**fig9, "r": float(fc.p2[i])}
        _, orb = exact_orbit(p, float(fc.sigma[i]), fig9["Gamma"], fc.points[i], 2)
        assert orb.converged and int(np.sum(orb.contacts)) == 1
        assert np.min(np.abs(orb.multipliers + 1.0)) < 2e-4, (fc.p2[i], fc.sigma[i], orb.multipliers)
