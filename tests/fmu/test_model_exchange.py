"""Model Exchange (FMI 2.0, and FMI 3.0 once built): fmpy's own CVODE integrates the FMU's
derivatives and handles its wall indicator and jumps; the results agree with the closed-form
oracle and with the Co-Simulation interface of the same FMU."""
from __future__ import annotations

import numpy as np
import pytest
from fmpy import read_model_description

from mapcheck.exact import ExactOscillator
from tests.support.fmu import FMU3_PATH, FMU_PATH, LoggedSlave, at_times, on_orbit, simulate

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)
UNDERDAMPED = dict(nu=0.196, Omega=7.368)
T0 = 0.5

CASES = [
    ("compliant", 0.5, FIG9, 10.0),
    ("compliant", 0.2, FIG9, 10.0),
    ("rigid", 0.3, FIG9, 10.0),
    ("compliant", 0.05, UNDERDAMPED, 1000.0),
]


def paths():
    out = [FMU_PATH]
    if FMU3_PATH.exists():
        out.append(FMU3_PATH)
    return out


@pytest.mark.parametrize("path", paths(), ids=lambda p: p.name)
def test_model_description_declares_model_exchange(path):
    md = read_model_description(str(path))
    assert md.modelExchange is not None and md.coSimulation is not None
    assert md.modelExchange.modelIdentifier == md.coSimulation.modelIdentifier
    assert [s.name for s in md.modelVariables if s.name in ("u", "v")] == ["u", "v"]
    assert {d.variable.name for d in md.derivatives} == {"der(u)", "der(v)"}
    assert md.numberOfEventIndicators == 1


@pytest.mark.parametrize("path", paths(), ids=lambda p: p.name)
@pytest.mark.parametrize("wall,sigma,lin,Gamma", CASES)
def test_me_matches_oracle_and_cs(path, wall, sigma, lin, Gamma):
    n = 10
    times = T0 + np.arange(n + 1, dtype=float)
    start = dict(wall=wall, sigma=sigma, Gamma=Gamma, **on_orbit(sigma, T0), **lin)
    me = simulate(path, "ModelExchange", T0, times[-1], 1.0, rtol=1e-10, **start)
    x_me, k_me = at_times(me, times)
    exact, counts = ExactOscillator(lin["nu"], lin["Omega"], sigma, Gamma=Gamma, wall=wall) \
        .strobe(start["u0"], start["v0"], times, t0=T0)
    scale = max(1.0, np.abs(exact).max())
    assert np.abs(x_me - exact).max() <= 2e-6 * scale  # fmpy's CVODE, rtol 1e-10
    assert list(k_me) == list(counts)
    assert counts[-1] > 0, "the case was meant to hit the wall"

    cs = LoggedSlave(name="cs-vs-me")  # the FMI 2.0 CS interface of the same model
    try:
        cs.start(t0=T0, **start)
        x_cs = []
        for t in times[1:]:
            cs.step_to(float(t))
            x_cs.append(cs.state())
    finally:
        cs.close()
    assert np.abs(x_me[1:] - np.array(x_cs)).max() <= 2e-6 * scale


def test_me_records_each_impact_as_an_event_row():
    """fmpy records the state before and after each event: the rows at an entry time differ by
    the jump v -> r v (compliant, linear law) at u = 0."""
    sigma, r = 0.5, 0.9
    start = dict(wall="compliant", sigma=sigma, r=r, **on_orbit(sigma, T0), **FIG9)
    res = simulate(FMU_PATH, "ModelExchange", T0, T0 + 3, 1.0, **start)
    t, k = res["time"], res["impacts"]
    jumps = np.flatnonzero(np.diff(k) == 1)
    assert len(jumps) >= 2
    osc = ExactOscillator(FIG9["nu"], FIG9["Omega"], sigma, r=r)
    enters = [tc for tc, kind in osc.crossings(start["u0"], start["v0"], T0, T0 + 3)
              if kind == "enter"]
    assert len(enters) == len(jumps)
    for j, tc in zip(jumps, enters):
        assert t[j] == t[j + 1] and abs(t[j] - tc) < 1e-8
        assert abs(res["u"][j + 1]) < 1e-200  # on the wall (a hair inside, see model.c)
        assert res["v"][j + 1] == pytest.approx(r * res["v"][j], rel=1e-12)
