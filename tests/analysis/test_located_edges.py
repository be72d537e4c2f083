"""The per-value scans' edges located by the continuation (:mod:`harness.analysis.windows.located_edges`),
on two failure modes of per-value scans on Figure 9's chart and on COCO's impact example.

Figure 9's family (nu = 4.605, Omega = 0.3059, r = 0.9) at Gamma = 48.9, the chart's fifth value:
the march and bisection lost period 1 on both sides of its seed at sigma = 17.3 (edges 17.04 and
18.62, "lost": the band missed 0.82-17), and stopped period 2 at 0.526 with a "graze" that was
Newton falling onto the unstable period-1 orbit (2 impacts per 2 periods).  Truth: the exact flow
(:mod:`mapcheck.exact`, sharing nothing with the FMU): each edge must be an edge of the exact flow
of its kind 1e-8 beyond the located interval, and the orbit must be a stable orbit of the exact
flow where the per-value scans put the edges.

COCO's example (Recipes for Continuation, Ex. 15.2, omega = 1.32, docs/continuation.md): the
period-1 impacting orbit's fold from the closed-form orbit of :mod:`mapcheck.impact_orbit`.
"""
from __future__ import annotations

import numpy as np
import pytest

from harness.analysis.windows.ode_windows import Family, shoot_family
from harness.dynamics.maps.shooting import StroboscopicMap
from mapcheck.impact_orbit import fold_velocity, one_impact_orbit, sigma_of_v
from tests.support.edges import ExactFlow, dominant, edge_sides, good
from tests.mapcheck.test_impact_orbit import coco, section_state

FIG9 = {"nu": 4.605170185988091, "Omega": 0.3059238689620112, "r": 0.9, "wall": 1, "Gamma": 48.9, "solver": 1}

#: How far beyond each end of an edge's interval the exact flow is asked about its two sides.
TOL = 1e-8


def _family(smap: StroboscopicMap, M: int, s: float, lo: float, hi: float) -> Family:
    """The family as the scans give it: the state the flow settles on at s (from the wall-free
    orbit), seen over [lo, hi] on a geometric grid."""
    w, _ = smap.iterate(s, np.zeros(2), 600)
    z = w + smap.offset(s)
    return Family(M, 1, lo, hi, s, z, ["up"], [(s, z)], True)


@pytest.fixture(scope="module")
def fig9(sim):
    smap = StroboscopicMap(sim, FIG9, 0.5)
    ratio = (400 / 0.05) ** (1 / 63)  # the chart's scan grid: 64 values over [0.05, 400]
    out = {}
    for M, s, seen in ((1, 17.341081779469544, (0.867, 400.0)), (2, 0.4900393480584413, (0.319, 0.752))):
        out[M] = shoot_family(smap, _family(smap, M, s, *seen), (0.005, 1600.0), 1e-4, ratio)
    flow = ExactFlow(FIG9["nu"], FIG9["Omega"], FIG9["r"], FIG9["Gamma"], "compliant", 0.5)
    return out, flow


def test_fig9_gamma_48_9_windows_are_located_not_lost(fig9) -> None:
    """Period 1 from its flip to beyond the range, period 2 from its flip to its graze, both sides
    of each located by the continuation (no "lost", no fallback)."""
    res, _ = fig9
    p1, p2 = res[1], res[2]
    assert p1["located"] == ["continuation", "continuation"] and p2["located"][0] == "continuation"
    assert p2["located"][1] == "continuation (gap = 0)" or p2["located"][1].startswith("continuation (contact change")
    assert (p1["lower"].kind, p1["upper"].kind, p1["upper"].sigma) == ("flip", "range", None)
    assert (p2["lower"].kind, p2["upper"].kind) == ("flip", "graze")
    # far from the per-value scans' answers: period 1 [17.04, 18.62], period 2 up to 0.526
    assert p1["lower"].sigma < 1.0 and 0.25 < p2["lower"].sigma < 0.35 and p2["upper"].sigma > 0.8


@pytest.mark.slow  # ~13 s: Newton and marches on the exact flow (pure Python)
def test_fig9_gamma_48_9_edges_are_edges_of_the_exact_flow(fig9) -> None:
    """Each located edge, TOL inside its interval: the exact flow's orbit (continued from one
    settled inside the window) is stable with one impact; TOL outside, across a flip it is unstable
    with a multiplier below -1, across a graze Newton finds no such orbit and the flow meets the
    wall twice in M periods.  And where the march and bisection ended the windows (period 1 below
    17.04, period 2 above 0.526) the exact flow settles on the stable orbit with one impact per period."""
    res, flow = fig9
    # seeds inside the windows where each is the only attractor (periods 1 and 2 coexist in 0.82-0.84)
    for M, side, s_seed in ((1, "lower", 0.85), (2, "lower", 0.3), (2, "upper", 0.75)):
        e = res[M][side]
        seed = flow.settle(s_seed, M, 150)
        assert good(seed) and seed.contacts.sum() == 1
        es = edge_sides(flow, M, seed, s_seed, e.kind, e.good, e.bad, TOL)
        assert good(es.inside) and es.inside.contacts.sum() == 1, (M, side)
        if e.kind == "flip":
            # the multipliers to ~1e-10 (the orbit's own finite differences carry ~1e-8 of rounding)
            mu = flow.multipliers(es.s_out, es.outside.z[0], M)
            assert es.outside.converged and dominant(mu).real < -1.0 and np.max(np.abs(mu)) > 1.0, (M, side, mu)
        else:
            assert not (es.outside.converged and es.outside.maximal) and es.contacts_out == 2
    for M, s in ((1, 16.0), (1, 2.0), (2, 0.53), (2, 0.8)):
        orb = flow.settle(s, M, 150)
        assert good(orb) and orb.contacts.sum() == 1 and len(orb.z) == M, (M, s)


def _coco_family(nu: float, Om: float) -> Family:
    """COCO's period-1 impacting orbit with impact velocity 6 (sigma = -0.62, on the stable side
    of the fold at v = 4.78) from the closed form, at the section, as a family seen there alone
    (the wall-free orbit coexists and attracts the scans' starts)."""
    orb = one_impact_orbit(nu, Om, 0.8, 6.0)
    s0, z0 = float(orb.sigma), section_state(nu, Om, orb)
    return Family(1, 1, s0, s0, s0, z0, ["up"], [(s0, z0)], False)


def test_coco_fold_is_the_closed_forms(sim) -> None:
    """COCO's example at omega = 1.32: the stable period-1 impacting orbit seeded at sigma = -0.62
    ends below in its fold, located by the continuation within 1e-8 of the closed form's
    (d sigma / dv = 0), its interval holding it, and above it leaves the range stable."""
    nu, Om = coco(1.32)
    params = {"nu": nu, "Omega": Om, "r": 0.8, "wall": 2, "solver": 1}
    smap = StroboscopicMap(sim, params, 0.5)
    r = shoot_family(smap, _coco_family(nu, Om), (-0.9, -0.3), 1e-6, 0.01, relative=False)
    truth = sigma_of_v(nu, Om, 0.8, fold_velocity(nu, Om, 0.8, 1.0, 10.0))
    lo, hi = r["lower"], r["upper"]
    assert r["located"] == ["continuation", "continuation"]
    assert lo.kind == "fold" and abs(lo.sigma - truth) < 1e-8, (lo.sigma, truth)
    assert min(lo.good, lo.bad) - 1e-10 <= truth <= max(lo.good, lo.bad) + 1e-10 and lo.bracket < 1e-8
    assert hi.kind == "range" and hi.sigma is None


def test_a_side_the_continuation_cannot_settle_is_bisected_and_says_so(sim, monkeypatch) -> None:
    """With a continuation budget too small to reach the fold, the lower edge comes from the march
    and bisection, to its own tolerance (1e-6 here) of the closed form's fold, and the entry says
    "bisection" with the reason."""
    from harness.analysis.windows import located_edges

    monkeypatch.setattr(located_edges, "SEGMENTS", 1)
    monkeypatch.setattr(located_edges, "SEGMENT_POINTS", 3)
    nu, Om = coco(1.32)
    smap = StroboscopicMap(sim, {"nu": nu, "Omega": Om, "r": 0.8, "wall": 2, "solver": 1}, 0.5)
    r = shoot_family(smap, _coco_family(nu, Om), (-0.9, -0.6), 1e-6, 0.01, relative=False)
    truth = sigma_of_v(nu, Om, 0.8, fold_velocity(nu, Om, 0.8, 1.0, 10.0))
    assert r["located"][0].startswith("bisection (") and "3 continuation steps" in r["located"][0]
    assert abs(r["lower"].sigma - truth) <= 1e-6 and r["lower"].bracket <= 1e-6
