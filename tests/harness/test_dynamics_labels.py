"""The sweeps' ``dynamics`` label never contradicts the numbers next to it.

A sweep over Figure 9's sigma in [0.01, 0.6] with a short transient holds chaos (sigma < 0.15),
the period-adding windows and points near their edges that still converge (a period found in the
samples, which still shrink towards a shorter one).  Every point's label is checked against its
own period, samples and Lyapunov exponent by the rules of harness.dynamics.maps.classify, and the labels "periodic" and
"chaotic" against an independent truth: a run 40 times longer from the same start settles on a
period dividing the one found (periodic), or finds no period at all (chaotic).
"""
from __future__ import annotations

import numpy as np
import pytest

from harness import SamplingSpec, SweepSpec, classify_orbit, run_sweep, strobe
from harness.dynamics.maps.classify import (CHAOTIC, DECIDED, NOT_CONVERGED, PERIODIC, QUASI_PERIODIC, REASON_KEYS,
                                       SIGMAS, still_settling)
from harness.fmu.simulator import FmuSimulator
from tests.support.fmu import harness_params

SAMPLING = SamplingSpec(theta=0.5, n_transient=60, n_samples=16, lyapunov=100)
SIGMA = np.linspace(0.01, 0.6, 24)


@pytest.fixture(scope="module")
def sweep(model):
    ds = run_sweep(model, SweepSpec("sigma", SIGMA, ("fresh",)), sampling=SAMPLING, backend="serial",
                   progress=False)
    return ds.sel(direction="fresh")


def _points(ds):
    for i, sigma in enumerate(ds["sigma"].values):
        period = int(ds["period"].values[i])
        u, v = ds["u"].values[i], ds["v"].values[i]
        settling = period > 0 and still_settling(u, v, period, SAMPLING.tol)
        yield (float(sigma), period, settling, float(ds["lyapunov"].values[i, 0]),
               float(ds["lyapunov_err"].values[i, 0]), int(ds["dynamics"].values[i]),
               int(ds["dynamics_reason"].values[i]))


def test_sweep_covers_chaos_windows_and_edges(sweep) -> None:
    """The sweep has what the rules below are about (else they would pass vacuously)."""
    pts = list(_points(sweep))
    assert any(d == CHAOTIC for *_, d, _ in pts)
    assert any(p > 0 and not s for _, p, s, *_ in pts)  # converged periodic points
    assert any(p > 0 and s and lam < 0 for _, p, s, lam, *_ in pts)  # near an edge, still settling
    assert any(p == 0 and lam < 0 for _, p, _, lam, *_ in pts)  # no period found, attracting


def test_labels_agree_with_period_and_exponent(sweep) -> None:
    for sigma, period, settling, lam, err, dyn, reason in _points(sweep):
        where = f"sigma = {sigma:.4f}: P{period}, settling {settling}, lambda_1 = {lam:+.4f} +- {err:.4f}"
        if period > 0 and (lam < 0 or not settling):
            assert dyn == PERIODIC, where  # a detected period and a negative exponent: periodic
        if dyn == PERIODIC:
            assert period > 0, where
        if dyn == CHAOTIC:
            assert period == 0 and lam - SIGMAS * err > 0, where
        if dyn == QUASI_PERIODIC:
            assert period == 0 and abs(lam) <= SIGMAS * err, where
        decided = dyn in (PERIODIC, CHAOTIC, QUASI_PERIODIC)
        assert (reason == DECIDED) == decided, where
        if dyn == NOT_CONVERGED:
            # neither decides: the reason names which numbers left it open
            assert REASON_KEYS[reason] in ("attracting_no_period", "exponent_band_too_wide",
                                           "settling_exponent_not_negative"), where
            if REASON_KEYS[reason] == "attracting_no_period":
                assert period == 0 and lam + SIGMAS * err < 0, where
            if REASON_KEYS[reason] == "exponent_band_too_wide":
                assert period == 0 and abs(lam) <= SIGMAS * err, where
    flags = sweep["dynamics_reason"].attrs
    assert flags["flag_meanings"].split() == [REASON_KEYS[c] for c in sorted(REASON_KEYS)]


def test_labels_hold_after_a_long_run(model, sweep) -> None:
    """Periodic near an edge (settling, lambda_1 < 0): 40x longer from the same start, the orbit
    is periodic with a period dividing the one the sweep found.  Chaotic: still no period."""
    sim = FmuSimulator(model.source())
    pts = list(_points(sweep))
    edge = [p for p in pts if p[1] > 0 and p[2] and p[5] == PERIODIC]
    chaos = [p for p in pts if p[5] == CHAOTIC]
    assert edge and chaos
    for sigma, period, *_ in edge[:2] + chaos[:1]:
        r = strobe(sim, harness_params(model, sigma=sigma), (-1.0, 0.0), theta=SAMPLING.theta, n_transient=2400,
                   n_samples=48)
        orbit = classify_orbit(r.u, r.v, r.impacts, SAMPLING.tol)
        if period > 0:
            assert orbit.periodic and period % orbit.period == 0, (sigma, period, orbit)
            assert not still_settling(r.u, r.v, orbit.period, SAMPLING.tol)
        else:
            assert not orbit.periodic, (sigma, orbit)
