"""Resonant grazing (Simpson & Ghosh 2026) on a rigid wall: the saddle-node curve of the single-impact
period-M orbits emanates from grazing (sigma = 0) at the Omega where the damped natural frequency
omega_d = sqrt(Omega^2 - nu^2/4) is a rational multiple of the forcing frequency, omega_d M = pi
(P12(M) = 0), quadratically tangent to the grazing line; the atlas shows the tongue it bounds.

The fold is located in closed form (docs/examples/resonant-grazing/README.md): an orbit with one
impact at t_i with velocity v per M periods satisfies (I - P(M)) w(t_i) = -v q with w(t) = (1 - A cos
2 pi t, 2 pi A sin 2 pi t), A = 1 + sigma, q = (r P12, 1 + r P22); eliminating v leaves K0 + A (-K0
cos 2 pi t + K2 sin 2 pi t) = 0, whose two roots t_i merge at A = |K0| / sqrt(K0^2 + K2^2), K2 =
-2 pi (1 + r) P12(M): sigma_SN = 0 exactly where P12(M) = 0. The exact flow (mapcheck.exact, Newton
on its M-period map, independent of that algebra) confirms each fold: just above it a period-M orbit
with one impact whose multiplier approaches 1 by the square-root law, just below none.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from mapcheck.resonant_grazing import fold as resonant_fold
from tests.support.edges import ExactFlow

NU, R = 0.2, 0.8


def resonance(M: int, n: int = 1) -> float:
    """Omega with omega_d M = n pi."""
    return math.sqrt((n * math.pi / M) ** 2 + NU ** 2 / 4)


def fold(Omega: float, M: int = 1) -> tuple[float, float, float]:
    """(sigma_SN, impact time t_i, impact velocity v) of the single-impact period-M orbit."""
    return resonant_fold(NU, R, Omega, M)


def _exact_orbit(Omega: float, M: int, sigma: float, t: float, v: float):
    """Newton on the exact flow's M-period map from the orbit right after the predicted impact."""
    flow = ExactFlow(NU, Omega, R, 10.0, "rigid", theta=0.5)
    t1 = math.floor(t) + 0.5 + (1.0 if math.floor(t) + 0.5 <= t else 0.0)
    u0, v0, _ = flow.oscillator(sigma).state_at(0.0, -R * v, t, t1)
    orb = flow.orbit(sigma, M, [u0, v0])
    mu = flow.multipliers(sigma, orb.z[0], M) if orb.converged else None
    return orb, mu


@pytest.mark.parametrize("M", [1, pytest.param(2, marks=pytest.mark.slow)])
def test_the_fold_curve_leaves_grazing_at_the_resonance(M: int) -> None:
    om_star = resonance(M)
    d = (0.015, 0.03) if M == 1 else (0.004, 0.008)
    folds = []
    for x in d:
        s, t, v = fold(om_star + x, M)
        assert s < 0 and v > 0  # below grazing, an impact into the wall: admissible
        near, mu_near = _exact_orbit(om_star + x, M, s + 1e-3 * abs(s), t, v)
        far, mu_far = _exact_orbit(om_star + x, M, s + 4e-3 * abs(s), t, v)
        assert near.converged and far.converged and int(near.contacts.sum()) == 1 == int(far.contacts.sum())
        top_near, top_far = np.max(np.abs(mu_near)), np.max(np.abs(mu_far))
        assert 0.95 < top_far < top_near < 1.0
        # a fold: 1 - mu grows like the square root of the distance (4x farther: 2x)
        assert (1 - top_far) / (1 - top_near) == pytest.approx(2.0, rel=0.15)
        below, _ = _exact_orbit(om_star + x, M, s - 1e-3 * abs(s), t, v)
        assert not below.converged or int(below.contacts.sum()) != 1
        folds.append(s)
    # sqrt(-sigma_SN) is linear in Omega - Omega_0 to leading order: Omega_0 from the two folds
    r0, r1 = math.sqrt(-folds[0]), math.sqrt(-folds[1])
    om0 = om_star + d[0] - r0 * (d[1] - d[0]) / (r1 - r0)
    assert om0 == pytest.approx(om_star, abs=0.05 * d[0])
    # at the resonance itself the fold sits on the grazing line; a quadratic tangency
    assert abs(fold(om_star, M)[0]) < 1e-12
    c = [-s / x ** 2 for s, x in zip(folds, d)]
    assert c[1] == pytest.approx(c[0], rel=0.2)


def test_the_atlas_shows_the_tongue_the_fold_bounds() -> None:
    from harness.runs.atlas.plane import AtlasPlane
    from harness.runs.atlas.scan import run_atlas_plane
    from harness.runs.atlas.tiles import PERIODIC

    om = resonance(1) + np.array([0.04, 0.07, 0.1])
    sigma = np.linspace(-0.2, 0.0, 41)
    plane = AtlasPlane(dict(nu=NU, Omega=3.0, r=R, wall=2), "Omega", om, sigma, starts=6, theta=0.5)
    d = run_atlas_plane(plane, progress=False).data
    present = ((d["kind"] == PERIODIC) & (d["period"] == 1) & (d["impacts"] == 1)).any(axis=2)
    step = sigma[1] - sigma[0]
    for i, x in enumerate(om):
        s = fold(float(x))[0]
        assert not present[i][sigma < s - step].any()  # no single-impact orbit below its fold
        first = sigma[present[i]].min()
        assert s <= first <= s + 3 * step  # and the atlas finds it within three pixels above the fold
