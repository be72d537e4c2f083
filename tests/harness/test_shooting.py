"""Window edges by Newton shooting on the real FMU are measured, never echoed from the guide.

The guide of :func:`harness.dynamics.maps.shooting.map_guided_windows` is the map's window; shooting
starts inside it and brackets each edge itself.  A march from the window's centre with step
width/6 lands exactly on the map's edges, and with xtol 1e-4 a bisection that started there would
never move off them: the "ODE" window would be the map's, to 16 digits.
Independent truth: the same shooting at a 100x finer tolerance must fall inside the coarse
brackets (and those brackets must come from the shooting, not from the guide).
"""
from __future__ import annotations

import math

import pytest

from harness.dynamics.maps.shooting import StroboscopicMap, map_guided_windows
from mapcheck.coeffs import coefficients
from mapcheck.linear import invert_alpha_gamma

#: A case where shooting once failed: (alpha, gamma) = (0.5, 0.05), r = 0.8, compliant wall Gamma = 10,
#: the A~ map's period-4 window (closed-form maximal orbits, mapcheck).
GUIDE_M4 = (0.0007036372600123284, 0.004341898116748781)


@pytest.fixture(scope="module")
def setup(model, sim):
    inv = invert_alpha_gamma(0.5, 0.05)
    c = coefficients(inv.nu, inv.Omega, 0.8, "compliant")
    params = {**model.defaults(), "nu": inv.nu, "Omega": inv.Omega, "r": 0.8, "Gamma": 10.0, "wall": 1}
    return StroboscopicMap(sim, params, 0.5), c


def _check_measured(res: dict, M: int, guide: tuple[float, float], xtol: float) -> None:
    w = res["windows"][M]
    assert w is not None and res["unresolved"] == {}
    for edge, g, (good, bad), width in zip(w, guide, res["intervals"][M], res["brackets"][M]):
        # the edge is the midpoint of a bracket the shooting found and bisected to xtol
        assert bad is not None and 0 < abs(bad - good) <= xtol
        assert edge == pytest.approx(0.5 * (good + bad), abs=1e-15)
        assert width == pytest.approx(abs(bad - good))
        # ... and not the guide's number (a march of width/6 lands on it exactly)
        assert abs(edge - g) > 1e-12 * g
        assert good != g and bad != g


def test_edges_are_measured_not_the_maps(setup) -> None:
    smap, c = setup
    coarse = map_guided_windows(smap, c, {4: GUIDE_M4}, (1e-4, 1.0), 1e-4)
    _check_measured(coarse, 4, GUIDE_M4, 1e-4)
    fine = map_guided_windows(smap, c, {4: GUIDE_M4}, (1e-4, 1.0), 1e-6)
    _check_measured(fine, 4, GUIDE_M4, 1e-6)
    # the fine edges lie in the coarse brackets (up to the fine bracket's half-width)
    for edge, (good, bad) in zip(fine["windows"][4], coarse["intervals"][4]):
        lo, hi = min(good, bad), max(good, bad)
        assert lo - 1e-6 <= edge <= hi + 1e-6
    assert coarse["kinds"][4][0] == fine["kinds"][4][0] == "flip"


def test_march_step_does_not_depend_on_xtol(setup) -> None:
    """xtol larger than the march step: the march's bracket is reported as its midpoint, still
    a bracket the shooting found, never a march point (which is the guide's centre + k step)."""
    smap, c = setup
    res = map_guided_windows(smap, c, {4: GUIDE_M4}, (1e-4, 1.0), 5e-3)
    (lo_good, lo_bad), (hi_good, hi_bad) = res["intervals"][4]
    width = GUIDE_M4[1] - GUIDE_M4[0]
    # one march step: width / 6.3, whatever xtol is
    assert abs(lo_bad - lo_good) == pytest.approx(width / 6.3, rel=1e-9)
    assert abs(hi_bad - hi_good) == pytest.approx(width / 6.3, rel=1e-9)
    for e, g in zip(res["windows"][4], GUIDE_M4):
        assert abs(e - g) > 1e-12


def test_unbracketed_edges_are_unresolved(setup) -> None:
    """Period 1 has no upper edge below sigma = 0.26 (its window reaches sigma -> inf): the
    upper edge is reported as unresolved with the interval searched, never as a number; a
    guide window where no stable maximal orbit exists gives two unresolved edges."""
    smap, c = setup
    res = map_guided_windows(smap, c, {1: (0.15, None), 5: (0.5, 0.6)}, (1e-4, 0.26), 1e-3)
    lo, hi = res["windows"][1]
    assert hi is None and lo is not None and math.isfinite(lo)
    assert res["kinds"][1][1] == "range" and res["unresolved"][1] == ["upper"]
    good, bad = res["intervals"][1][1]
    assert bad is None and good == pytest.approx(0.26)
    assert res["windows"][5] is None
    assert res["kinds"][5] == ("unresolved", "unresolved") and res["unresolved"][5] == ["lower", "upper"]
    assert all(good is None and bad is None for good, bad in res["intervals"][5])
