"""The fold of single-impact period-1 orbits continued over Omega from near a resonant grazing point.

Rigid wall, nu = 0.2, r = 0.8: the fold leaves sigma = 0 at Omega* = 3.1432 (omega_d = pi) and falls
below grazing quadratically as Omega grows (docs/examples/resonant-grazing). Started at the first value
of the range, the curve's first point is corrected orthogonally to the curve's tangent, which is steep
in sigma there, so its Omega lands a little below the range's start: the curve must go on from it over
the range, not stop at its first point.

Truth: the closed form of the fold (:func:`mapcheck.resonant_grazing.fold`, the free flight's algebra),
and the exact flow's orbit near it to start from (mapcheck, nothing of the FMU).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from harness.analysis.chart.wall_free import continued_intervals
from harness.dynamics.curves.event_curves import continue_event
from mapcheck.resonant_grazing import fold
from tests.support.edges import ExactFlow

NU, R, OM0 = 0.2, 0.8, 3.16


def test_the_fold_curve_goes_on_from_a_start_its_corrector_moved_below_the_range(model, sim) -> None:
    s, t, v = fold(NU, R, OM0)
    sigma0 = s + 1e-7 * abs(s)  # the fold, as located in sigma (the orbit exists just above it)
    flow = ExactFlow(NU, OM0, R, 10.0, "rigid", theta=0.5)
    t1 = math.floor(t) + 0.5 + (1.0 if math.floor(t) + 0.5 <= t else 0.0)
    u0, v0, _ = flow.oscillator(sigma0).state_at(0.0, -R * v, t, t1)
    orb = flow.orbit(sigma0, 1, [u0, v0])
    assert orb.converged and int(orb.contacts.sum()) == 1
    params = {**model.defaults(), "nu": NU, "r": R, "Omega": OM0, "wall": 2, "solver": 1}
    fc = continue_event(sim, params, "fold", 1, sigma0, orb.z[0], "Omega", (OM0, 3.3), False, 1.0,
                        sigma_range=(-0.25, 0.15), max_points=120)
    assert len(fc.p2) > 10 and fc.end["reason"] == "range", fc.end
    assert fc.p2[0] < OM0 and fc.p2[-1] > 3.25  # from below the start (its corrector) across the range
    for om, sg in zip(fc.p2, fc.sigma):
        assert sg == pytest.approx(fold(NU, R, float(om))[0], abs=1e-7)
    assert np.all(np.diff(fc.sigma) < 0)  # below grazing, further down as Omega grows
    # past the curve's end (below the charted sigma) the window is open below, not absent: at Omega =
    # 3.3 the closed form's fold lies below the range's bottom, and the window goes on above it
    assert fold(NU, R, 3.3)[0] < -0.25
    w = {"M": 1, "impacts": 1, "lower": {"kind": "fold"}, "upper": None, "closing": {"closes": None},
         "curves": {"lower": fc.as_dict(), "upper": None}}
    (c,) = continued_intervals([w], 3.3, None, 0.05, -0.15)
    assert c["lo"] is None and c["hi"] is None
    assert continued_intervals([w], 3.3, None, 0.05, None) == []  # without the range's bottom: not there
