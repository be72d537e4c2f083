"""Grazes located on their defining equation, against exact values.

Truth: COCO's impact example (Dankowicz & Schilder, *Recipes for Continuation*, Example 15.2:
x'' + 0.1 x' + x = A cos(omega t), wall at x = 1, restitution e = 0.8), in this project's units
(time in forcing periods, lengths in the gap: nu = 0.2 pi / omega, Omega = 2 pi / omega, r = 0.8,
a rigid wall, sigma = A / A_g - 1 with A_g = sqrt((1 - omega^2)^2 + (0.1 omega)^2), docs/theory.md
section 1).  Its period-1 impacting branch grazes at sigma = 0 exactly (the grazing orbit is the
wall-free orbit (4) touching the wall); its folds and flips come from the closed-form orbit of
:mod:`mapcheck.impact_orbit`, which shares nothing with the FMU or the harness.  A compliant
wall's wall-free orbit grazes at sigma = 0 exactly too.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from harness.dynamics.attractors.scans import find_attractors
from harness.dynamics.continuation.continue_orbit import continue_orbit
from harness.dynamics.continuation.graze_location import entry_velocity
from harness.dynamics.maps.periodic_map import PeriodMap, wall_free_offset
from mapcheck.impact_orbit import flip_velocities, fold_velocity, one_impact_orbit
from tests.mapcheck.test_impact_orbit import coco, section_state

#: COCO's omegas, and the smooth events of their period-1 impacting branch between sigma = 2
#: and the graze: the closed form's (fold: d sigma/dv = 0; flip: det(J + I) = 0 over v in [0.5, 5])
OMEGAS = {0.8: "flip", 1.0: "fold", 1.1: "fold", 1.32: "fold"}


@pytest.fixture(scope="module")
def coco_branches(sim, model) -> dict[float, tuple[dict, object]]:
    out = {}
    for omega in OMEGAS:
        nu, Om = coco(omega)
        p = {**model.defaults(), "nu": nu, "Omega": Om, "r": 0.8, "wall": 2, "solver": 1}
        (a,) = [x for x in find_attractors(sim, p, [2.0], M_max=2, transient=300).attractors if x.period == 1]
        out[omega] = p, continue_orbit(sim, p, 1, 2.0, a.points[0], p_range=(-0.9, 10.0), direction=-1, max_points=400)
    return out


@pytest.mark.parametrize("omega", sorted(OMEGAS))
def test_coco_graze_is_at_sigma_zero_within_its_interval(coco_branches, omega: float) -> None:
    """The impacting branch's graze: within 1e-8 of sigma = 0, its reported interval contains 0
    and is narrower than 1e-8, and it is not the last orbit that converged (which the rigid wall's
    square-root singularity keeps 1e-7 to 1e-3 short of the graze)."""
    _, br = coco_branches[omega]
    graze = [e for e in br.events if e.kind == "graze"][0]
    assert graze.quantity == "entry velocity"
    lo, hi = graze.interval
    assert abs(graze.value) < 1e-8 and lo <= 0.0 <= hi and hi - lo < 1e-8, (graze.value, graze.interval)
    assert graze.bracket == pytest.approx(hi - lo)
    assert abs(br.values[graze.index]) > 10 * (hi - lo)  # the last orbit: not the answer


@pytest.mark.parametrize("omega", sorted(OMEGAS))
def test_coco_fold_and_flip_match_the_closed_form(coco_branches, omega: float) -> None:
    """The smooth events of the same branches against the closed-form orbit, to 1e-8."""
    p, br = coco_branches[omega]
    kind = OMEGAS[omega]
    (event,) = [e for e in br.events if e.kind == kind]
    if kind == "fold":
        v = fold_velocity(p["nu"], p["Omega"], 0.8, 1e-6, 10.0)
    else:
        (v,) = flip_velocities(p["nu"], p["Omega"], 0.8, 0.5, 5.0)
    assert abs(event.value - one_impact_orbit(p["nu"], p["Omega"], 0.8, v).sigma) < 1e-8


@pytest.mark.parametrize("omega,v", [(0.8, 0.3), (1.0, 0.02), (1.32, 1e-3), (1.32, 0.5)])
def test_entry_velocity_is_the_closed_form_orbits(sim, model, omega: float, v: float) -> None:
    """The defining quantity itself: the entry velocity the free flight from the section reaches
    the wall with is the closed-form orbit's impact velocity, down to 1e-3 (to the crossing time's
    rounding, ~eps a / v in v: 1e-11 at v = 1e-3)."""
    nu, Om = coco(omega)
    orb = one_impact_orbit(nu, Om, 0.8, v)
    pmap = PeriodMap(sim, {**model.defaults(), "nu": nu, "Omega": Om, "r": 0.8, "wall": 2, "solver": 1}, "sigma")
    got = entry_velocity(pmap, section_state(nu, Om, orb), orb.sigma)
    assert got == pytest.approx(v, rel=1e-9, abs=2e-11)


def test_a_section_point_inside_a_compliant_wall_has_no_entry_velocity(sim, model) -> None:
    """A compliant wall's orbit may be in contact at the section (u > 0): no free flight starts
    there, so its period has no entry velocity (NaN), whatever the state.  (Random seed 171: the
    free flight from such a point had a maximum above the wall with no sign change before it, and
    the root search raised, ending the continuation of a flip; its bisection was 5e-5 off.)  A point
    just outside the wall still gets its entry velocity."""
    nu, Om = coco(1.0)
    pmap = PeriodMap(sim, {**model.defaults(), "nu": nu, "Omega": Om, "r": 0.8, "wall": 1, "Gamma": 151.0,
                           "solver": 1}, "sigma")
    for u in (1e-12, 1e-6, 1e-3, 0.1, 0.5):
        for v in np.linspace(-8.0, 8.0, 9):
            assert math.isnan(entry_velocity(pmap, np.array([u, v]), 0.77))
    nu_s, Om_s = coco(1.32)
    orb = one_impact_orbit(nu_s, Om_s, 0.8, 0.5)
    z = section_state(nu_s, Om_s, orb)
    assert z[0] < 0.0
    rigid = PeriodMap(sim, {**model.defaults(), "nu": nu_s, "Omega": Om_s, "r": 0.8, "wall": 2, "solver": 1}, "sigma")
    assert entry_velocity(rigid, z, orb.sigma) == pytest.approx(0.5, rel=1e-9)


@pytest.mark.parametrize("gamma_w,omega", [(10.0, 1.32), (100.0, 0.8), (1e4, 1.0)])
def test_compliant_wall_free_orbit_grazes_at_sigma_zero(sim, model, gamma_w: float, omega: float) -> None:
    """The wall-free orbit of a compliant wall, continued up in sigma: its graze (gap = 0) within
    1e-12 of sigma = 0, inside its interval; the orbit before it is the wall-free orbit itself."""
    nu, Om = coco(omega)
    p = {**model.defaults(), "nu": nu, "Omega": Om, "r": 0.8, "wall": 1, "Gamma": gamma_w, "solver": 1}
    z0 = wall_free_offset(-0.05, 0.5)
    br = continue_orbit(sim, p, 1, -0.05, z0, p_range=(-0.1, 0.1), direction=1, max_points=100)
    graze = [e for e in br.events if e.kind == "graze"][0]
    lo, hi = graze.interval
    assert graze.quantity == "gap" and abs(graze.value) < 1e-12 and lo <= 0.0 <= hi, graze
    i = graze.index
    assert np.max(np.abs(br.points[i, 0] - wall_free_offset(br.values[i], 0.5))) < 1e-9
    assert math.isfinite(graze.bracket) and graze.bracket < 1e-10


def test_a_test_function_through_a_pole_is_not_a_flip() -> None:
    """det(D + I) and det(D - I) change sign where a multiplier passes through infinity as well as
    through -1 and +1 (COCO's hybrid toolbox reports period doublings at a graze for that reason,
    the saltation's 1/v).  On u -> m(sigma) u with m = 1 / (sigma - 1/2) - 1/2 (its multiplier,
    exactly), the flip at m = -1 (sigma = -3/2) is located, and neither a flip nor a fold is
    reported at the pole sigma = 1/2 (without the check both were, at 0.5074)."""
    from harness.fmu.simulator import MappingSimulator

    def m(s: float) -> float:
        return 1.0 / (s - 0.5) - 0.5

    sim = MappingSimulator(lambda u, v, t, p: (m(p["sigma"]) * u, 0.5 * v, 1), {"sigma": 0.0},
                           lambda u, v, t, p: (np.array([[m(p["sigma"]), 0.0], [0.0, 0.5]]),
                                               np.array([-u / (p["sigma"] - 0.5) ** 2, 0.0])))
    z0 = wall_free_offset(-3.0, 0.5)  # the fixed point u = 0 sits at the section's offset: w = 0
    br = continue_orbit(sim, {}, 1, -3.0, z0, p_range=(-3.0, 1.0), direction=1, max_points=400, ds_max=0.02)
    assert br.values.max() > 0.9  # the branch went through the pole
    kinds = [(e.kind, e.value) for e in br.events if e.kind != "end"]
    assert len(kinds) == 1 and kinds[0][0] == "flip" and abs(kinds[0][1] + 1.5) < 1e-8, kinds


def _exact_after_impact_gap(p: dict, sigma: float, z) -> tuple[float, np.ndarray]:
    """The exact flow's one-impact orbit at ``sigma`` (mapcheck's shooting) and the distance to the
    wall of the highest point of its flight after the impact (dense exact states, the top refined
    on a parabola through the three highest samples)."""
    from mapcheck.exact import ExactOscillator
    from mapcheck.orbits import solve_periodic_orbit

    ex = ExactOscillator(p["nu"], p["Omega"], sigma, p["r"], 10.0, "rigid")
    # to 1e-13 in (u, v) (scale 1): the orbit's v is ~18 here, so rounding alone leaves ~4e-14 in F(z) - z
    orb = solve_periodic_orbit(lambda a, b: ex.state_at(a, b, 0.5, 1.5), np.asarray(z, float), 1, tol=1e-13,
                               scale=np.array([1e-1, 1.0]))
    assert orb.converged and int(orb.contacts.sum()) == 1
    (t_imp,) = [t for t, kind in ex.crossings(*orb.z[0], 0.5, 1.5) if kind == "impact"]
    t = np.linspace(t_imp + 1e-6, 1.5, 40001)
    u = ex.dense(*orb.z[0], t, 0.5)[0][:, 0]
    i = int(np.argmax(u[1:-1])) + 1
    a, b, c = u[i - 1], u[i], u[i + 1]
    top = b + 0.125 * (a - c) ** 2 / (2 * b - a - c)  # the parabola's vertex
    return -float(top), orb.z[0]


def test_an_impact_added_after_another_is_located_on_the_flights_gap(sim, coco_branches) -> None:
    """COCO's example at omega = 0.8, continued up from sigma = 2: the flight after the impact reaches
    the wall again near sigma = 4.668 (a second impact per period).  Located on that flight's gap,
    it agrees to 1e-9 with the exact flow's own zero of that gap (extrapolated from its one-impact
    orbits 1e-6 and 2e-6 below) and lies in its interval; the last orbit with one impact was short
    of it by 3e-9."""
    p, _ = coco_branches[0.8]
    (a,) = [x for x in find_attractors(sim, p, [2.0], M_max=2, transient=300).attractors if x.period == 1]
    br = continue_orbit(sim, p, 1, 2.0, a.points[0], p_range=(-0.9, 10.0), direction=1, max_points=400)
    (graze,) = [e for e in br.events if e.kind == "graze"]
    assert graze.quantity == "gap" and "after its impact 1" in graze.note
    g1, z = _exact_after_impact_gap(p, graze.value - 1e-6, graze.point)
    g2, _ = _exact_after_impact_gap(p, graze.value - 2e-6, z)
    exact = graze.value - 1e-6 + g1 * 1e-6 / (g2 - g1)
    lo, hi = graze.interval
    assert abs(graze.value - exact) < 1e-9 and hi - lo < 1e-9, (graze.value, exact, graze.interval)
    assert graze.value - br.values[graze.index] > 1e-9  # not the last orbit with one impact


def test_a_flip_curve_runs_to_the_end_of_a_range_next_to_the_fmus_domain(sim, coco_branches) -> None:
    """COCO's flip at omega = 0.8 continued in the restitution r from 0.8 to 0.97: near the range's
    end the corrector's steps reach r > 1, which the FMU refuses; that is a failed step, not the end
    of the curve (it was: chart over r reported the edge "not continued").  The curve reaches the
    range's end, every point in the FMU's domain, each a flip of the closed-form orbit at its r."""
    from harness.dynamics.curves.event_curves import continue_event

    p, br = coco_branches[0.8]
    (flip,) = [e for e in br.events if e.kind == "flip"]
    curve = continue_event(sim, p, "flip", 1, flip.value, flip.point, "r", (0.8, 0.97), log2=False,
                           sigma_range=(-0.6, 1.0), ds_max=0.5)
    assert curve.end["reason"] == "range" and curve.p2.max() <= 1.0 and curve.p2[-1] >= 0.97 - 1e-9, curve.end
    for r, s in list(zip(curve.p2, curve.sigma))[:: max(1, len(curve.p2) // 4)]:
        if r > 0.97:
            continue
        vs = flip_velocities(p["nu"], p["Omega"], float(r), 0.5, 5.0)
        assert min(abs(s - one_impact_orbit(p["nu"], p["Omega"], float(r), v).sigma) for v in vs) < 1e-8, (r, s)
