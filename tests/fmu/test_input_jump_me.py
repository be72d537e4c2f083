"""One rule for input jumps in Co-Simulation and Model Exchange.

A compliant wall given as a staircase u_wall(t): at t = 1 it steps past the mass while the mass
is in contact (the mass is then outside: the contact ends, the mass does not move; README
"Inputs that jump", model_input_jump), at t = 2.5 it steps back. Model Exchange through fmpy
(FMI 2.0 and 3.0, fmpy's CVODE at rtol 1e-10) once put the mass onto the new wall position and
counted an extra impact (2e-2 per period). Here ME, the FMU's own Co-Simulation (the
input set between steps) and the closed form, solved piecewise between the jumps
(mapcheck.exact with u_wall held constant, the state carried across each jump unchanged), agree
at every period, and so do the impact counts.
"""
from __future__ import annotations

import numpy as np
import pytest
from fmpy import simulate_fmu

from mapcheck.exact import ExactOscillator
from tests.support.fmu import FMU3_PATH, FMU_PATH, LoggedSlave

LIN = dict(nu=4.605170185988091, Omega=0.3059238689620112)
SIGMA, GAMMA, R = 0.5, 10.0, 0.8
W0, T_JUMPS, T_END = -0.1, (1.0, 2.5), 12.0
PERIODS = np.arange(1.0, T_END + 0.5, 1.0)


def _exact(walls: list[float]) -> tuple[np.ndarray, np.ndarray, tuple[float, float]]:
    """Per-period states and impact counts of the closed form across the staircase."""
    ex = ExactOscillator(LIN["nu"], LIN["Omega"], SIGMA, R, GAMMA, "compliant", u_wall=walls[0])
    u0, v0 = (float(x) for x in ex.wall_free_orbit(0.0))
    edges = (0.0,) + T_JUMPS + (T_END,)
    states, counts, u, v, total = [], [], u0, v0, 0
    for k, w in enumerate(walls):
        seg = ExactOscillator(LIN["nu"], LIN["Omega"], SIGMA, R, GAMMA, "compliant", u_wall=w)
        times = [t for t in PERIODS if edges[k] < t <= edges[k + 1]]
        st, cnt = seg.strobe(u, v, times + [edges[k + 1]], edges[k])
        states += list(st[:-1])
        counts += [total + c for c in cnt[:-1]]
        u, v = st[-1]
        total += int(cnt[-1])
    return np.array(states), np.array(counts), (u0, v0)


def _staircase() -> tuple[list[float], float, float]:
    """The wall positions: the first jump lands 0.01 beyond the mass while it is inside."""
    ex = ExactOscillator(LIN["nu"], LIN["Omega"], SIGMA, R, GAMMA, "compliant", u_wall=W0)
    u0, v0 = (float(x) for x in ex.wall_free_orbit(0.0))
    (u1, _), = ex.strobe(u0, v0, [T_JUMPS[0]])[0]
    assert u1 > W0, "the mass must be in contact when the wall steps"
    return [W0, u1 + 0.01, W0 - 0.05], u0, v0


@pytest.fixture(scope="module")
def reference():
    walls, u0, v0 = _staircase()
    states, counts, _ = _exact(walls)
    return walls, u0, v0, states, counts


def _start_values(u0: float, v0: float) -> dict:
    return dict(wall=1, sigma=SIGMA, Gamma=GAMMA, r=R, u0=u0, v0=v0, u_wall=W0, **LIN)


def test_co_simulation_applies_the_rule(reference):
    walls, u0, v0, states, counts = reference
    fmu = LoggedSlave(name="jumpcs")
    try:
        fmu.start(**_start_values(u0, v0))
        got, n = [], []
        for t in PERIODS:
            for k, tj in enumerate(T_JUMPS):
                if fmu.t < tj <= t:
                    fmu.step_to(tj)
                    fmu.set(u_wall=walls[k + 1])
            if t > fmu.t:
                fmu.step_to(t)
            got.append(fmu.state())
            n.append(fmu.impacts())
        err = np.max(np.abs(np.array(got) - states))
        assert err <= 1e-8, err
        assert n == list(counts)
    finally:
        fmu.close()


@pytest.mark.parametrize("path", [FMU_PATH, FMU3_PATH], ids=["fmi2", "fmi3"])
def test_model_exchange_applies_the_same_rule(reference, path):
    walls, u0, v0, states, counts = reference
    rows = [(0.0, walls[0])]
    for k, tj in enumerate(T_JUMPS):
        rows += [(tj, walls[k]), (tj, walls[k + 1])]
    rows.append((T_END, walls[-1]))
    signal = np.array(rows, dtype=[("time", np.float64), ("u_wall", np.float64)])
    res = simulate_fmu(str(path), fmi_type="ModelExchange", start_time=0.0, stop_time=T_END,
                       output_interval=1.0 / 64, relative_tolerance=1e-10, input=signal,
                       start_values={k: x for k, x in _start_values(u0, v0).items()
                                     if k != "u_wall"},
                       output=["u", "v", "impacts"])
    rows_at = [int(np.flatnonzero(np.isclose(res["time"], t, rtol=0, atol=1e-12))[-1])
               for t in PERIODS]
    got = np.c_[res["u"][rows_at], res["v"][rows_at]]
    err = np.max(np.abs(got - states))
    # fmpy's CVODE at rtol 1e-10 with event location: well inside 1e-6 (an ME update that moved the
    # mass onto the stepped wall would be off by 2e-2)
    assert err <= 1e-6, err
    assert list(res["impacts"][rows_at]) == list(counts)


@pytest.mark.parametrize("interface", ["fmi2-me", "fmi3-me"])
@pytest.mark.parametrize("jump", [dict(F_ext=0.3), dict(u_wall=-0.05), dict(u_wall=-0.6)])
def test_an_input_jump_in_event_mode_asks_the_importer_to_restart(interface, jump):
    """A jump of F_ext or u_wall set in Event Mode makes the right-hand side jump: the event
    iteration reports valuesOfContinuousStatesChanged (the flag on which fmusim restarts its
    integrator; FMPy restarts at every event), with the state itself unchanged unless the input-jump rule moves it (the
    wall stepping 0.1 past the mass into the compliant wall: the state kept, contact taken)."""
    from tests.support.derivatives import Instance

    x = Instance(interface, u0=-0.5, v0=0.2, wall=1)
    try:
        x.enter_event_mode()
        x.set_inputs(**jump)
        assert x.event_update()
        assert x.states().tolist() == [-0.5, 0.2]
        assert x.integer("in_contact") == int(jump.get("u_wall", 0.0) < -0.5)
        x.fmu.enterContinuousTimeMode()
        x.enter_event_mode()  # no input changed since: nothing to restart
        assert not x.event_update()
    finally:
        x.close()
