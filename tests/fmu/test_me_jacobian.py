"""The FMU's Jacobian in use: a Model Exchange integration (scikit-sundae's CVODE driving the FMU
through fmpy, tests/support/me_jacobian.py) with CVODE's Newton iteration given the FMU's exact
Jacobian (directional derivatives, one call per state), against the same run with CVODE's
difference quotients. Both follow the closed form (mapcheck.exact) within the Model Exchange
bound of the project (2e-6 of the state's size at rtol 1e-10, tests/fmu/test_model_exchange.py),
impact counts exact; the counts of both runs are printed (BENCHMARKS.md gives them)."""
from __future__ import annotations

import numpy as np
import pytest

from mapcheck.exact import ExactOscillator
from tests.support.me_jacobian import run_me

RTOL = 1e-10
ME_TOL = 2e-6
CASES = {
    "underdamped-stiff-wall": dict(nu=0.196, Omega=7.368, sigma=0.5, wall=1, Gamma=1000.0,
                                   u0=-0.5, v0=1.0),
    "fig9": dict(nu=4.605170185988091, Omega=0.3059238689620112, sigma=0.2, wall=1,
                 Gamma=10.0, u0=-0.2, v0=3.0),
}
T0 = 0.5


@pytest.mark.parametrize("interface", ["fmi2-me", "fmi3-me"])
@pytest.mark.parametrize("case", CASES)
def test_cvode_with_the_fmus_jacobian_follows_the_closed_form(interface, case):
    p = CASES[case]
    times = T0 + np.arange(1, 11, dtype=float)
    exact, counts = ExactOscillator(p["nu"], p["Omega"], p["sigma"], Gamma=p["Gamma"],
                                    wall="compliant").strobe(p["u0"], p["v0"], times, t0=T0)
    scale = max(1.0, float(np.abs(exact).max()))
    runs = {jac: run_me(interface, p, T0, times, RTOL, fmu_jacobian=jac) for jac in (True, False)}
    for jac, run in runs.items():
        err = float(np.abs(np.array(run.states) - exact).max())
        print(f"{case} {interface} {'FMU Jacobian' if jac else 'difference quotients'}: "
              f"error {err:.2g} (scale {scale:.2g}), FMU right-hand sides {run.fmu_rhs}, "
              f"Jacobians {run.fmu_jacobians if jac else run.cvode_njev}, CVODE nfev "
              f"{run.cvode_nfev}, events {run.events}")
        assert err <= ME_TOL * scale
        assert run.impacts == list(counts) and counts[-1] > 0
    assert runs[True].fmu_jacobians == runs[True].cvode_njev > 0  # CVODE used the FMU's
    assert runs[False].fmu_jacobians == 0
