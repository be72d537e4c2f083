"""The global search of ``windows`` (:mod:`harness.runs.basins.global_search`) and the routes it
joins (:mod:`harness.analysis.windows.routes`): orbits told apart by their point sets, two orbits
of one kind two windows, the starts a function of the parameter set only.

The oracle is the exact flow (:mod:`mapcheck.exact`, an implementation independent of the FMU and
its batch kernel): every attractor the search reports is a stable periodic orbit of the exact flow
with its period and impacts, and random starts iterated on the exact flow reach one of them.
"""
from __future__ import annotations

import numpy as np
import pytest

from harness.analysis.windows.routes import (
    ROUTE_SEARCH,
    RouteFamily,
    Sighting,
    attractors_at,
    collapsed,
    families_from_routes,
    merge_results,
)
from harness.analysis.windows.summary import coexistence
from harness.config import SamplingSpec
from harness.dynamics.attractors.identity import hausdorff
from harness.errors import HarnessInputError
from harness.runs.basins.global_search import Region, global_search, seed_of, spread_starts
from tests.support.edges import ExactFlow

#: A lightly damped oscillator on a stiff compliant wall, just below grazing: random starts on the
#: exact flow reach a period-8 orbit with 4 impacts (most of them) and a period-10 orbit with 5
#: (a few per cent), the scans only the first (found by brute force: many random starts).
LIGHT = dict(nu=0.1, Omega=2.25, r=0.8, Gamma=100.0)
SIGMA = -0.002


def _params(sigma: float = SIGMA) -> dict:
    return dict(LIGHT, wall=1, sigma=sigma, solver=1)


@pytest.fixture(scope="module")
def found():
    s = SamplingSpec(theta=0.5, n_transient=400, n_samples=40, tol=1e-6)
    return global_search(_params(), s, Region.around_orbits(SIGMA, 0.5, False), 1000, workers=1)


def test_every_attractor_found_is_a_stable_orbit_of_the_exact_flow(found) -> None:
    """Each attractor (period M, k impacts) is a fixed point of the exact flow's M-period map to
    1e-9 with k contacts per M periods and every multiplier inside the unit circle; the shares add
    up with the other starts to all of them."""
    flow = ExactFlow(LIGHT["nu"], LIGHT["Omega"], LIGHT["r"], LIGHT["Gamma"], "compliant")
    kinds = {a.key for a in found.attractors}
    assert "8/4" in kinds and found.attractors[0].share > 0.5
    for a in found.attractors:
        orb = flow.orbit(SIGMA, a.period, a.points[-1])
        assert orb.converged and int(np.sum(orb.contacts)) == a.impacts
        assert hausdorff(np.asarray(orb.z), a.points) < 1e-4
        assert np.max(np.abs(flow.multipliers(SIGMA, orb.z[0], a.period))) < 1.0
    assert sum(a.starts for a in found.attractors) + sum(found.other.values()) == found.n_starts


@pytest.mark.slow  # 900 periods of the exact flow in Python
def test_random_starts_on_the_exact_flow_reach_the_attractors_found(found) -> None:
    """Three random starts of the region iterated 300 periods on the exact flow each end on one of
    the attractors the search lists (within 1e-3 of its points)."""
    flow = ExactFlow(LIGHT["nu"], LIGHT["Omega"], LIGHT["r"], LIGHT["Gamma"], "compliant")
    step = flow.step_of(SIGMA)
    rng = np.random.default_rng(7)
    reg = found.region
    for _ in range(3):
        z = (rng.uniform(reg.u_lo, reg.u_hi), rng.uniform(reg.v_lo, reg.v_hi))
        for _ in range(300):
            *z, _c = step(*z)
        near = [np.min(np.max(np.abs(a.points - np.asarray(z)), axis=1)) for a in found.attractors]
        assert min(near) < 1e-3, f"a start of the exact flow ends at {z}, on no attractor found"


def test_the_starts_depend_on_the_parameter_set_only() -> None:
    """Grid plus random starts, as many as asked (the grid rounded up), inside the region, the same
    for the same parameters whatever else is asked; a rigid wall keeps them outside it."""
    reg = Region.around_orbits(-0.1, 0.5, True)
    us, vs = spread_starts(reg, 1000, seed_of(_params(-0.1)))
    assert us.size >= 1000 and np.all(us < 0) and np.all((vs > reg.v_lo) & (vs < reg.v_hi))
    again = spread_starts(reg, 1000, seed_of(dict(reversed(list(_params(-0.1).items())))))
    assert np.array_equal(us, again[0]) and np.array_equal(vs, again[1])
    assert not np.array_equal(us, spread_starts(reg, 1000, seed_of(_params(-0.2)))[0])
    with pytest.raises(HarnessInputError, match="starts"):
        spread_starts(reg, 0, 1)
    with pytest.raises(HarnessInputError, match="path"):
        global_search(_params(), SamplingSpec(), reg, 10, path="gpu")


def _ring(centre: float, M: int, radius: float = 0.5) -> np.ndarray:
    t = 2 * np.pi * np.arange(M) / M
    return np.column_stack([centre + radius * np.cos(t), radius * np.sin(t)])


def test_two_orbits_of_one_kind_at_one_sigma_are_two_attractors() -> None:
    """Sightings of one kind whose point sets lie apart are two attractors, the same orbit seen by
    two routes one; a sampled orbit whose points repeat after one period is period 1."""
    a, b = _ring(-1.0, 2), _ring(-3.0, 2)
    got = attractors_at([Sighting(0, 0.1, 2, 2, a, {"scan up"}), Sighting(0, 0.1, 2, 2, b, {ROUTE_SEARCH}, 0.3),
                         Sighting(0, 0.1, 2, 2, a[::-1] + 1e-4, {ROUTE_SEARCH}, 0.6)])
    assert len(got) == 2
    assert got[0].routes == {"scan up", ROUTE_SEARCH} and got[0].share == pytest.approx(0.6)
    spiral = np.array([[-2.0, 0.0]] * 5) + 1e-6 * np.arange(5)[:, None]
    M, k, pts = collapsed(5, 0, spiral)
    assert (M, k) == (1, 0) and pts.shape == (1, 2)
    assert collapsed(2, 2, a)[0] == 2


def test_two_coexisting_orbits_of_one_kind_are_two_windows_and_two_attractors() -> None:
    """Two tracks of period 2 seen at the same sigma values become two families (not one, as a
    merge by kind did) and stay two after the shooting even with equal edges; the coexistence
    table counts three attractors with the wall-free orbit."""
    import xarray as xr

    grid = np.linspace(-0.05, -0.01, 5)
    u = np.full((5, 2, 6), np.nan)
    v = np.full((5, 2, 6), np.nan)
    for j, c in enumerate((-1.0, -3.0)):
        u[:, j, :] = np.tile(_ring(c, 2)[:, 0], 3)
        v[:, j, :] = np.tile(_ring(c, 2)[:, 1], 3)
    ds = xr.Dataset({"period": (("sigma", "direction"), np.full((5, 2), 2)),
                     "orbit_impacts": (("sigma", "direction"), np.full((5, 2), 1)),
                     "u": (("sigma", "direction", "sample"), u), "v": (("sigma", "direction", "sample"), v)},
                    coords={"sigma": grid, "direction": ["up", "down"]})
    fams = families_from_routes(grid, ds, None, None, False, 0.5)
    kinds = sorted((f.M, f.impacts) for f in fams)
    assert kinds == [(1, 0), (2, 1), (2, 1)]
    assert all(isinstance(f, RouteFamily) for f in fams)

    class Edge:
        def __init__(self, s):
            self.sigma = s

    two = [f for f in fams if f.M == 2]
    results = [{"family": f, "resolved": True, "lower": Edge(-0.06), "upper": Edge(0.01)} for f in two]
    assert len(merge_results(results, 1e-6)) == 2  # seen at the same sigma: two orbits
    rows = [{"M": 1, "impacts": 0, "lo": None, "hi": 0.0, "resolved": True},
            {"M": 2, "impacts": 1, "lo": -0.06, "hi": 0.01, "resolved": True},
            {"M": 2, "impacts": 1, "lo": -0.04, "hi": 0.02, "resolved": True}]
    table = coexistence(rows, (-0.05, 0.05))
    assert max(len(c["attractors"]) for c in table) == 3
    assert any("orbit 2" in a for c in table for a in c["attractors"])


def test_one_parameter_set_as_chart_would_search_it() -> None:
    """:func:`search_parameter_set` on a lightly damped rigid wall just below grazing: no start
    inside the wall, and its main attractor (period 3, 2 impacts) a stable orbit of the exact flow."""
    from harness.runs.basins.global_search import search_parameter_set

    got = search_parameter_set(dict(nu=0.1, Omega=2.5, r=0.8, wall=2, sigma=-0.005, solver=1), 0.5, 500)
    assert got.region.u_hi < 0 and got.other["invalid"] == 0
    top = got.attractors[0]
    assert top.key == "3/2" and top.share > 0.5  # the rest still settling after the short transient
    flow = ExactFlow(0.1, 2.5, 0.8, 10.0, "rigid")
    orb = flow.orbit(-0.005, 3, top.points[-1])
    assert orb.converged and int(np.sum(orb.contacts)) == 2
    assert np.max(np.abs(flow.multipliers(-0.005, orb.z[0], 3))) < 1.0


def test_the_fmu_path_labels_the_starts_as_the_kernel_does(model) -> None:
    """The same 16 starts through the FMU with CVODE (the path of a nonlinear contact law, or of
    --global-path fmu; one process here) reach the attractors the batch kernel finds from them,
    with the same counts, the orbits' points within 1e-5."""
    params = dict(nu=0.1, Omega=2.5, r=0.8, wall=2, sigma=-0.005)
    s = SamplingSpec(theta=0.5, n_transient=200, n_samples=24, tol=1e-6)
    reg = Region.around_orbits(-0.005, 0.5, True)
    fmu = global_search({**params, "solver": 0}, s, reg, 16, path="fmu", fmu=model, workers=1, seed=3)
    kernel = global_search({**params, "solver": 1}, s, reg, 16, path="batch", workers=1, seed=3)
    assert fmu.path == "fmu" and kernel.path == "batch" and fmu.attractors
    assert sorted((a.key, a.starts) for a in fmu.attractors) == sorted((a.key, a.starts) for a in kernel.attractors)
    for a in fmu.attractors:
        b = next(x for x in kernel.attractors if x.key == a.key)
        assert hausdorff(a.points, b.points) < 1e-5
