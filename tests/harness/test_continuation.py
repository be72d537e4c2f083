"""Continuation of the FMU's periodic orbits against independent truth.

Truth: mapcheck's closed-form solution of the ODE (:mod:`mapcheck.exact`) with mapcheck's own
Newton shooting (:func:`mapcheck.orbits.solve_periodic_orbit`, finite differences): a code path
that shares nothing with the FMU, its sensitivities or the harness's continuation.  Located
events are checked by solving the closed form on both sides of each edge (the brute-force
check: the multiplier or the contact pattern must change across it).
"""
from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from harness.dynamics.attractors.scans import find_attractors
from harness.dynamics.continuation.continue_orbit import continue_orbit, switch_at_flip
from mapcheck.exact import ExactOscillator
from mapcheck.orbits import solve_periodic_orbit

ROOT = Path(__file__).resolve().parents[2]
FIG9 = tomllib.loads((ROOT / "harness" / "experiments" / "fig9.toml").read_text())["model"]
THETA = 0.5
SCALE = np.array([1e-2, 1e-1])


def closed_form_orbit(p: dict, sigma: float, z0, M: int):
    """mapcheck's own shooting on the exact flow at the section phase THETA."""
    wall = {1: "compliant", 2: "rigid"}[int(p["wall"])]
    ex = ExactOscillator(p["nu"], p["Omega"], sigma, p["r"], p.get("Gamma", 10.0), wall)

    def step(u: float, v: float):
        return ex.state_at(u, v, THETA, THETA + 1.0)

    return solve_periodic_orbit(step, np.asarray(z0, dtype=float), M, tol=1e-10, scale=SCALE, max_iter=10)


@pytest.fixture(scope="module")
def fig9(model) -> dict:
    return {**model.defaults(), **FIG9, "wall": 1, "solver": 1}


@pytest.fixture(scope="module")
def under(model) -> dict:
    """An underdamped oscillator (alpha ~ -1.05), rigid wall."""
    return {**model.defaults(), "nu": 0.8, "Omega": 2.5, "r": 0.8, "wall": 2, "solver": 1}


def _seed(sim, params, sigma, M=None):
    scan = find_attractors(sim, params, [sigma], M_max=4, transient=300)
    cands = [a for a in scan.attractors if M is None or a.period == M]
    assert cands, f"no attractor at sigma = {sigma}"
    return cands[0]


def _rotations_match(z_fmu: np.ndarray, z_cf: np.ndarray, tol: float) -> bool:
    return any(np.max(np.abs(np.roll(z_cf, k, axis=0) - z_fmu)) < tol for k in range(len(z_cf)))


def test_attractors_kept_apart_and_refined(sim, fig9, under) -> None:
    """Between the period-1 flip (0.8121) and the period-2 window's graze (0.8190) of Figure 9 the
    one-impact period-1 and period-2 orbits coexist: both are found, by different scans, and kept
    apart; each is the closed form's orbit with the closed form's multipliers."""
    scan = find_attractors(sim, fig9, [0.81, 0.815, 0.818, 0.82], M_max=4, transient=300)
    assert {a.label for a in scan.at(0.81)} == {"P2/1"}
    assert {a.label for a in scan.at(0.815)} == {"P1/1", "P2/1"}
    assert {a.label for a in scan.at(0.818)} == {"P1/1", "P2/1"}
    assert {a.label for a in scan.at(0.82)} == {"P1/1"}
    rigid = find_attractors(sim, under, [1.7], M_max=4, transient=300)
    for a in scan.attractors + rigid.attractors:
        params = fig9 if a in scan.attractors else under
        orb = closed_form_orbit(params, a.value, a.points[0], a.period)
        assert orb.converged and _rotations_match(a.points, orb.z, 1e-8)
        assert np.allclose(np.sort_complex(a.multipliers), np.sort_complex(orb.multipliers), atol=1e-5)
    (p1,) = rigid.attractors
    # a sweep of the underdamped rigid case: multipliers -0.921, -0.312 at 1.70
    assert p1.label == "P1/1" and np.allclose(np.sort(p1.multipliers.real), [-0.921, -0.312], atol=1e-3)


def test_branch_matches_closed_form(sim, fig9) -> None:
    """Points of the Figure 9 period-1 branch, stable and unstable (below the flip), are the
    closed form's orbits: state to 1e-8, multipliers to 1e-5."""
    a = _seed(sim, fig9, 1.0, 1)
    br = continue_orbit(sim, fig9, 1, 1.0, a.points[0], p_range=(0.3, 1.3), direction=-1)
    assert len(br) > 10 and not br.stable.all() and br.stable.any()
    for i in np.linspace(0, len(br) - 1, 6).astype(int):
        orb = closed_form_orbit(fig9, br.values[i], br.points[i, 0] + 1e-5, 1)
        assert orb.converged
        assert np.max(np.abs(orb.z[0] - br.points[i, 0])) < 1e-8
        assert np.allclose(np.sort_complex(orb.multipliers), np.sort_complex(br.multipliers[i]), atol=1e-5)
        assert int(orb.contacts.sum()) == int(br.impacts[i])


def _check_flip(params, sigma_f, z, M, inside: float, delta: float = 1e-6) -> None:
    """Brute force across a located flip: the closed form's largest |multiplier| is < 1 on the
    inside and > 1 on the outside, at ``delta`` from the edge (the closed form's difference
    multipliers are good to ~1e-7 on the compliant wall, ~5e-6 on the rigid one)."""
    for side, stable in ((inside, True), (-inside, False)):
        orb = closed_form_orbit(params, sigma_f + side * delta, z, M)
        assert orb.converged
        assert (np.abs(orb.multipliers).max() < 1.0) == stable


def _check_graze(params, sigma_g, z, M, inside: float) -> None:
    """Brute force across a located graze: the closed form's orbit has one contact per period
    on the inside, and no orbit with that contact pattern exists 1e-6 beyond."""
    orb_in = closed_form_orbit(params, sigma_g + inside * 1e-6, z, M)
    assert orb_in.converged and orb_in.maximal
    orb_out = closed_form_orbit(params, sigma_g - inside * 1e-6, orb_in.z[0], M)
    assert not (orb_out.converged and orb_out.maximal)


#: Window edges of Figure 9 from earlier harness shooting (xtol 1e-5): a consistency check only;
#: the truth is the closed form on both sides of every edge.
FIG9_PREVIOUS = {1: (0.812073, None), 2: (0.289969, 0.819002), 3: (0.173086, 0.249713)}


@pytest.mark.parametrize("M,seed,lo,hi", [(1, 1.0, 0.7, 1.2), (2, 0.5, 0.25, 0.85), (3, 0.2, 0.15, 0.3)])
def test_fig9_windows(sim, fig9, M, seed, lo, hi) -> None:
    a = _seed(sim, fig9, seed, M)
    down = continue_orbit(sim, fig9, M, seed, a.points[0], p_range=(lo, hi), direction=-1)
    flip = [e for e in down.events if e.kind == "flip"][0]
    assert flip.bracket < 1e-8
    assert abs(flip.value - FIG9_PREVIOUS[M][0]) < 2e-5
    _check_flip(fig9, flip.value, flip.point, M, inside=+1.0)
    if FIG9_PREVIOUS[M][1] is not None:
        up = continue_orbit(sim, fig9, M, seed, a.points[0], p_range=(lo, hi), direction=1)
        graze = [e for e in up.events if e.kind == "graze"][0]
        assert graze.bracket < 1e-8 and abs(graze.value - FIG9_PREVIOUS[M][1]) < 2e-5
        _check_graze(fig9, graze.value, graze.point, M, inside=-1.0)


def test_switch_at_flip_reaches_period_two_window(sim, fig9) -> None:
    """The period-2 branch born at the period-1 flip is unstable, meets the stable period-2 window
    at its upper graze (a nonsmooth fold) and runs down to the window's flip."""
    a = _seed(sim, fig9, 1.0, 1)
    br = continue_orbit(sim, fig9, 1, 1.0, a.points[0], p_range=(0.2, 1.2), direction=-1)
    flip = [e for e in br.events if e.kind == "flip"][0]
    b2 = switch_at_flip(sim, fig9, br, flip, p_range=(0.2, 1.2), max_points=100)
    assert b2 is not None and b2.M == 2
    kinds = [e.kind for e in b2.events]
    assert kinds[:2] == ["graze", "flip"]
    graze, flip2 = b2.events[0], b2.events[1]
    assert "nonsmooth fold" in graze.note and abs(graze.value - 0.819005) < 1e-5
    assert abs(flip2.value - 0.289971) < 1e-5
    _check_flip(fig9, flip2.value, flip2.point, 2, inside=+1.0)


def test_underdamped_rigid_window(sim, under) -> None:
    """The underdamped rigid case: the one-impact period-1 orbit is stable from a flip at sigma ~ 1.60
    up to the end of the range (3), with multipliers ~ -0.969 at 1.64."""
    a = _seed(sim, under, 1.7, 1)
    down = continue_orbit(sim, under, 1, 1.7, a.points[0], p_range=(1.0, 3.0), direction=-1, max_points=60)
    flip = [e for e in down.events if e.kind == "flip"][0]
    assert 1.59 < flip.value < 1.62
    _check_flip(under, flip.value, flip.point, 1, inside=+1.0, delta=1e-4)
    up = continue_orbit(sim, under, 1, 1.7, a.points[0], p_range=(1.0, 3.0), direction=1)
    assert up.stable.all() and up.events[-1].note.startswith("left the range")
    # the stable two-impact period-2 orbit at 1.55 is the one born at that flip: its branch runs
    # into the period-1 orbit there (a branch point, located on the period-1 orbit's flip)
    p2 = _seed(sim, under, 1.55, 2)
    b2 = continue_orbit(sim, under, 2, 1.55, p2.points[0], p_range=(1.0, 3.0), direction=1)
    meet = [e for e in b2.events if e.kind == "flip"]
    assert p2.label == "P2/2" and meet and abs(meet[0].value - flip.value) < 1e-7
    at164 = _seed(sim, under, 1.64, 1)
    orb = closed_form_orbit(under, 1.64, at164.points[0], 1)
    assert orb.converged
    assert abs(np.abs(orb.multipliers).max() - 0.969) < 2e-3
    assert abs(np.abs(at164.multipliers).max() - np.abs(orb.multipliers).max()) < 1e-5


def test_underdamped_gamma100_window(sim, under) -> None:
    """Gamma = 100: the one-impact period-2 orbit, stable up to its flip near sigma = 0.15."""
    params = {**under, "wall": 1, "Gamma": 100.0}
    a = _seed(sim, params, 0.1, 2)
    assert a.impacts == 1
    up = continue_orbit(sim, params, 2, 0.1, a.points[0], p_range=(0.0, 0.5), direction=1)
    flip = [e for e in up.events if e.kind == "flip"][0]
    assert 0.12 < flip.value < 0.2
    _check_flip(params, flip.value, flip.point, 2, inside=-1.0)


def test_exact_and_difference_parameter_derivative_agree(sim, fig9) -> None:
    """Continuation in Gamma (d/dGamma by central differences, not the FMU's S outputs): its
    points are the closed form's orbits at their Gamma."""
    params = {**fig9, "sigma": 0.5}
    a = _seed(sim, params, 0.5, 2)
    br = continue_orbit(sim, params, 2, 10.0, a.points[0], param="Gamma", p_range=(8.0, 12.0), max_points=5)
    assert br.param == "Gamma" and len(br) >= 2
    orb = closed_form_orbit({**params, "Gamma": float(br.values[-1])}, 0.5, br.points[-1, 0], 2)
    assert orb.converged and np.max(np.abs(orb.z[0] - br.points[-1, 0])) < 1e-8


def test_branch_dataset(sim, fig9, tmp_path) -> None:
    from harness.dynamics.continuation.branch import branches_dataset
    from harness.io.results import read_netcdf, write_netcdf

    a = _seed(sim, fig9, 1.0, 1)
    br = continue_orbit(sim, fig9, 1, 1.0, a.points[0], p_range=(0.7, 1.1), direction=-1, max_points=30)
    ds = branches_dataset([br], ["down"], {"model.nu": fig9["nu"]})
    write_netcdf(ds, tmp_path / "b.nc")
    back = read_netcdf(tmp_path / "b.nc")
    assert np.allclose(back["sigma"].values, br.values)
    assert list(back["event"].values).count("flip") == 1
    assert int(back["stable"].values[0]) == 1


def _mapping(step, derivative):
    from harness.fmu.simulator import MappingSimulator

    return MappingSimulator(step, {"sigma": 0.0}, derivative)


def test_fold_flip_ns_on_maps_with_known_bifurcations() -> None:
    """The event machinery on maps whose bifurcations are known exactly (the FMU's cases above
    have no smooth fold or Neimark-Sacker point): u -> u + sigma - u^2 has its fold at sigma = 0
    and, on the branch u = sqrt(sigma), its flip at sigma = 1 (multiplier 1 - 2 sqrt(sigma));
    z -> (1/2 + sigma) R(1) z has a Neimark-Sacker point at sigma = 1/2."""
    quad = _mapping(lambda u, v, t, p: (u + p["sigma"] - u * u, 0.5 * v, 1),
                    lambda u, v, t, p: (np.array([[1.0 - 2.0 * u, 0.0], [0.0, 0.5]]), np.array([1.0, 0.0])))
    down = continue_orbit(quad, {}, 1, 0.25, [0.5, 0.0], p_range=(-1.0, 2.0), direction=-1,
                          max_points=80)
    fold = [e for e in down.events if e.kind == "fold"]
    assert fold and abs(fold[0].value) < 1e-8 and abs(fold[0].multipliers.real.max() - 1.0) < 1e-4
    # beyond the fold the branch is the unstable u = -sqrt(sigma)
    assert not down.stable[-1] and down.values[-1] > 0
    up = continue_orbit(quad, {}, 1, 0.25, [0.5, 0.0], p_range=(-1.0, 2.0), direction=1)
    flip = [e for e in up.events if e.kind == "flip"]
    assert flip and abs(flip[0].value - 1.0) < 1e-8

    c, s = np.cos(1.0), np.sin(1.0)
    R = np.array([[c, -s], [s, c]])

    def rot(u, v, t, p):
        z = (0.5 + p["sigma"]) * (R @ (np.array([u, v]) - o(p))) + o(p)
        return z[0], z[1], 1

    def o(p):  # the map's fixed point sits at the section's offset, so w = 0 along the branch
        return np.array([(1.0 + p["sigma"]) * np.cos(np.pi) - 1.0, 0.0])

    def drot(u, v, t, p):
        J = (0.5 + p["sigma"]) * R
        return J, (np.eye(2) - J) @ np.array([-1.0, 0.0]) + R @ (np.array([u, v]) - o(p))

    ns = continue_orbit(_mapping(rot, drot), {}, 1, 0.0, o({"sigma": 0.0}), p_range=(-0.4, 1.0), direction=1)
    found = [e for e in ns.events if e.kind == "ns"]
    assert found and abs(found[0].value - 0.5) < 1e-8 and abs(abs(found[0].multipliers[0]) - 1.0) < 1e-8


def test_newton_steps_into_a_rigid_wall_are_failed_steps_not_errors(sim, model) -> None:
    """A Newton iterate inside a rigid wall is not a state (the FMU refuses it at initialization).
    It is a failed evaluation and the search goes on, not an error that ends find_attractors
    (nu = 0.5, Omega = 1, r = 0.5, rigid: u0 = 0.077 inside the wall)."""
    from harness.dynamics.maps.periodic_map import PeriodMap, refine_orbit

    p = {**model.defaults(), "nu": 0.5, "Omega": 1.0, "r": 0.5, "wall": 2, "solver": 1}
    pmap = PeriodMap(sim, p, "sigma", THETA)
    inside = np.array([0.077, -0.8]) - pmap.offset(1.0)
    ev = pmap.evaluate(inside, 1.0, 1)
    assert not np.any(np.isfinite(ev.image)) and not np.any(np.isfinite(ev.J))
    assert not refine_orbit(pmap, inside, 1.0, 1)[2]
    scan = find_attractors(sim, p, np.geomspace(0.05, 20.0, 9), M_max=3, transient=300)
    assert "P3/1" in {a.label for a in scan.attractors}
    for a in scan.attractors:  # what it finds is the exact flow's orbit
        orb = closed_form_orbit(p, a.value, a.points[0], a.period)
        assert orb.converged and _rotations_match(a.points, orb.z, 1e-7)


def test_an_impact_added_to_a_chatter_is_located_not_lost(sim, model) -> None:
    """On a rigid wall a flight between two impacts of one period can reach the wall again (an
    impact added to the chatter); the gap of the free periods does not see it and the corrector
    just fails there.  The branch does not end as 'orbit lost': the flow beyond says the
    contacts changed, and the event is located.  Truth: the exact flow on both sides."""
    p = {**model.defaults(), "nu": 1.0, "Omega": 10.0, "r": 0.3, "wall": 2, "solver": 1}
    a = _seed(sim, p, 2.0, 1)
    assert a.label == "P1/3"
    br = continue_orbit(sim, p, 1, 2.0, a.points[0], "sigma", (1.0, 3.0), 1.0, ds_max=0.1)
    (e,) = [e for e in br.events if e.kind == "graze"]
    assert 2.2 < e.value < 2.3 and e.bracket < 1e-7
    below = closed_form_orbit(p, e.value * (1 - 1e-7), e.point, 1)
    assert below.converged and int(np.sum(below.contacts)) == 3
    ex = ExactOscillator(p["nu"], p["Omega"], e.value * (1 + 1e-4), p["r"], 10.0, "rigid")
    z = np.asarray(e.point, dtype=float)
    for _ in range(60):  # the exact flow just beyond settles with one more impact per period
        u, v, c = ex.state_at(z[0], z[1], THETA, THETA + 1.0)
        z = np.array([u, v])
    assert c == 4


@pytest.mark.slow  # a continuation into sticking, each point shot
def test_sticking_onset_is_located_where_the_orbit_stops_sticking(sim, model) -> None:
    """A rigid wall, r = 0.3: the period-1 orbit chatters into sticking (its D(F) is exactly 0)
    for sigma above ~2.419; followed down, its chatter loses impacts in a cascade and the orbit
    stops sticking.  Exactly one event is the sticking onset, and the exact flow agrees on both
    sides of it: sticking above, not below."""
    p = {**model.defaults(), "nu": 1.0, "Omega": 10.0, "r": 0.3, "wall": 2, "solver": 1}
    a = _seed(sim, p, 3.25, 1)
    assert a.impacts >= 20 and np.max(np.abs(a.multipliers)) == 0.0
    br = continue_orbit(sim, p, 1, 3.25, a.points[0], "sigma", (2.3, 3.5), -1.0, ds_max=0.2)
    (stick,) = [e for e in br.events if e.kind == "stick"]
    assert 2.40 < stick.value < 2.44
    for factor, sticks in ((1.001, True), (0.999, False)):
        ex = ExactOscillator(p["nu"], p["Omega"], stick.value * factor, p["r"], 10.0, "rigid")
        z = np.asarray(stick.point, dtype=float)
        for _ in range(100):
            u, v, _ = ex.state_at(z[0], z[1], THETA, THETA + 1.0)
            z = np.array([u, v])
        kinds = [k for _, k in ex.crossings(z[0], z[1], THETA, THETA + 1.0)]
        assert ("stick" in kinds) == sticks, (factor, kinds)
