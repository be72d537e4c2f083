"""``jacobian``: the singularity exponent with its standard error and fit range, soft and hard
contacts fitted apart at a compliant wall, saved in the NetCDF; ``--state`` prints and saves the
multipliers; the help says the default is exact.

Independent truths: scipy's linear regression for the slope and its standard error; the theory's
exponents (docs/theory.md section 8): +1/2 for soft elastic contacts (r = 1), -1/2 for the
square-root map (a rigid wall), tending to -1/2 for hard contacts as the wall stiffens; beta of
section 5 for the regime bounds; the free oscillator's multipliers exp(s), s the roots of
s^2 + nu s + Omega^2.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from harness import read_netcdf
from harness.dynamics.maps.singularity_fit import HARD_BETA, SOFT_BETA, fit_singularity, loglog_fit
from tests.support.cli import run_main

FIG6 = ["--set", "nu=0.196", "--set", "Omega=7.368", "--set", "sigma=0"]


@pytest.mark.parametrize("q, noise", [(-0.5, 0.0), (0.5, 0.05), (-0.3, 0.2)])
def test_loglog_fit_matches_linear_regression(q, noise) -> None:
    rng = np.random.default_rng(7)
    x = np.geomspace(1e-8, 1e-2, 19)
    y = -3.0 * x ** q * np.exp(noise * rng.standard_normal(x.size))
    slope, se = loglog_fit(x, y)
    ref = stats.linregress(np.log(x), np.log(np.abs(y)))
    assert slope == pytest.approx(ref.slope, rel=1e-10, abs=1e-12)
    # abs: scipy forms the error from 1 - r^2, which cancels to ~1e-9 for an exact power law
    assert se == pytest.approx(ref.stderr, rel=1e-8, abs=1e-8)
    if noise == 0.0:
        assert slope == pytest.approx(q, abs=1e-12)


def test_regimes_are_fitted_apart_and_short_ones_refused() -> None:
    """A soft x^{+1/2} below beta = 0.1 and a hard x^{-1/2} above beta = 5, crossover between:
    each regime gets its own exponent; a regime under a decade of x gets none."""
    x = np.geomspace(1e-8, 1e-1, 43)
    beta = 50.0 * np.sqrt(x)
    d = np.where(beta <= 1.0, x ** 0.5, 1e-3 * x ** -0.5)
    fits = fit_singularity(x, d, np.zeros_like(x), beta)
    assert fits["soft"].exponent == pytest.approx(0.5, abs=1e-9)
    assert fits["hard"].exponent == pytest.approx(-0.5, abs=1e-9)
    assert 50 * math.sqrt(fits["soft"].x_max) <= SOFT_BETA and 50 * math.sqrt(fits["hard"].x_min) >= HARD_BETA
    short = fit_singularity(x[-8:], d[-8:], np.zeros(8), beta[-8:])
    assert short["soft"] is None and short["hard"] is not None
    # a point whose own error estimate is not small enough stays out
    noisy = fit_singularity(x, d, np.where(x > 1e-2, 1.0, 0.0), beta)
    assert noisy["hard"] is None or noisy["hard"].x_max <= 1e-2


def test_compliant_wall_soft_and_hard_exponents_saved(tmp_path, capsys) -> None:
    """Figure 6's oscillator (r = 1), Gamma = 1e4: soft contacts +1/2, hard contacts near -1/2."""
    out = tmp_path / "j.nc"
    code, stdout, err = run_main(["jacobian", *FIG6, "--set", "r=1", "--set", "wall=compliant", "--set", "Gamma=1e4",
                                  "--x-start", "1e-9", "--x-stop", "0.1", "--x-num", "33", "--out", str(out),
                                  "--no-plot", "--no-progress"], capsys)
    assert code == 0, err
    ds = read_netcdf(out)
    assert list(ds["regime"].values) == ["soft", "hard"]
    q, se = ds["exponent"].values, ds["exponent_stderr"].values
    assert q[0] == pytest.approx(0.5, abs=0.01) and 0 <= se[0] < 0.01
    assert -0.5 <= q[1] < -0.4 and 0 < se[1] < 0.05  # approaches -1/2 only as Gamma grows (reproduce fig6)
    kappa = math.sqrt(1e4) * 7.368
    beta = lambda x: kappa * math.sqrt(8 * math.pi ** 2 * x) / (4 * math.pi ** 2)  # noqa: E731 (r = 1, sigma = 0)
    assert beta(ds["fit_x_max"].values[0]) <= SOFT_BETA and beta(ds["fit_x_min"].values[1]) >= HARD_BETA
    np.testing.assert_allclose(ds["beta"].values, [beta(x) for x in ds["x"].values], rtol=1e-12)
    for k, regime in enumerate(("soft", "hard")):
        assert f"{regime} regime" in stdout and f"{q[k]:+.4f}" in stdout and int(ds["fit_points"].values[k]) >= 3


def test_rigid_wall_one_regime(tmp_path, capsys) -> None:
    out = tmp_path / "j.nc"
    code, stdout, err = run_main(["jacobian", *FIG6, "--set", "r=0.8", "--set", "wall=rigid", "--x-start", "1e-8",
                                  "--x-stop", "1e-2", "--x-num", "13", "--out", str(out), "--no-plot",
                                  "--no-progress"], capsys)
    assert code == 0, err
    ds = read_netcdf(out)
    assert list(ds["regime"].values) == ["all"] and "beta" not in ds
    assert float(ds["exponent"][0]) == pytest.approx(-0.5, abs=0.01)
    assert float(ds["fit_x_min"][0]) == pytest.approx(1e-8) and float(ds["fit_x_max"][0]) == pytest.approx(1e-2)
    assert "whole range" in stdout


@pytest.mark.parametrize("nu, Omega", [(4.605170185988091, 0.3059238689620112), (0.196, 7.368), (0.5, 12.0)])
def test_state_prints_and_saves_the_multipliers(tmp_path, capsys, nu, Omega) -> None:
    out = tmp_path / "s.nc"
    code, stdout, err = run_main(["jacobian", "--set", f"nu={nu}", "--set", f"Omega={Omega}", "--set", "wall=none",
                                  "--state=-0.5,0.3", "--theta", "0.25", "--out", str(out), "--no-progress"], capsys)
    assert code == 0, err
    ds = read_netcdf(out)
    mu = ds["multiplier_real"].values + 1j * ds["multiplier_imag"].values
    s = np.roots([1.0, nu, Omega ** 2])
    expected = np.exp(s)
    assert np.allclose(np.sort_complex(mu), np.sort_complex(expected), atol=1e-8)
    np.testing.assert_allclose(ds["multiplier_abs"].values, np.abs(mu))
    assert "eigenvalues of J (multipliers)" in stdout and f"det J = {math.exp(-nu):.6g}"[:14] in stdout


def test_help_says_the_default_is_exact(capsys) -> None:
    code, stdout, _ = run_main(["jacobian", "--help"], capsys)
    text = " ".join(stdout.split())
    assert code == 0 and "exact by default" in text and "Central-difference Jacobian" not in text
    assert "multipliers" in text and "standard error" in text
