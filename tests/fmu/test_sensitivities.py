"""The FMU's sensitivities: J = d(u, v)(end of doStep)/d(u, v)(start) and
S = d(u, v)(end)/d sigma, from the variational equations with saltation matrices at every wall
event, in CVODE mode (integrated alongside the state) and in closed-form mode (analytic).

Independent truth: central differences of mapcheck.exact (the closed form in Python, exact
crossing times), Richardson extrapolated, away from grazing; near grazing the growth
depth^(-1/2) of the saltation matrix; FMU state save/restore/serialisation carry the matrix.
"""
from __future__ import annotations

import numpy as np
import pytest

from tests.support.fmu import on_orbit
from tests.support.sensitivities import FIG9, UNDERDAMPED, Fmu, exact_derivatives, one_period, oracle

# (name, parameters, starts (t0, sigma-orbit phase)): every case has wall events in its period
CASES = {
    "fig9_compliant": dict(FIG9, wall=1),
    "underdamped_compliant": dict(UNDERDAMPED, sigma=0.05, wall=1),
    "underdamped_rigid": dict(UNDERDAMPED, sigma=0.05, wall=2),
    "compliant_r1": dict(UNDERDAMPED, sigma=0.05, r=1.0, Gamma=30.0, wall=1),
    "no_wall": dict(UNDERDAMPED, sigma=0.05, wall=0),
}


def rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.fixture(scope="module")
def fmu2():
    f = Fmu(2)
    yield f
    f.close()


@pytest.mark.parametrize("solver", [0, 1])
@pytest.mark.parametrize("case", sorted(CASES))
def test_derivatives_match_differences_of_the_closed_form(fmu2, case, solver):
    p = CASES[case]
    for t0 in (0.55, 0.8):
        x0 = on_orbit(p["sigma"], t0)  # on the wall-free orbit: the wall is hit within the period
        x0 = (x0["u0"], x0["v0"])
        x1, J, S = one_period(fmu2, p, x0, t0, solver=solver)
        contacts = oracle(p).crossings(*x0, t0, t0 + 1.0)
        assert (len(contacts) > 0) == (p["wall"] != 0)
        Jx, Sx = exact_derivatives(p, x0, t0)
        assert rel(J, Jx) < 1e-7, (case, t0, J, Jx)
        assert rel(S, Sx) < 1e-7, (case, t0, S, Sx)


@pytest.mark.parametrize("solver", [0, 1])
def test_derivatives_chain_over_doSteps(fmu2, solver):
    """J over one period = J(second half) J(first half); S chains as S2 + J2 S1."""
    p = dict(FIG9, wall=1)
    x = on_orbit(p["sigma"], 0.6)
    fmu2.start(0.6, **p, **x, sensitivities=True, solver=solver)
    fmu2.step(1.1)
    J1, S1 = fmu2.jac()
    fmu2.step(1.6)
    J2, S2 = fmu2.jac()
    _, J, S = one_period(fmu2, p, (x["u0"], x["v0"]), 0.6, solver=solver)
    tol = 1e-12 if solver else 1e-8  # CVODE: two runs with different steps
    assert rel(J2 @ J1, J) < tol
    assert rel(S2 + J2 @ S1, S) < tol


@pytest.mark.parametrize("wall", [1, 2])
@pytest.mark.parametrize("solver", [0, 1])
def test_growth_like_inverse_square_root_of_the_depth_near_grazing(fmu2, wall, solver):
    """A contact of depth x (the wall-free orbit at sigma = x peaks at u = x): the saltation
    matrix's entry row grows like 1/v ~ x^(-1/2), so does max |J|. Fitted slope -1/2."""
    p = dict(UNDERDAMPED, wall=wall, Gamma=100.0)
    depths = np.logspace(-5, -12 if solver == 1 else -9, 8)  # where the singular part dominates
    norms = []
    for x in depths:
        q = dict(p, sigma=x)
        st = on_orbit(x, 0.5)
        _, J, S = one_period(fmu2, q, (st["u0"], st["v0"]), 0.5, solver=solver)
        assert fmu2.impacts() >= 1  # the contact was found
        norms.append(np.max(np.abs(J)))
    slope = np.polyfit(np.log(depths), np.log(norms), 1)[0]
    assert abs(slope + 0.5) < 0.01, (slope, norms)


def test_cvode_and_closed_form_sensitivities_agree(fmu2):
    p = dict(UNDERDAMPED, sigma=0.05, wall=2)
    x = on_orbit(p["sigma"], 0.7)
    _, J0, S0 = one_period(fmu2, p, (x["u0"], x["v0"]), 0.7, solver=0)
    _, J1, S1 = one_period(fmu2, p, (x["u0"], x["v0"]), 0.7, solver=1)
    assert rel(J0, J1) < 1e-8 and rel(S0, S1) < 1e-8


@pytest.mark.parametrize("solver", [0, 1])
def test_sensitivities_off_leave_identity_and_the_same_state(fmu2, solver):
    p = dict(FIG9, wall=1)
    x = on_orbit(p["sigma"], 0.6)
    a, J, S = one_period(fmu2, p, (x["u0"], x["v0"]), 0.6, sens=False, solver=solver)
    assert np.array_equal(J, np.eye(2)) and np.array_equal(S, np.zeros(2))  # not computed
    b, _, _ = one_period(fmu2, p, (x["u0"], x["v0"]), 0.6, sens=True, solver=solver)
    assert np.max(np.abs(a - b)) < (1e-9 if solver == 0 else 1e-15)  # CVODE: other steps


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("solver", [0, 1])
def test_fmu_state_and_serialisation_carry_the_matrix(version, solver):
    f = Fmu(version)
    s = f.slave
    try:
        p = dict(FIG9, wall=1)
        f.start(0.6, **p, **on_orbit(p["sigma"], 0.6), sensitivities=True, solver=solver)
        f.step(1.6)
        J1, S1 = f.jac()
        if version == 2:
            st = s.getFMUstate()
            blob = s.serializeFMUstate(st)
        else:
            st = s.getFMUState()
            blob = s.serializeFMUState(st)
        f.step(2.6)
        J2, S2 = f.jac()
        assert not np.array_equal(J1, J2)
        if version == 2:
            s.setFMUstate(s.deSerializeFMUstate(blob))
        else:
            s.setFMUState(s.deserializeFMUState(blob))
        f.t = 1.6
        J, S = f.jac()
        assert np.array_equal(J, J1) and np.array_equal(S, S1)  # the matrix came back
        f.step(2.6)
        J, S = f.jac()
        assert np.array_equal(J, J2) and np.array_equal(S, S2)  # and continues identically
        (s.freeFMUstate if version == 2 else s.freeFMUState)(st)
    finally:
        f.close()


def test_fmi3_sensitivities_equal_fmi2(fmu2):
    f3 = Fmu(3)
    try:
        p = dict(UNDERDAMPED, sigma=0.05, wall=1)
        x = on_orbit(p["sigma"], 0.7)
        for solver in (0, 1):
            _, J2, S2 = one_period(fmu2, p, (x["u0"], x["v0"]), 0.7, solver=solver)
            _, J3, S3 = one_period(f3, p, (x["u0"], x["v0"]), 0.7, solver=solver)
            assert rel(J3, J2) < 1e-12 and rel(S3, S2) < 1e-12
    finally:
        f3.close()
