"""The tolerance-ball check (harness/runs/basins/ball.py) that lets one period within the
tolerance of an attractor's point label a start: its verdicts against the FMU's CVODE mode (an
independent solver, every start run in full), and the one-period stop changing no label of a
grid against the same grid run in full."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from harness import FmuModel, SamplingSpec
from harness.dynamics.attractors.identity import hausdorff
from harness.dynamics.maps.sampling import strobe
from harness.fmu import batch_kernel as bk
from harness.fmu.simulator import FmuSimulator
from harness.runs.basins.ball import ball_starts, check_balls
from harness.runs.basins.registry import Registry
from harness.runs.basins.tiles import label_result

#: Figure 7 at sigma = 0.01: two period-3 orbits, the two-impact one with a basin boundary
#: within the matching tolerance of one of its points
FIG7 = dict(nu=0.196, Omega=7.368, r=0.9, Gamma=1000.0, wall=1, sigma=0.01)
S = SamplingSpec(theta=0.0, n_transient=150, n_samples=30)
TOL = 0.0726  # the scan's own tolerance there (1e3 x tol x largest |v| sampled)


@pytest.fixture(scope="module")
def registry() -> Registry:
    """The attractors of a coarse grid run in full, each with its balls checked."""
    u0, v0 = (x.ravel() for x in np.meshgrid(np.linspace(-1.2, 0, 12), np.linspace(-8, 8, 12), indexing="ij"))
    full = bk.run_batch(FIG7, u0, v0, S.theta, S.n_transient, S.n_samples, None, threads=2)
    reg = Registry(TOL, ball=lambda known, a: check_balls(FIG7, S, 2, known, a))
    reg.merge(label_result(full, S, reg.known()))
    assert len(reg.found) == 2
    return reg


def test_ball_grid_spans_the_max_norm_ball() -> None:
    us, vs = ball_starts(np.array([[1.0, -2.0], [0.0, 0.0]]), 0.5, half=1)
    assert us.size == vs.size == 18
    assert np.max(np.abs(us[:9] - 1.0)) == 0.5 and np.max(np.abs(vs[:9] + 2.0)) == 0.5  # corners included
    assert np.allclose(np.sort(us[9:]), np.repeat([-0.5, 0.0, 0.5], 3))


def test_verdicts_agree_with_cvode(registry: Registry) -> None:
    """A start the check says leaves its ball's attractor leaves it on CVODE too; the corners of
    a ball that passed reach its attractor on CVODE."""
    passed = [f for f in registry.found if f.ball["inside"]]
    failed = [f for f in registry.found if not f.ball["inside"]]
    assert passed and failed  # both verdicts are exercised
    model = FmuModel(Path(__file__).resolve().parents[2] / "build" / "fmu" / "ImpactOscillator.fmu")
    cvode = {**FIG7, "solver": 0}
    with FmuSimulator(model.source()) as sim:
        for f, start in [(failed[0], failed[0].ball["first_other"]),
                         (passed[0], passed[0].array[0] + TOL), (passed[0], passed[0].array[-1] - TOL)]:
            r = strobe(sim, cvode, tuple(start), S.theta, S.n_transient, 2 * f.period)
            reached = hausdorff(np.column_stack([r.u, r.v]), f.array) <= TOL
            assert reached == bool(f.ball["inside"]), (start, f.period, f.impacts)


def test_the_one_period_stop_changes_no_label(registry: Registry) -> None:
    n = 40
    u0, v0 = (x.ravel() for x in np.meshgrid(np.linspace(-1.2, 0, n), np.linspace(-8, 8, n), indexing="ij"))
    full = bk.run_batch(FIG7, u0, v0, S.theta, S.n_transient, S.n_samples, None, threads=2)
    ref = registry.merge(label_result(full, S, registry.known()))
    known = registry.known()
    assert 1 in known.confirm  # the one-period rule is used, for the attractor that passed
    fast = bk.run_batch(FIG7, u0, v0, S.theta, S.n_transient, S.n_samples, known, threads=2)
    np.testing.assert_array_equal(registry.merge(label_result(fast, S, known)), ref)
    strict = bk.run_batch(FIG7, u0, v0, S.theta, S.n_transient, S.n_samples, registry.known(strict=True), threads=2)
    assert fast.periods.mean() < 0.8 * strict.periods.mean()  # and it stops sooner
