"""The harness records the wall-event times an FMI 3.0 FMU reports through early return, and
they are the closed form's crossing times."""
from __future__ import annotations

import numpy as np
import pytest

from harness import FmuModel, FmuSimulator, HarnessInputError
from mapcheck.exact import ExactOscillator
from tests.support.fmu import FMU_PATH, harness_params, on_orbit

FMU3_PATH = FMU_PATH.with_name("ImpactOscillator_fmi3.fmu")
FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)
UNDERDAMPED = dict(nu=0.196, Omega=7.368)


@pytest.fixture(scope="module")
def model3() -> FmuModel:
    assert FMU3_PATH.is_file(), f"build the FMUs first ({FMU3_PATH} missing)"
    return FmuModel(FMU3_PATH)


@pytest.mark.parametrize("wall,sigma,lin,Gamma", [
    ("compliant", 0.5, FIG9, 10.0),      # entries and exits
    ("rigid", 0.05, UNDERDAMPED, 1000.0),  # impacts
    ("compliant", 0.05, UNDERDAMPED, 1000.0),
])
def test_event_times_are_the_closed_form_crossings(model3, wall, sigma, lin, Gamma):
    sim = FmuSimulator(model3.source(), record_events=True)
    walls = {"none": 0, "compliant": 1, "rigid": 2}
    params = harness_params(model3, sigma=sigma, Gamma=Gamma, wall=walls[wall], **lin)
    t0, t1 = 0.5, 12.5
    start = on_orbit(sigma, t0)
    sim.start(params, t0, (start["u0"], start["v0"]))
    sim.advance(t1)  # one period per doStep: every event comes back as an early return
    exact = [t for t, _ in ExactOscillator(lin["nu"], lin["Omega"], sigma, r=0.9, Gamma=Gamma, wall=wall)
             .crossings(start["u0"], start["v0"], t0, t1)]
    got = sim.event_times
    assert len(exact) >= 4, "the case was meant to hit the wall"
    assert len(got) == len(exact)
    # CVODE locates roots to ~1e-13 in time; the state error ahead of a crossing (~1e-11) over
    # the crossing speed (>= 1e-2 here) bounds the time error well below 1e-8
    assert np.max(np.abs(np.array(got) - np.array(exact))) < 1e-8
    # and the sampled states are those of a run without event mode
    u, v, n = sim.read()
    plain = FmuSimulator(model3.source())
    plain.start(params, t0, (start["u0"], start["v0"]))
    plain.advance(t1)
    assert np.max(np.abs(np.array(plain.read()[:2]) - [u, v])) < 1e-9
    assert plain.read()[2] == n
    assert plain.event_times == []


def test_event_times_need_fmi3(model):
    with pytest.raises(HarnessInputError, match="FMI 3.0"):
        FmuSimulator(model.source(), record_events=True)
