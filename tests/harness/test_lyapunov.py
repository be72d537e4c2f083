"""Lyapunov exponents of the stroboscopic map and the classification they allow.

Independent truths: the Henon map's largest exponent (0.4192, a textbook value) and its
exact sum log b; the free oscillator's exponents, the real parts of the eigenvalues of
[[0, 1], [-Omega^2, -nu]]; the sum of the exponents of the FMU's map, which must equal
-nu + 2 log(r) x impacts per period (det J = r^2 e^{-nu} across each impact); for a periodic
orbit, log |multiplier| / M from Newton shooting; for the chaotic orbit, Benettin's
two-trajectory estimate on the exact closed-form flow (mapcheck.exact), with its standard
error.  Periodic sigma = 0.5 and chaotic sigma = 0.03 at Figure 9's parameters.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from harness.dynamics.maps.classify import CHAOTIC, NOT_CONVERGED, PERIODIC, QUASI_PERIODIC, UNCLASSIFIED, classify_dynamics
from harness.dynamics.maps.lyapunov import lyapunov_exponents, lyapunov_from_jacobians, qr_logs
from harness.dynamics.maps.shooting import StroboscopicMap
from harness.fmu.simulator import MappingSimulator
from mapcheck.exact import ExactOscillator
from mapcheck.linear import propagator
from mapcheck.orbits import solve_periodic_orbit
from tests.support.cli import run_main as _run_main
from tests.support.fmu import harness_params as _params

HENON_A, HENON_B = 1.4, 0.3


def _henon(u, v, t, params):
    return 1.0 - HENON_A * u * u + v, HENON_B * u, 0


def _henon_jac(u, v, t, params):
    return np.array([[-2.0 * HENON_A * u, 1.0], [HENON_B, 0.0]]), None


def test_henon_exponents() -> None:
    sim = MappingSimulator(_henon, derivative=_henon_jac)
    res = lyapunov_exponents(sim, {}, (0.1, 0.1), 0.0, n_transient=100, n_periods=20000, blocks=20)
    assert res.method == "exact"
    assert res.largest == pytest.approx(0.4192, abs=max(4 * res.largest_uncertainty, 0.005))
    assert 0 < res.largest_uncertainty < 0.01
    assert res.exponents.sum() == pytest.approx(math.log(HENON_B), abs=1e-12)
    # the same orbit by finite differences of the map
    fd = lyapunov_exponents(MappingSimulator(_henon), {}, (0.1, 0.1), 0.0, n_transient=100, n_periods=2000,
                            method="fd")
    assert fd.method == "fd"
    assert fd.largest == pytest.approx(0.4192, abs=5 * fd.largest_uncertainty + 0.01)


def test_qr_of_a_constant_matrix_gives_its_eigenvalues() -> None:
    J = np.array([[0.9, 0.5], [0.0, -0.2]])
    logs = qr_logs(np.repeat(J[None], 200, axis=0))
    np.testing.assert_allclose(logs[-1], [math.log(0.9), math.log(0.2)], atol=1e-12)
    res = lyapunov_from_jacobians(np.repeat(J[None], 200, axis=0))
    assert res.uncertainty[0] < 1e-3  # only the first block's transient varies


def test_free_oscillator_exponents_on_the_fmu(model, sim) -> None:
    p = _params(model, wall=0, sigma=0.3)
    n = 40
    res = lyapunov_exponents(sim, p, (-1.0, 0.0), 0.25, n_transient=0, n_periods=n, method="fd")
    nu, Om = p["nu"], p["Omega"]
    # finite N: the same QR iteration on the closed-form propagator P(1)
    exact = lyapunov_from_jacobians(np.repeat(propagator(1.0, nu, Om)[None], n, axis=0))
    np.testing.assert_allclose(res.exponents, exact.exponents, rtol=5e-5, atol=1e-5)
    # and the limit, the real parts of the eigenvalues of the ODE's matrix, to O(1/N)
    eig = np.sort(np.linalg.eigvals(np.array([[0.0, 1.0], [-Om * Om, -nu]])).real)[::-1]
    np.testing.assert_allclose(res.exponents, eig, atol=2e-3)
    assert res.impacts == 0


@pytest.fixture(scope="module")
def fig9_orbits(model, sim):
    out = {}
    for sigma, n in ((0.5, 200), (0.03, 600)):
        p = _params(model, sigma=sigma)
        out[sigma] = (p, lyapunov_exponents(sim, p, (-1.0, 0.0), 0.5, n_transient=300, n_periods=n))
    return out


def _rotation(a: float) -> np.ndarray:
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


def test_qr_accumulates_full_matrices_in_orbit_order() -> None:
    """J_k = R(a_k) D R(a_{k-1})^T with random angles: every J_k is a full matrix (Q turns at
    every step), but the product J_N .. J_1 = R(a_N) D^N R(a_0)^T telescopes, so the exponents
    are exactly log d_1, log d_2 (up to the O(1/N) transient of the first steps).  An
    accumulation in the wrong order (Q J instead of J Q) multiplies non-telescoping rotations."""
    rng = np.random.default_rng(7)
    a = rng.uniform(0.0, 2.0 * math.pi, 2001)
    D = np.diag([math.exp(0.3), -math.exp(-0.8)])
    Js = np.array([_rotation(a[k + 1]) @ D @ _rotation(a[k]).T for k in range(2000)])
    assert np.median(np.abs(Js[:, 1, 0])) > 0.1  # full matrices, not triangular
    res = lyapunov_from_jacobians(Js)
    np.testing.assert_allclose(res.exponents, [0.3, -0.8], atol=2e-3)
    # the per-step logs after the transient are the exponents themselves, step by step
    logs = qr_logs(Js)
    np.testing.assert_allclose(logs[50:], np.broadcast_to([0.3, -0.8], logs[50:].shape), atol=1e-12)


@pytest.mark.parametrize("sigma", [0.5, 0.03])
def test_sum_of_exponents_is_the_impact_dissipation(fig9_orbits, sigma) -> None:
    p, res = fig9_orbits[sigma]
    assert res.impacts > 0
    expected = -p["nu"] + 2.0 * math.log(p["r"]) * res.impacts / res.periods
    # differences straddle the chaotic orbit's near-grazing contacts (a perturbed run that
    # misses the wall): a few periods' dets are off, so the fallback meets it to ~1e-2 only
    tol = 1e-8 if res.method == "exact" else (1e-4 if sigma == 0.5 else 2e-2)
    assert res.exponents.sum() == pytest.approx(expected, abs=tol)


@pytest.fixture(scope="module")
def periodic_lambda(model, sim) -> float:
    """sigma = 0.5: lambda_1 of the stable period-2 orbit (one impact) from its Floquet
    multipliers, log |m_1| / 2, by Newton shooting: the truth the QR averages are held to."""
    p = _params(model, sigma=0.5)
    smap = StroboscopicMap(sim, p, 0.5)
    step = smap.at(0.5)
    w = np.zeros(2)
    for _ in range(300):
        *w, _n = step(*w)
    orb = solve_periodic_orbit(step, np.array(w), 2, tol=1e-9, rel_h=1e-4, scale=np.array([1e-2, 1e-1]),
                               dstep=smap.at_with_jacobian(0.5))
    assert orb.converged and orb.maximal and orb.stable
    return math.log(float(np.max(np.abs(orb.multipliers)))) / 2


def test_periodic_exponent_is_the_log_multiplier(fig9_orbits, periodic_lambda) -> None:
    """sigma = 0.5: the QR average over 200 periods is the multipliers' lambda_1."""
    _, res = fig9_orbits[0.5]
    assert res.largest == pytest.approx(periodic_lambda, abs=1e-4)
    assert res.largest < -0.4 and res.largest_uncertainty < 1e-4
    assert classify_dynamics(2, False, res.largest, res.largest_uncertainty) == PERIODIC


def benettin_largest_exponent(step, x0: np.ndarray, t0: float, n: int, d0: float = 1e-8,
                              blocks: int = 20) -> tuple[float, float]:
    """lambda_1 of the one-period map by two trajectories (Benettin et al. 1976): a companion
    starts d0 away along e, both run one period, log(d1 / d0) is that period's stretch, and the
    companion is put back at distance d0 along the new separation.  No derivative, no QR: only
    the map itself.  Distances in (u, v / 2 pi), both of order 1.  Returns the mean stretch and
    its batch-means standard error over ``blocks`` consecutive blocks.

    ``step(u, v, t) -> (u1, v1)`` maps the state at t to the state at t + 1."""
    w = np.array([1.0, 2.0 * math.pi])
    x, t = np.asarray(x0, dtype=float), t0
    e = np.array([1.0, 1.0]) / math.sqrt(2.0)
    logs = np.empty(n)
    for k in range(n):
        x1 = np.array(step(*x, t))
        dy = (np.array(step(*(x + d0 * e * w), t)) - x1) / w
        d = float(np.linalg.norm(dy))
        logs[k] = math.log(d / d0)
        x, e, t = x1, dy / d, t + 1.0
    means = logs[: n // blocks * blocks].reshape(blocks, -1).mean(axis=1)
    return float(logs.mean()), float(means.std(ddof=1) / math.sqrt(blocks))


def test_chaotic_orbit_has_a_positive_exponent(model, sim, fig9_orbits) -> None:
    """sigma = 0.03: the harness's lambda_1 (QR over the FMU's own derivatives) against an
    independent estimate, Benettin's two trajectories on the exact closed-form flow
    (mapcheck.exact: no FMU, no derivatives, no harness code), each with its batch-means
    standard error: they agree within 4 combined sigma.  Both averages are over the chaotic
    attractor (different orbits; the exponent is the attractor's).  2000 harness periods and
    2400 closed-form ones give standard errors ~0.013 and ~0.01 on lambda_1 ~ 0.3."""
    p, res = fig9_orbits[0.03]
    assert res.largest > 5 * res.largest_uncertainty > 0
    assert classify_dynamics(0, False, res.largest, res.largest_uncertainty) == CHAOTIC
    long = lyapunov_exponents(sim, p, (-1.0, 0.0), 0.5, n_transient=300, n_periods=2000, blocks=20)
    ex = ExactOscillator(p["nu"], p["Omega"], p["sigma"], r=p["r"], Gamma=p["Gamma"], wall="compliant")
    assert p["wall"] == 1 and p["contact"] == 0 and p["F_ext"] == 0 and p["u_wall"] == 0  # what ex models
    x0 = np.array(ex.state_at(-1.0, 0.0, 0.5, 300.5)[:2])

    def step(u: float, v: float, t: float) -> tuple[float, float]:
        return ex.state_at(u, v, t, t + 1.0)[:2]

    lam, err = benettin_largest_exponent(step, x0, 300.5, 2400)
    assert lam > 10 * err and 0 < err < 0.02 and 0 < long.largest_uncertainty < 0.02  # the check has teeth
    combined = math.hypot(err, long.largest_uncertainty)
    assert abs(long.largest - lam) < 4.0 * combined, (long, lam, err)
    # the short run of the fixture agrees too, within its own (larger) error
    assert abs(res.largest - lam) < 4.0 * math.hypot(err, res.largest_uncertainty), (res, lam, err)


def test_classification_rules() -> None:
    assert classify_dynamics(3, False, math.nan, math.nan) == PERIODIC
    assert classify_dynamics(3, True, -0.01, 0.001) == PERIODIC  # still settling, but attracting
    assert classify_dynamics(12, True, -0.055, 0.029) == PERIODIC  # a period-12 orbit with a near-zero exponent
    assert classify_dynamics(3, True, 0.01, 0.001) == NOT_CONVERGED  # settling, exponent not negative
    assert classify_dynamics(3, True, math.nan, math.nan) == NOT_CONVERGED  # settling, no exponent
    assert classify_dynamics(0, False, -0.05, 0.002) == NOT_CONVERGED  # stable, transient not over
    assert classify_dynamics(0, False, 0.0004, 0.001) == QUASI_PERIODIC  # zero within its uncertainty
    assert classify_dynamics(0, False, 0.3, 0.03) == CHAOTIC
    assert classify_dynamics(0, False, 0.02, 0.01) == NOT_CONVERGED  # zero within 3 sigma, but too wide to tell
    assert classify_dynamics(0, False, math.nan, math.nan) == UNCLASSIFIED


# -- the sweep output and the CLI ---------------------------------------------------------
def test_sweep_writes_exponents_and_dynamics(tmp_path, capsys, periodic_lambda) -> None:
    """``sweep --lyapunov N``: NetCDF variables lyapunov, lyapunov_err (exponent = 1, 2) and
    dynamics with CF flag attributes; periodic at sigma = 0.5, chaotic at 0.03."""
    from harness import read_netcdf
    from harness.dynamics.maps.classify import DYNAMICS_NAMES

    out = tmp_path / "ly.nc"
    code, stdout, err = _run_main(["sweep", "--values", "0.03,0.5", "--mode", "fresh", "--theta", "0.5",
                                   "--transient", "200", "--samples", "12", "--lyapunov", "150", "--backend",
                                   "serial", "--out", str(out), "--no-plot", "--no-progress"], capsys)
    assert code == 0, err
    assert "chaotic 1" in stdout and "periodic 1" in stdout
    ds = read_netcdf(out)
    lam = ds["lyapunov"].sel(direction="fresh")
    assert lam.dims == ("sigma", "exponent")
    d = ds["dynamics"].sel(direction="fresh").values
    assert [DYNAMICS_NAMES[int(c)] for c in d] == ["chaotic", "periodic"]
    l1, e1 = float(lam.values[0, 0]), float(ds["lyapunov_err"].sel(direction="fresh").values[0, 0])
    assert l1 > 3 * e1 > 0
    assert float(lam.values[1, 0]) == pytest.approx(periodic_lambda, abs=1e-3)  # 150 periods
    assert ds.attrs["sampling.lyapunov"] == 150
    assert "flag_meanings" in ds["dynamics"].attrs


def test_solver_flag(model, tmp_path, capsys) -> None:
    """``--solver cvode`` is accepted by every FMU (one without the parameter has CVODE only);
    ``--solver closed-form`` selects solver = 1, or is refused in one line without it."""
    base = ["strobe", "--set", "sigma=0.5", "--transient", "20", "--samples", "4", "--no-plot", "--no-progress"]
    code, _, err = _run_main([*base, "--solver", "cvode", "--out", str(tmp_path / "a.nc")], capsys)
    assert code == 0, err
    code, out, err = _run_main([*base, "--solver", "closed-form", "--out", str(tmp_path / "b.nc")], capsys)
    if "solver" in model.variables:
        assert code == 0, err
        from harness import read_netcdf

        assert int(read_netcdf(tmp_path / "b.nc").attrs["model.solver"]) == 1
    else:
        assert code == 2 and "--solver" in err and "no closed-form solver" in err
    code, _, err = _run_main([*base, "--solver", "euler"], capsys)
    assert code == 2 and "invalid choice" in err


def test_closed_form_solver_gives_the_same_exponents(model, sim) -> None:
    """solver = 1 (closed form) against CVODE: the periodic orbit's exponents to 1e-6; the
    chaotic orbits part ways after a few dozen periods (chaos), their exponents agree within
    the combined uncertainty."""
    res = {}
    for solver in (0, 1):
        for sigma, n in ((0.5, 200), (0.03, 600)):
            p = _params(model, sigma=sigma, solver=solver)
            res[(solver, sigma)] = lyapunov_exponents(sim, p, (-1.0, 0.0), 0.5, n_transient=300, n_periods=n)
    np.testing.assert_allclose(res[(1, 0.5)].exponents, res[(0, 0.5)].exponents, atol=1e-6)
    a, b = res[(0, 0.03)], res[(1, 0.03)]
    assert abs(a.largest - b.largest) < 3.0 * math.hypot(a.largest_uncertainty, b.largest_uncertainty)


def test_strobe_reports_exponents(tmp_path, capsys, periodic_lambda) -> None:
    from harness import read_netcdf

    out = tmp_path / "st.nc"
    code, stdout, err = _run_main(["strobe", "--set", "sigma=0.5", "--theta", "0.5", "--transient", "300",
                                   "--samples", "8", "--lyapunov", "60", "--out", str(out), "--no-plot",
                                   "--no-progress"], capsys)
    assert code == 0, err
    assert "Lyapunov exponents" in stdout and ": periodic" in stdout
    ds = read_netcdf(out)
    assert float(ds["lyapunov"].values[0]) == pytest.approx(periodic_lambda, abs=1e-3)  # 60 periods
    assert ds.attrs["dynamics"] == "periodic"
