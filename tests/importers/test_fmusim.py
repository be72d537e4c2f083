"""The FMUs in fmusim (Reference FMUs 0.0.39), an importer no one here wrote, against the closed form.

Co-Simulation (FMI 2.0 and 3.0): output intervals 1, 0.1, 0.01; FMI 3 early return with event
mode; input files with F_ext and u_wall staircases (input events: fmusim steps to them) and ramps
(fmusim interpolates the file at each communication point and the FMU holds the value over the
step). Every run is compared at t = 1, 2, ... (once per forcing period) with
``mapcheck.exact`` under the same piecewise-constant inputs: <= 1e-8 in u and v, impact counts
equal at every period, ``t_impact`` the closed form's last entry time.

Model Exchange (FMI 2.0 and 3.0): fmusim's own CVODE (``--solver cvode``; its default is explicit
Euler) at relative tolerance 1e-10, the FMU giving its event indicator; the per-period error is
within ME_TOL, impact counts exact.

fmusim is built by scripts/setup.sh from ``$IMPACT_SHARED/tools/fmusim-v0.0.39``; without that
source these tests skip naming the path, with it and no binary they fail.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.support.fmu import FMU3_PATH, FMU_PATH, ROOT
from tests.support.importers import (CS_TOL, Case, PeriodCheck, compare_per_period,
                                    fmusim_holds_cs, run_fmusim, write_input_csv)

PERIODS = 10
OVERDAMPED = dict(nu=4.605170185988091, Omega=0.3059238689620112)  # the paper's figure 9
UNDERDAMPED = dict(nu=0.196, Omega=7.368)
CASES = {
    "over-compliant": Case(sigma=0.5, wall="compliant", Gamma=1000.0, **OVERDAMPED),
    "over-rigid": Case(sigma=0.5, wall="rigid", **OVERDAMPED),
    "under-compliant": Case(sigma=0.5, wall="compliant", Gamma=10.0, u0=-0.5, v0=1.0,
                            **UNDERDAMPED),
    "under-rigid": Case(sigma=0.2, wall="rigid", r=0.8, u0=-0.5, v0=1.0, **UNDERDAMPED),
}
FMUS = {"fmi2": FMU_PATH, "fmi3": FMU3_PATH}
ME_RTOL = 1e-10
#: ME: CVODE controls the local error per step (rtol 1e-10, atol = rtol x nominal 1 in fmusim);
#: over ~1e3 steps and the located wall events it accumulates to a global error far above rtol.
#: The project's bound for ME at rtol 1e-10 (tests/fmu/test_model_exchange.py, fmpy's CVODE), relative to
#: the state's size: measured here up to 1.0e-7 in u and 7.9e-7 in v (underdamped, rigid wall).
ME_TOL = 2e-6


def cs_check(fmu: Path, case: Case, tmp: Path, h: float, inputs=None, flags=()):
    """One CS run in fmusim and its per-period comparison with the closed form."""
    csv = write_input_csv(tmp / "inputs.csv", inputs) if inputs else None
    res = run_fmusim(fmu, tmp, case, interface="cs", stop=PERIODS, h=h, flags=flags,
                     input_csv=csv)
    t = res["time"]
    if inputs:
        holds = fmusim_holds_cs(inputs, np.unique(t))
    else:
        holds = [(0.0, 0.0, 0.0)]
    t_impact = res["t_impact"] if "t_impact" in res.dtype.names else None
    return res, compare_per_period(t, res["u"], res["v"], res["impacts"], t_impact,
                                   case, holds, PERIODS)


@pytest.mark.parametrize("h", [1.0, 0.1, 0.01])
@pytest.mark.parametrize("version", FMUS)
@pytest.mark.parametrize("name", CASES)
def test_cs_per_period_matches_closed_form(name: str, version: str, h: float,
                                           tmp_path: Path) -> None:
    case = CASES[name]
    _, chk = cs_check(FMUS[version], case, tmp_path, h)
    assert chk.err_u <= CS_TOL and chk.err_v <= CS_TOL * max(1.0, case.Omega), chk
    assert chk.impacts == chk.impacts_exact > 0


@pytest.mark.parametrize("h", [1.0, 0.1])
@pytest.mark.parametrize("name", CASES)
def test_fmi3_cs_early_return_and_event_mode(name: str, h: float, tmp_path: Path) -> None:
    """With early return and event mode the FMU returns at each wall event: fmusim records a row
    there (before and after the event), at the closed form's event time."""
    case = CASES[name]
    res, chk = cs_check(FMU3_PATH, case, tmp_path, h,
                         flags=("--early-return-allowed", "--event-mode-used"))
    assert chk.err_u <= CS_TOL and chk.err_v <= CS_TOL * max(1.0, case.Omega), chk
    assert chk.impacts == chk.impacts_exact > 0
    off_grid = res["time"][np.abs(res["time"] / h - np.round(res["time"] / h)) > 1e-9]
    assert off_grid.size >= chk.impacts  # it stopped at every impact (and at exits)
    assert np.isin(np.unique(res["t_impact"][res["impacts"] > 0]), off_grid).all()


#: (time, F_ext / Omega^2, u_wall): F_ext as the shift of the equilibrium it causes, so that one
#: file fits both parameter sets; a repeated time is a step (an input event in fmusim)
STAIRS = [(0.0, 0.0, 0.0), (2.5, 0.0, 0.0), (2.5, 0.1, -0.05), (5.25, 0.1, -0.05),
          (5.25, -0.2, 0.03), (7.5, -0.2, 0.03), (7.5, 0.0, -0.02), (10.0, 0.0, -0.02)]
RAMPS = [(0.0, 0.0, 0.0), (4.0, 0.2, -0.08), (10.0, -0.1, 0.04)]


def scaled(inputs, case: Case) -> list[tuple[float, float, float]]:
    return [(t, shift * case.Omega ** 2, w) for t, shift, w in inputs]


@pytest.mark.parametrize("name", ["over-compliant", "under-compliant"])
@pytest.mark.parametrize("version", FMUS)
@pytest.mark.parametrize("inputs,h", [(STAIRS, 0.1), (STAIRS, 0.01), (RAMPS, 0.1)],
                         ids=["stairs-0.1", "stairs-0.01", "ramps-0.1"])
def test_cs_with_input_file(inputs, version: str, h: float, name: str, tmp_path: Path) -> None:
    """F_ext and u_wall from a CSV file, compliant wall (a step may put the wall into the mass:
    the CS rule keeps the state). Ramps at h = 0.1 only: the FMU sees a new value at every
    communication point, a closed-form segment each."""
    case = CASES[name]
    _, chk = cs_check(FMUS[version], case, tmp_path, h, inputs=scaled(inputs, case))
    assert chk.err_u <= CS_TOL and chk.err_v <= CS_TOL * max(1.0, case.Omega), chk
    assert chk.impacts == chk.impacts_exact > 0


def me_check(fmu: Path, case: Case, tmp: Path) -> PeriodCheck:
    """One ME run in fmusim's CVODE (rtol 1e-10, output interval 0.1), compared per period."""
    res = run_fmusim(fmu, tmp, case, interface="me", stop=PERIODS, h=0.1,
                     flags=("--solver", "cvode"), tolerance=ME_RTOL)
    return compare_per_period(res["time"], res["u"], res["v"], res["impacts"], res["t_impact"],
                              case, [(0.0, 0.0, 0.0)], PERIODS, t_impact_tol=ME_TOL)


@pytest.mark.parametrize("version", FMUS)
@pytest.mark.parametrize("name", CASES)
def test_me_in_fmusims_cvode(name: str, version: str, tmp_path: Path) -> None:
    case = CASES[name]
    chk = me_check(FMUS[version], case, tmp_path)
    assert max(chk.err_u, chk.err_v) <= ME_TOL * chk.scale, chk
    assert chk.impacts == chk.impacts_exact > 0


# The wall steps into the mass (compliant wall, the overdamped orbit at u ~ -0.067 at t = 3):
# the CS rule keeps the state and starts a contact without an impact (docs/fmu.md); ME applies
# the same rule at fmusim's input event.
INTO_THE_MASS = [(0.0, 0.0, 0.0), (3.0, 0.0, 0.0), (3.0, 0.0, -0.1), (10.0, 0.0, -0.1)]
ME_HOLDS = [(0.0, 0.0, 0.0), (3.0, 0.0, -0.1)]


@pytest.mark.parametrize("version", FMUS)
def test_me_wall_stepping_into_the_mass_follows_the_cs_rule(version: str, tmp_path: Path) -> None:
    case = CASES["over-compliant"]
    ex = case.oscillator()
    (u, _), = ex.strobe(case.u0, case.v0, [3.0])[0]
    assert -0.1 < u < 0.0  # the new wall position is behind the mass: it is inside at once
    csv = write_input_csv(tmp_path / "inputs.csv", INTO_THE_MASS)
    # CS first: the documented rule, exact
    _, chk = cs_check(FMUS[version], case, tmp_path, 0.1, inputs=INTO_THE_MASS)
    assert chk.err_u <= CS_TOL and chk.err_v <= CS_TOL, chk
    res = run_fmusim(FMUS[version], tmp_path, case, interface="me", stop=PERIODS, h=0.1,
                     flags=("--solver", "cvode"), tolerance=ME_RTOL, input_csv=csv)
    chk = compare_per_period(res["time"], res["u"], res["v"], res["impacts"], res["t_impact"],
                             case, ME_HOLDS, PERIODS, t_impact_tol=ME_TOL)
    assert max(chk.err_u, chk.err_v) <= ME_TOL * chk.scale, chk


def _me_holds(inputs) -> list[tuple[float, float, float]]:
    """The held values of a staircase file: the last row at each time."""
    last = {t: (t, f, w) for t, f, w in inputs}
    return [last[t] for t in sorted(last)]


@pytest.mark.parametrize("version", FMUS)
@pytest.mark.parametrize("name", ["over-compliant", "under-compliant"])
def test_me_across_steps_of_both_inputs_restarts_fmusims_cvode(name: str, version: str,
                                                              tmp_path: Path) -> None:
    """The staircase of both inputs (three F_ext steps, three u_wall steps) in ME: at each input
    event the FMU reports valuesOfContinuousStatesChanged, fmusim re-initialises CVODE, and the
    run stays within ME_TOL of the closed form (before, with no state changed at an F_ext step,
    CVODE went on with its history: 6.4e-6 per period afterwards)."""
    case = CASES[name]
    inputs = scaled(STAIRS, case)
    res = run_fmusim(FMUS[version], tmp_path, case, interface="me", stop=PERIODS, h=0.1,
                     flags=("--solver", "cvode"), tolerance=ME_RTOL,
                     input_csv=write_input_csv(tmp_path / "inputs.csv", inputs))
    chk = compare_per_period(res["time"], res["u"], res["v"], res["impacts"], res["t_impact"],
                             case, _me_holds(inputs), PERIODS, t_impact_tol=ME_TOL)
    print(f"{name} {version}: {chk}")
    assert max(chk.err_u, chk.err_v) <= ME_TOL * chk.scale, chk
    assert chk.impacts == chk.impacts_exact > 0


TWIN_FMU = ROOT / "build" / "fmu" / "ImpactOscillatorPy.fmu"


@pytest.mark.parametrize("name,h", [("over-compliant", 1.0), ("under-rigid", 0.1)])
def test_pythonfmu_twin_in_fmusim(name: str, h: float, tmp_path: Path) -> None:
    """The twin (FMI 2.0 CS, Python inside) in a C host, with no Python environment given
    (two runs: each starts Python and scikit-sundae inside fmusim, several seconds)."""
    case = CASES[name]
    _, chk = cs_check(TWIN_FMU, case, tmp_path, h)
    assert chk.err_u <= CS_TOL and chk.err_v <= CS_TOL * max(1.0, case.Omega), chk
    assert chk.impacts == chk.impacts_exact > 0
