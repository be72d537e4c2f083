"""The FMU's two solvers against each other on oscillators nobody has looked at: the closed form and
CVODE over random parameters (light damping, r near 1, rigid and compliant walls, sigma below 0)
and random starts must see the same impacts in every period while their states agree.

Each oscillator of :mod:`tests.support.random_oscillators` is run from random starts for
:data:`PERIODS` periods by both solvers.  While the two states at the start of a period agree (to
:data:`STATE_TOL`; beyond it a chaotic orbit has amplified their 1e-10 differences, and nothing
more is compared), the wall entries of that period must be equal, except (a) one entry more or
fewer with the states after the period still agreeing (a grazing contact 1e-12 deep that one
solver resolves and the other not), (b) a chatter on a rigid wall that both end in sticking
(at least :data:`CHATTER` entries each: their counts of vanishing impacts differ).  A spurious
chatter of one solver (90 entries for the other's 4) is neither.
"""
from __future__ import annotations

import numpy as np
import pytest

from tests.support.random_oscillators import FAST_SEEDS, impact_sequences, random_oscillator, slow_seeds, starts

PERIODS = 30
STARTS = 6
STATE_TOL = 1e-6
CHATTER = 10


@pytest.fixture(scope="module")
def sims():
    from harness.fmu.fmi import FmuModel
    from harness.fmu.simulator import FmuSimulator

    model = FmuModel("build/fmu/ImpactOscillator.fmu")
    return {"cvode": FmuSimulator(model.source(), instance_name="random-cvode"),
            "closed-form": FmuSimulator(model.source(), instance_name="random-closed-form")}


def disagreements(seed: int, sims, n_starts: int = STARTS) -> list[str]:
    """Every period where the two solvers' impacts differ while their states agree."""
    osc = random_oscillator(seed)
    rng = np.random.default_rng(10_000 + seed)
    out = []
    for _ in range(n_starts):
        sigma = float(rng.uniform(-0.4, 1.5))
        u, v = starts(sigma, 1, rng)
        z0 = (float(u[0]), float(v[0]))
        seq = impact_sequences(osc, sigma, z0, PERIODS, sims)
        (pc, ic), (pf, i_f) = seq["cvode"], seq["closed-form"]
        scale = max(1.0, float(np.max(np.abs(pf))))
        for k in range(PERIODS):
            if np.max(np.abs(pc[k] - pf[k])) > STATE_TOL * scale:
                break  # the states parted (chaos, or a grazing contact decided differently): no more to compare
            if ic[k] == i_f[k]:
                continue
            after = float(np.max(np.abs(pc[k + 1] - pf[k + 1])))
            if abs(int(ic[k]) - int(i_f[k])) == 1 and after <= STATE_TOL * scale:
                continue  # a grazing contact seen by one solver only
            if osc.wall == "rigid" and min(ic[k], i_f[k]) >= CHATTER and after <= STATE_TOL * scale:
                continue  # both chatter into sticking; the number of vanishing impacts is not a quantity
            out.append(f"{osc}, sigma = {sigma:.6g}, start ({z0[0]:.6g}, {z0[1]:.6g}), period {k}: "
                       f"CVODE {ic[k]} wall entries, closed form {i_f[k]} (states differ by {after:.2g} after it)")
            break
    return out


#: seeds that found a bug: 107 (its closed form chattered where CVODE did not, with the curvature
#: margin of the certified monotone step dropped: mutant M66)
BUG_SEEDS = (107,)


@pytest.mark.parametrize("seed", FAST_SEEDS + BUG_SEEDS + (5, 7))
def test_closed_form_and_cvode_see_the_same_impacts(seed: int, sims) -> None:
    assert disagreements(seed, sims) == []


@pytest.mark.slow
@pytest.mark.parametrize("seed", slow_seeds())
def test_closed_form_and_cvode_see_the_same_impacts_on_more_oscillators(seed: int, sims) -> None:
    assert disagreements(seed, sims) == []
