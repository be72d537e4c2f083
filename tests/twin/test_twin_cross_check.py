"""The pythonfmu twin against the C FMU: both driven by the *harness*
(``harness.fmu.simulator.FmuSimulator``, the same code path for both) over 50 periods for the
compliant, rigid and no wall; stroboscopic states and impact counts are equal bit for bit (both
step CVODE past the communication points and interpolate there).  Also with sigma tuned
mid-run, through chatter and sticking, the importer's tolerance, FMU states, the event log and
directional derivatives.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from mapcheck.exact import ExactOscillator
from tests.support.fmu import WALLS
from tests.support.twin import FIG9, THETA, UNDERDAMPED, Slave, harness_strobe, on_orbit


# ---------------------------------------------------------------------------------------------
# cross-check against the C FMU, both driven by the harness
# ---------------------------------------------------------------------------------------------
#: The twin and the C FMU over 50 periods: the same bits.  Both let CVODE take its own steps past
#: the communication points and read the state there from CVODE's interpolant (the C FMU with
#: CVodeGetDky, the twin with normal-mode CVode(tout) without a stop time, which returns
#: CVodeGetDky(tout)); both take the first step after a restart in one-step mode towards
#: tau + 1 and stop only at the re-origin time.  Same model, events, tolerances and CVODE
#: algorithm, so equality is what is asserted: the twin is a packaging cross-check of the C
#: FMU (another language, another SUNDIALS build), not an independent physics check.
XCASES = [
    # wall, sigma, linear part, Gamma, r, start state at THETA (None: on the wall-free orbit)
    ("compliant", 0.2, FIG9, 10.0, 0.9, None),            # period-3 window of Fig. 9
    ("rigid", 0.2, FIG9, 10.0, 0.9, None),                # strongly damped: rare impacts
    ("none", 0.3, FIG9, 10.0, 0.9, None),
    ("compliant", 0.05, UNDERDAMPED, 1000.0, 0.9, None),
    ("rigid", 0.05, UNDERDAMPED, 1000.0, 0.9, None),      # an impact about every other period
    ("compliant", 1e-6, UNDERDAMPED, 1000.0, 0.9, None),  # near grazing: contacts ~1e-6 deep
    ("rigid", 1e-4, UNDERDAMPED, 1000.0, 0.9, None),
]


@pytest.mark.parametrize("wall,sigma,lin,Gamma,r,state", XCASES)
def test_twin_agrees_with_c_fmu_over_50_periods(twin_fmu, c_fmu, wall, sigma, lin, Gamma, r,
                                                 state, record_property) -> None:
    params = dict(wall=WALLS[wall], sigma=sigma, Gamma=Gamma, r=r, **lin)
    state = state or on_orbit(THETA, sigma)
    c_states, c_counts, c_cost = harness_strobe(c_fmu, params, THETA, state, 50)
    t_states, t_counts, t_cost = harness_strobe(twin_fmu, params, THETA, state, 50)
    record_property("us_per_period_c", round(c_cost * 1e6, 1))
    record_property("us_per_period_twin", round(t_cost * 1e6, 1))
    diff = np.max(np.abs(t_states - c_states))
    record_property("max_state_difference", float(diff))
    assert diff == 0.0, f"max state difference {diff:.2e}"  # bit for bit (see above)
    np.testing.assert_array_equal(t_counts, c_counts)
    if wall != "none":
        assert c_counts[-1] > 0, "the case was meant to hit the wall"


def test_twin_agrees_with_c_fmu_through_chatter_and_sticking(twin_fmu, c_fmu) -> None:
    """Rigid wall, r = 0.5, released at the wall while the drive pushes in: chatter, sticking,
    release.  States agree after the release (both stick at u = v = 0 and release at the same
    zero of the wall force).  The impact counts of a Zeno sequence depend on where it is
    truncated: the twin sums the unresolvable tail in closed form and matches the oracle
    exactly; the C FMU resolves it with CVODE (observed: one impact fewer), so the two must
    agree to within one decade of impact velocity, the C FMU's own tolerance against the
    oracle."""
    sigma, r, state = 0.3, 0.5, (0.0, -0.1)
    params = dict(wall=WALLS["rigid"], sigma=sigma, r=r, **FIG9)
    t_states, t_counts, _ = harness_strobe(twin_fmu, params, THETA, state, 10)
    c_states, c_counts, _ = harness_strobe(c_fmu, params, THETA, state, 10)
    # not bit for bit: the chatter tails differ on purpose (docstring); measured 1.0e-10
    assert np.max(np.abs(t_states - c_states)) <= 1e-9
    osc = ExactOscillator(FIG9["nu"], FIG9["Omega"], sigma, r=r, wall="rigid")
    _, exact_counts = osc.strobe(*state, THETA + np.arange(1, 11), THETA)
    np.testing.assert_array_equal(t_counts, exact_counts)
    decade = math.log(10) / math.log(1 / r)
    assert np.all(np.abs(t_counts - c_counts) <= decade), (t_counts, c_counts)


def test_twin_agrees_with_c_fmu_when_sigma_is_tuned_mid_run(twin_fmu, c_fmu) -> None:
    """sigma is tunable: changed between doSteps it acts from that time on, in both FMUs
    (across a period-3 window, a period-1 orbit and back below grazing)."""
    params = dict(wall=WALLS["compliant"], sigma=0.2, **FIG9)
    tune = {9: 0.95, 19: 0.5, 29: -0.05}
    state = on_orbit(THETA, 0.2)
    c_states, c_counts, _ = harness_strobe(c_fmu, params, THETA, state, 40, tune)
    t_states, t_counts, _ = harness_strobe(twin_fmu, params, THETA, state, 40, tune)
    np.testing.assert_array_equal(t_states, c_states)  # bit for bit
    np.testing.assert_array_equal(t_counts, c_counts)
    # the change did something: impacts per period differ between the windows
    per_period = np.diff(c_counts)
    assert per_period[10:19].sum() != per_period[30:39].sum()


@pytest.mark.parametrize("tolerance", [1e-13, 1e-6])
def test_importer_tolerance_tightens_rtol_as_in_the_c_fmu(twin_fmu, c_fmu, tolerance) -> None:
    """setupExperiment's tolerance can only tighten rtol (1e-13 acts, 1e-6 is ignored): the two
    FMUs give the same states, and a tighter rtol changes them (it was applied)."""
    results = {}
    for name, path in (("twin", twin_fmu), ("c", c_fmu)):
        for tol in (None, tolerance):
            s = Slave(path)
            try:
                s.start(t0=THETA, tolerance=tol, sigma=0.5, u0=-2.5, v0=0.0, **FIG9)
                for k in range(5):
                    s.step_to(THETA + k + 1)
                results[name, tol] = s.state()
            finally:
                s.close()
    np.testing.assert_array_equal(results["twin", tolerance], results["c", tolerance])
    changed = np.any(results["twin", tolerance] != results["twin", None])
    assert changed == (tolerance < 1e-12)


def test_fmu_state_save_restore_serialize(twin_fmu, c_fmu) -> None:
    """fmi2GetFMUstate/SetFMUstate and serialisation: "continue" and "restore, then continue"
    (in the same instance, and in a fresh one from the serialised bytes) give the same bits, and
    the same bits as the C FMU doing the same."""
    finals = {}
    for path in (twin_fmu, c_fmu):
        a, b = Slave(path), Slave(path)
        try:
            u0, v0 = on_orbit(THETA, 0.2)
            a.start(t0=THETA, sigma=0.2, u0=u0, v0=v0, **FIG9)
            a.step_to(THETA + 3)
            saved = a.slave.getFMUstate()
            blob = a.slave.serializeFMUstate(saved)
            a.step_to(THETA + 8)
            first = (a.state(), a.impacts())
            a.slave.setFMUstate(saved)
            a.t = THETA + 3
            a.step_to(THETA + 8)
            again = (a.state(), a.impacts())
            a.slave.freeFMUstate(saved)
            b.start(t0=0.0)  # another run entirely, then the serialised state
            restored = b.slave.deSerializeFMUstate(blob)
            b.slave.setFMUstate(restored)
            b.t = THETA + 3
            b.step_to(THETA + 8)
            other = (b.state(), b.impacts())
            b.slave.freeFMUstate(restored)
        finally:
            a.close()
            b.close()
        assert np.array_equal(first[0], again[0]) and first[1] == again[1] > 0
        assert np.array_equal(first[0], other[0]) and first[1] == other[1]
        finals[path.name] = first
    np.testing.assert_array_equal(finals[twin_fmu.name][0], finals[c_fmu.name][0])
    assert finals[twin_fmu.name][1] == finals[c_fmu.name][1]


def test_event_log_is_the_c_fmus(twin_fmu, c_fmu) -> None:
    """With logging on, both FMUs report the wall events of each step in the same words; with
    logging off, neither says anything."""
    logs = {}
    for path in (twin_fmu, c_fmu):
        for logging in (True, False):
            s = Slave(path, logging=logging)
            try:
                u0, v0 = on_orbit(THETA, 0.5)
                s.start(t0=THETA, sigma=0.5, u0=u0, v0=v0, **FIG9)
                for k in range(3):
                    s.step_to(THETA + k + 1)
                logs[path.name, logging] = s.messages
            finally:
                s.close()
    assert logs[twin_fmu.name, True] == logs[c_fmu.name, True]
    assert len(logs[twin_fmu.name, True]) == 3
    assert all(cat == "logEvents" for _, cat, _ in logs[twin_fmu.name, True])
    assert logs[twin_fmu.name, False] == logs[c_fmu.name, False] == []


def test_twins_directional_derivatives_are_the_c_fmus_in_co_simulation(twin_fmu: Path,
                                                                       c_fmu: Path) -> None:
    """The twin (Co-Simulation, no inputs) answers fmi2GetDirectionalDerivative from its C front:
    its Real outputs u, v with respect to the states u, v, as the C FMU's Co-Simulation does."""
    from fmpy.fmi1 import FMICallException
    seeds = [(1.0, 0.0), (0.0, 1.0), (0.3, -2.0)]
    got = {}
    for path in (twin_fmu, c_fmu):
        s = Slave(path)
        try:
            s.start(t0=0.0, u0=-0.4, v0=0.5)
            s.step_to(0.7)
            got[path] = [s.slave.getDirectionalDerivative([13, 14], [13, 14], list(w))
                         for w in seeds]
            if path == twin_fmu:
                with pytest.raises(FMICallException):
                    s.slave.getDirectionalDerivative([13], [2], [1.0])  # sigma: no known
        finally:
            s.close()
    assert got[twin_fmu] == got[c_fmu] == [list(w) for w in seeds]
