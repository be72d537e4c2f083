"""The default solver as sure as the exact one: `windows` under CVODE and under the closed form give
the same report row for row -- the same orbits, one row each, the same edge kinds, the edges within
CVODE's accuracy, coincident events (a birth at its parent's flip) located once under both.

Newton and the continuation stop at the residual the solver resolves (CVODE's error over M
periods, :func:`harness.dynamics.maps.periodic_map.map_accuracy`), not at the closed form's
rounding: a residual of 7e-10 is CVODE's accuracy, not "did not converge".
"""
from __future__ import annotations

import pytest

from harness.dynamics.maps.periodic_map import map_accuracy
from tests.support.random_oscillators import Oscillator, duplicate_rows, random_oscillator, windows_report

#: Edges of the two solvers agree to this (CVODE locates an edge to ~1e-9 in sigma).
EDGE_TOL = 1e-7

CASES = [
    # lightly damped rigid wall: the wall-free orbit, period 2 flipping, period 4 born there up to its graze
    pytest.param(Oscillator(0, 0.5, 2.5, 0.95, "rigid", 10.0), (-0.55, -0.25), 4, id="rigid-light",
                 marks=pytest.mark.slow),
    pytest.param(random_oscillator(6), (0.0, 0.3), 3, id="compliant-seed6", marks=pytest.mark.slow),
    pytest.param(random_oscillator(12), (-0.236, 0.064), 3, id="rigid-seed12", marks=pytest.mark.slow),
]


def _rows(res: dict) -> list[tuple]:
    return sorted((e["M"], e["impacts"], e.get("resolved"), e.get("lo"), e.get("hi"), tuple(e.get("kinds") or ()),
                   tuple(sorted((e.get("located_by") or {}).items())))
                  for e in res["ode_windows_all"])


@pytest.mark.parametrize("osc,rng,M_max", CASES)
def test_cvode_and_the_closed_form_give_the_same_windows(osc: Oscillator, rng, M_max: int, tmp_path) -> None:
    exact = windows_report(osc, rng, tmp_path / "cf", "closed-form", M_max)
    cvode = windows_report(osc, rng, tmp_path / "cv", "cvode", M_max)
    a, b = _rows(exact), _rows(cvode)
    assert [r[:3] for r in a] == [r[:3] for r in b], (a, b)  # the same orbits, one row each
    assert all(r[2] for r in b), "every orbit resolved under CVODE as under the closed form"
    for x, y in zip(a, b):
        assert x[5] == y[5], (x, y)  # edge kinds
        assert x[6] == y[6], (x, y)  # edges located once for two windows, under both
        for e1, e2 in zip(x[3:5], y[3:5]):
            assert (e1 is None) == (e2 is None) and (e1 is None or abs(e1 - e2) <= EDGE_TOL), (x, y)
    assert duplicate_rows(cvode) == []
    assert not any("did not converge" in line for line in (tmp_path / "cv" / "report.md").read_text().splitlines())


def test_newton_stops_at_the_solvers_accuracy() -> None:
    """The closed form: the callers' own tolerance (0 added); CVODE at its default rtol = 1e-12:
    1e-9 per period of the orbit, so 7e-10 over a period-3 orbit is converged."""
    assert map_accuracy({"solver": 1}, 6) == 0.0
    assert map_accuracy({"solver": 0, "rtol": 1e-12}, 3) == pytest.approx(3e-9)
    assert map_accuracy({"rtol": 1e-10}, 1) == pytest.approx(1e-7)  # the FMU's default solver is CVODE
