"""Map Jacobians, multipliers and Newton shooting from the FMU's own derivatives.

The harness detects the FMU's sensitivity outputs (``sensitivities``, ``J_uu`` ... ``S_v``)
by name; with them a Jacobian is one run of the variational equations, without them it is
central differences.  Independent truths: the free-flight propagator P(1) (closed form),
det J = r^2 e^{-nu} per impact, the finite differences themselves away from grazing (the
cross-check), and the x^(-1/2) singularity near grazing.  The project's FMU must report
its derivatives (a build without them fails here rather than skipping the exact path).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from harness import HarnessInputError, jacobian_vs_x, map_jacobian
from harness.dynamics.maps.shooting import StroboscopicMap, good_orbit
from harness.fmu.simulator import FmuSimulator, MappingSimulator
from mapcheck.linear import propagator
from mapcheck.orbits import solve_periodic_orbit
from tests.support.fmu import harness_params as _params

# -- fallback and feature detection (every FMU) ------------------------------------------
def test_auto_method_follows_the_fmu(model, sim) -> None:
    p = _params(model, wall=0, sigma=0.2)
    res = map_jacobian(sim, p, (-0.7, 0.4), theta=0.3)
    assert model.has_sensitivities and res.method == "exact"
    # free flight: the variational equations give P(1) to rounding (measured 9e-16); the
    # differences to their truncation and the FMU's tolerance (measured 4.7e-9)
    np.testing.assert_allclose(res.J, propagator(1.0, p["nu"], p["Omega"]), rtol=0, atol=1e-10)
    fd = map_jacobian(sim, p, (-0.7, 0.4), theta=0.3, method="fd")
    assert fd.method == "fd" and fd.S is None
    np.testing.assert_allclose(fd.J, propagator(1.0, p["nu"], p["Omega"]), rtol=0, atol=1e-7)
    with pytest.raises(HarnessInputError, match="unknown Jacobian method"):
        map_jacobian(sim, p, (-0.7, 0.4), method="complex-step")


def test_fd_newton_multipliers_obey_the_determinant(model, sim) -> None:
    """Figure 9, sigma = 0.5: the period-2 orbit with one impact; the product of the FD
    multipliers is det D(F^2) = r^2 e^{-2 nu} (the saltation matrix's det r^2).  To ~1 %
    only: the differences' ~3e-5 error in J is large against the small multiplier (~2e-4);
    the exact path meets it to 1e-7 (below)."""
    p = _params(model, sigma=0.5)
    smap = StroboscopicMap(sim, p, 0.5, derivatives="fd")
    step = smap.at(0.5)
    w = np.zeros(2)
    for _ in range(300):  # settle on the attractor
        *w, _n = step(*w)
    orb = solve_periodic_orbit(step, np.array(w), 2, tol=1e-9, rel_h=1e-4, scale=np.array([1e-2, 1e-1]))
    assert orb.converged and orb.maximal and orb.stable
    det = float(np.prod(orb.multipliers).real)
    assert det == pytest.approx(p["r"] ** 2 * math.exp(-2 * p["nu"]), rel=3e-2)


def test_newton_with_a_derivative_equals_differences_on_henon() -> None:
    """mapcheck.orbits with ``dstep``: the Henon map's fixed point and multipliers in closed
    form, reached with one pass per iteration (the differences need five)."""
    a, b = 1.4, 0.3
    calls = {"n": 0}

    def step(x: float, y: float) -> tuple[float, float, int]:
        calls["n"] += 1
        return 1.0 - a * x * x + y, b * x, 1

    def dstep(x: float, y: float):
        calls["n"] += 1
        return 1.0 - a * x * x + y, b * x, 1, np.array([[-2 * a * x, 1.0], [b, 0.0]])

    xs = (-(1 - b) + math.sqrt((1 - b) ** 2 + 4 * a)) / (2 * a)
    mult = np.linalg.eigvals(np.array([[-2 * a * xs, 1.0], [b, 0.0]]))
    fd = solve_periodic_orbit(step, [0.5, 0.1], 1, tol=1e-13)
    n_fd, calls["n"] = calls["n"], 0
    ex = solve_periodic_orbit(step, [0.5, 0.1], 1, tol=1e-13, dstep=dstep)
    for orb in (fd, ex):
        assert orb.converged
        np.testing.assert_allclose(orb.z[0], [xs, b * xs], rtol=1e-12)
    np.testing.assert_allclose(np.sort(ex.multipliers.real), np.sort(mult.real), rtol=1e-13)
    np.testing.assert_allclose(np.sort(fd.multipliers.real), np.sort(mult.real), rtol=1e-6)
    assert calls["n"] * 4 < n_fd


def test_mapping_simulator_chains_derivatives() -> None:
    """A mapping given its derivative reports the chained product over several periods."""
    A = np.array([[0.5, 1.0], [-0.2, 0.3]])

    def step(u, v, t, params):
        x = A @ np.array([u, v]) + params["sigma"]
        return float(x[0]), float(x[1]), 0

    sim = MappingSimulator(step, {"sigma": 0.1}, derivative=lambda u, v, t, p: (A, np.ones(2)))
    sim.track_derivatives(True)
    sim.start({}, 0.0, (1.0, 2.0))
    sim.advance(3.0)
    J, S = sim.derivatives()
    np.testing.assert_allclose(J, A @ A @ A)
    np.testing.assert_allclose(S, (A @ A + A + np.eye(2)) @ np.ones(2))


# -- the exact path (an FMU with sensitivity outputs) ------------------------------------
REGULAR = [  # (overrides, state at theta, theta): free flight, one compliant / rigid contact
    ({"wall": 0, "sigma": 0.2}, (-0.7, 0.4), 0.3),
    ({"sigma": 0.5}, (-1.30, 0.0), 0.5),
    ({"sigma": 0.5, "wall": 2}, (-1.30, 0.0), 0.5),
    ({"nu": 0.196, "Omega": 7.368, "Gamma": 1e3, "sigma": 0.1}, (-1.1, 0.2), 0.5),
]


@pytest.mark.parametrize("over, state, theta", REGULAR)
def test_exact_jacobian_agrees_with_differences(model, sim, over, state, theta) -> None:
    p = _params(model, **over)
    ex = map_jacobian(sim, p, state, theta=theta, method="exact")
    fd = map_jacobian(sim, p, state, theta=theta, method="fd")
    assert ex.method == "exact"
    np.testing.assert_allclose(ex.image, fd.image, atol=1e-10)
    np.testing.assert_allclose(ex.J, fd.J, atol=max(20 * fd.error, 1e-7) * max(1.0, np.abs(fd.J).max()))
    # d/d sigma against a central difference in sigma: h = 1e-4 keeps the images' ~1e-10
    # error at ~1e-6 in the quotient, the truncation O(h^2) below it (smooth away from grazing)
    h = 1e-4
    plus = map_jacobian(sim, {**p, "sigma": p["sigma"] + h}, state, theta=theta, method="fd").image
    minus = map_jacobian(sim, {**p, "sigma": p["sigma"] - h}, state, theta=theta, method="fd").image
    np.testing.assert_allclose(ex.S, (plus - minus) / (2 * h), rtol=1e-5, atol=3e-6)


def test_derivatives_chain_over_several_doSteps(model) -> None:
    """A period in 7 doSteps gives the same J and S as one doStep (the harness chains the
    per-step matrices the FMU reports)."""
    p = _params(model, sigma=0.5)
    one = FmuSimulator(model.source(), instance_name="one")
    many = FmuSimulator(model.source(), instance_name="many", max_step=1.0 / 7.0)
    try:
        a = map_jacobian(one, p, (-1.30, 0.0), theta=0.5, method="exact")
        b = map_jacobian(many, p, (-1.30, 0.0), theta=0.5, method="exact")
    finally:
        one.close()
        many.close()
    # CVODE on other step sequences: measured 1.7e-11 (image), 4e-14 (J), 1.1e-11 (S)
    np.testing.assert_allclose(b.image, a.image, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.J, a.J, rtol=0, atol=1e-10)
    np.testing.assert_allclose(b.S, a.S, rtol=0, atol=1e-9)


def test_exact_singularity_reaches_1e_minus_9(model, sim) -> None:
    """J11 - P11 ~ x^(-1/2) at t = n (Figure 9, r = 0.9) over x = 1e-9 .. 1e-4: five decades
    below the differences' limit."""
    p = _params(model, sigma=0.0)
    x = np.geomspace(1e-9, 1e-4, 6)
    s = jacobian_vs_x(sim, p, x, theta=0.0, method="exact")
    assert s.method == "exact"
    d = np.abs(s.J[:, 0, 0] - s.P1[0, 0])
    slope = float(np.polyfit(np.log(x), np.log(d), 1)[0])
    assert slope == pytest.approx(-0.5, abs=0.02)
    np.testing.assert_allclose(np.linalg.det(s.J), p["r"] ** 2 * math.exp(-p["nu"]), rtol=1e-6)


def test_newton_exact_and_fd_find_the_same_orbit(model, sim) -> None:
    """Same orbit and multipliers from exact derivatives and from differences; the exact
    path needs a fraction of the FMU runs."""
    p = _params(model, sigma=0.5)
    out = {}
    for method in ("fd", "exact"):
        smap = StroboscopicMap(sim, p, 0.5, derivatives=method)
        w = np.zeros(2)
        for _ in range(300):
            *w, _n = smap.at(0.5)(*w)
        smap.evaluations = 0
        ok, orb = good_orbit(smap, 2, 0.5, [np.array(w)])
        assert ok
        out[method] = (orb, smap.evaluations)
    (fd, n_fd), (ex, n_ex) = out["fd"], out["exact"]
    np.testing.assert_allclose(ex.z, fd.z, atol=1e-9)
    # the leading multiplier to the differences' accuracy; the small one (~2e-4) carries their
    # ~3e-5 error in J, so the determinant is the sharper check of the exact one
    m_ex, m_fd = np.sort(np.abs(ex.multipliers)), np.sort(np.abs(fd.multipliers))
    assert m_ex[1] == pytest.approx(m_fd[1], rel=1e-4)
    assert m_ex[0] == pytest.approx(m_fd[0], rel=3e-2)
    assert float(np.prod(ex.multipliers).real) == pytest.approx(p["r"] ** 2 * math.exp(-2 * p["nu"]), rel=1e-7)
    assert n_ex * 3 < n_fd
