"""The pythonfmu twin (build/fmu/ImpactOscillatorPy.fmu) against the C FMU and the closed form.

* Build and interface: the one build command writes an FMU that ``fmpy validate`` accepts and
  whose variables (names, value references, types, causality, variability, initial, start,
  bounds) are exactly the C FMU's, so the harness drives either unchanged.
* Cross-check: both FMUs are driven by the *harness* (``harness.fmu.simulator.FmuSimulator``, the
  same code path for both) over 50 periods for the compliant, rigid and no wall; stroboscopic
  states and impact counts are equal bit for bit (both step CVODE past the communication
  points and interpolate there).  Also with sigma tuned mid-run.
* Oracle: the twin alone against ``mapcheck.exact.ExactOscillator`` (closed form, sharing no
  code with either FMU): one-period maps, 1e-9-deep grazing contacts at several phases, rigid
  chatter ending in sticking, the local time origin at t = 1e6.
* Bad parameters: rejected with a message naming the variable, and the instance stays usable
  (pythonfmu reports any Python exception as fmi2Fatal; the twin keeps the instance alive).
"""
from __future__ import annotations

import importlib.util
import math
import os
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path
from typing import Iterator

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from harness.fmu.fmi import FmuModel
from harness.fmu.simulator import FmuSimulator
from mapcheck.exact import ExactOscillator
from tests.support.fmu import WALLS, LoggedSlave

ROOT = Path(__file__).resolve().parents[2]
TWIN_SRC = ROOT / "fmu_src" / "pytwin"
TWIN_FMU = ROOT / "build" / "fmu" / "ImpactOscillatorPy.fmu"
C_FMU = ROOT / "build" / "fmu" / "ImpactOscillator.fmu"

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)  # overdamped, the paper's Fig. 9
UNDERDAMPED = dict(nu=0.196, Omega=7.368)
THETA = 0.5  # strobe half a period away from the grazing phase t = n



# ---------------------------------------------------------------------------------------------
# fixtures and helpers
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def twin_fmu() -> Path:
    """The twin as the set-up script builds it; rebuilt here if missing or older than its
    sources, so that the tests never run a stale twin."""
    sources = [*TWIN_SRC.glob("*.py"), *TWIN_SRC.glob("*.c")]
    if not TWIN_FMU.exists() or max(p.stat().st_mtime for p in sources) > TWIN_FMU.stat().st_mtime:
        subprocess.run(
            [sys.executable, str(TWIN_SRC / "build.py"), "--out", str(TWIN_FMU)],
            check=True, cwd=ROOT, capture_output=True,
        )
    return TWIN_FMU


@pytest.fixture(scope="module")
def c_fmu() -> Path:
    assert C_FMU.exists(), f"{C_FMU} missing: build it with scripts/setup.sh"
    return C_FMU


def Slave(path: Path, logging: bool = False) -> LoggedSlave:
    """fmpy's FMU2Slave on one FMU, collecting log messages (status, category, text).

    The tests of the twin alone use this (not the harness) so that they also see the FMI
    status codes and the log; the cross-check uses the harness.
    """
    return LoggedSlave(path=path, name="twin-test", logging=logging)


@pytest.fixture(scope="module")
def twin(twin_fmu: Path) -> Iterator[Slave]:
    s = Slave(twin_fmu)
    yield s
    s.close()


def on_orbit(t0: float, sigma: float) -> tuple[float, float]:
    """The wall-free periodic orbit p(t) = (1+sigma) cos(2 pi t) - 1 of eq (4) at t0."""
    w = 2.0 * math.pi
    return (1 + sigma) * math.cos(w * t0) - 1, -(1 + sigma) * w * math.sin(w * t0)


def harness_strobe(path: Path, params: dict, t0: float, state: tuple[float, float],
                   periods: int, tune: dict[int, float] | None = None
                   ) -> tuple[np.ndarray, np.ndarray, float]:
    """Drive one FMU through the harness's simulator and strobe it once per period.

    Parameters
    ----------
    path : Path
        The FMU.
    params : dict
        Parameters (by name) for ``FmuSimulator.start``.
    t0, state : float, (float, float)
        Start time and (u, v) there.
    periods : int
        Number of periods; the strobe times are t0 + 1, ..., t0 + periods.
    tune : dict, optional
        {period index k: sigma}: set sigma (tunable) after the k-th strobe.

    Returns
    -------
    states : ndarray (periods, 2)
    impacts : ndarray (periods,)
    seconds_per_period : float
        Wall-clock cost of the stepping (initialisation excluded).
    """
    sim = FmuSimulator(FmuModel(path).source(), instance_name="twin-xcheck")
    try:
        sim.start(params, t0, state)
        states, counts = np.empty((periods, 2)), np.empty(periods, dtype=int)
        tic = time.perf_counter()
        for k in range(periods):
            sim.advance(t0 + k + 1)
            u, v, n = sim.read()
            states[k] = u, v
            counts[k] = n
            if tune and k in tune:
                sim.set_parameter("sigma", tune[k])
        return states, counts, (time.perf_counter() - tic) / periods
    finally:
        sim.close()


# ---------------------------------------------------------------------------------------------
# build and interface
# ---------------------------------------------------------------------------------------------
def test_build_command_writes_a_valid_fmu(tmp_path: Path) -> None:
    """The README's build command, run as the set-up script runs it, gives an FMU that fmpy's
    validator accepts (pythonfmu alone would leave InitialUnknowns empty and fail it)."""
    out = tmp_path / "ImpactOscillatorPy.fmu"
    proc = subprocess.run([sys.executable, str(TWIN_SRC / "build.py"), "--out", str(out)],
                          cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert validate_fmu(str(out)) == []
    with zipfile.ZipFile(out) as z:
        names = set(z.namelist())
        md = ET.fromstring(z.read("modelDescription.xml"))
    assert {"binaries/linux64/ImpactOscillatorPy.so", "resources/ImpactOscillatorPy.py",
            "resources/impact_twin_model.py", "resources/slavemodule.txt"} <= names
    assert len(md.findall("ModelStructure/InitialUnknowns/Unknown")) == 7


#: The variables of the oscillator FMU, in value-reference order.
ISSUE_VARIABLES = ["nu", "Omega", "sigma", "r", "Gamma", "wall", "u0", "v0", "rtol", "atol",
                   "F_g", "phi", "kappa", "u", "v", "impacts", "in_contact"]


def _variables(path: Path) -> dict[str, dict]:
    md = read_model_description(str(path))
    return {
        v.name: dict(vr=v.valueReference, type=v.type, causality=v.causality,
                     variability=v.variability, initial=v.initial,
                     start=None if v.start is None or v.type == "Boolean" else float(v.start),
                     min=v.min, max=v.max, unit=v.unit)
        for v in md.modelVariables
    }


def test_interface_is_the_c_fmus(twin_fmu: Path, c_fmu: Path) -> None:
    """The twin's variables are the oscillator's, each with the C FMU's value reference, type,
    causality, variability, initial, start value, bounds and unit: the harness sees no
    difference.  (Descriptions are documentation and may differ where the C FMU documents
    features the twin does not have.)  Variables the C FMU has beyond these (it grows: Model
    Exchange, other contact laws) are not required of the twin."""
    twin_vars, c_vars = _variables(twin_fmu), _variables(c_fmu)
    assert list(twin_vars) == ISSUE_VARIABLES
    for name in ISSUE_VARIABLES:
        assert twin_vars[name] == c_vars[name], name
    # the InitialUnknowns of these variables, with their dependencies, too
    deps = []
    for path in (twin_fmu, c_fmu):
        md = read_model_description(str(path))
        # (dependencies on the C FMU's ports, which the twin lacks, are left out)
        deps.append({u.variable.name: sorted(d.name for d in (u.dependencies or [])
                                             if d.name in ISSUE_VARIABLES)
                     for u in md.initialUnknowns if u.variable.name in ISSUE_VARIABLES})
    assert deps[0] == deps[1]


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


# ---------------------------------------------------------------------------------------------
# the twin alone against the closed form
# ---------------------------------------------------------------------------------------------
OCASES = [
    ("compliant", 0.2, FIG9, 10.0),
    ("compliant", 0.95, FIG9, 10.0),
    ("rigid", 0.02, FIG9, 10.0),
    ("none", 0.3, FIG9, 10.0),
    ("compliant", 0.05, UNDERDAMPED, 1000.0),
    ("rigid", 0.05, UNDERDAMPED, 1000.0),
]


@pytest.mark.parametrize("wall,sigma,lin,Gamma", OCASES)
def test_one_period_map_matches_closed_form(twin, wall, sigma, lin, Gamma) -> None:
    """Each one-period step of the twin, from its own state, against the exact map (so that
    any instability of the orbit cannot amplify the error)."""
    u0, v0 = on_orbit(THETA, sigma)
    twin.start(t0=THETA, wall=wall, sigma=sigma, Gamma=Gamma, u0=u0, v0=v0, **lin)
    osc = ExactOscillator(lin["nu"], lin["Omega"], sigma, r=0.9, Gamma=Gamma, wall=wall)
    worst, n_twin, n_exact = 0.0, 0, 0
    x, k = twin.state(), twin.impacts()
    for n in range(20):
        t = THETA + n
        exact, count = osc.strobe(x[0], x[1], [t + 1.0], t0=t)
        twin.step_to(t + 1.0)
        x, k_new = twin.state(), twin.impacts()
        worst = max(worst, float(np.max(np.abs(x - exact[0]))))
        n_twin += k_new - k
        n_exact += int(count[0])
        k = k_new
    assert worst <= 1e-8, f"worst one-period error {worst:.2e}"
    assert n_twin == n_exact
    if wall != "none":
        assert n_twin > 0, "the case was meant to hit the wall"


def test_whole_orbit_matches_closed_form(twin) -> None:
    """20 periods in one run, strobed, against the closed form from the same start."""
    sigma = 0.5
    u0, v0 = on_orbit(THETA, sigma)
    twin.start(t0=THETA, sigma=sigma, u0=u0, v0=v0, **FIG9)
    times = np.arange(1, 21) + THETA
    exact, counts = ExactOscillator(FIG9["nu"], FIG9["Omega"], sigma).strobe(u0, v0, times, THETA)
    got = []
    for t in times:
        twin.step_to(float(t))
        got.append(twin.state())
    assert np.max(np.abs(np.array(got) - exact)) < 1e-8
    assert twin.impacts() == counts[-1] > 0


@pytest.mark.parametrize("lin", [FIG9, UNDERDAMPED], ids=["overdamped", "underdamped"])
@pytest.mark.parametrize("wall", ["compliant", "rigid"])
@pytest.mark.parametrize("t0", [0.05, 0.3, 0.5, 0.77, 0.999])
def test_grazing_contact_1e9_deep_is_found(twin, wall, lin, t0) -> None:
    """On the wall-free orbit with sigma = 1e-9 the maximum pokes 1e-9 into the wall at t = 1,
    reached from several phases (the contact falls at different places in the solver's steps);
    with sigma = -1e-9 it misses by 1e-9 and no contact may be invented."""
    for depth, expected in [(1e-9, 1), (-1e-9, 0)]:
        u0, v0 = on_orbit(t0, depth)
        twin.start(t0=t0, wall=wall, sigma=depth, u0=u0, v0=v0, Gamma=1000.0, **lin)
        twin.step_to(1.5)
        assert twin.impacts() == expected, f"depth {depth}: {twin.impacts()} contacts"


def test_rigid_chatter_ends_in_sticking(twin) -> None:
    """Rigid wall, r = 0.5, leaving the wall slowly while the net force pushes in: impacts
    accumulate in finite time; the twin must stick (in_contact, u = v = 0), release when the
    force stops pushing, and count the oracle's impacts (to one: the oracle sticks below the
    same velocity, but a chatter impact that close to the threshold is a coin toss)."""
    sigma, r, t0, (u0, v0) = 0.3, 0.5, THETA, (0.0, -0.1)
    twin.start(t0=t0, wall="rigid", sigma=sigma, r=r, u0=u0, v0=v0, **FIG9)
    osc = ExactOscillator(FIG9["nu"], FIG9["Omega"], sigma, r=r, wall="rigid")
    kinds = [k for _, k in osc.crossings(u0, v0, t0, t0 + 3)]
    assert "stick" in kinds and "release" in kinds, "the case was meant to chatter"
    stuck_seen = False
    for t in np.arange(t0 + 0.02, t0 + 3, 0.02):
        twin.step_to(float(t))
        if twin.in_contact():
            stuck_seen = True
            assert np.all(twin.state() == 0.0)
    assert stuck_seen
    assert not twin.in_contact(), "released by the end"
    _, counts = osc.strobe(u0, v0, [twin.t], t0)
    assert abs(twin.impacts() - counts[0]) <= 1, (twin.impacts(), counts[0])


def test_local_time_origin_keeps_accuracy_at_t_1e6(twin) -> None:
    """Started at t = 10^6 + 1/2 the one-period map is as accurate as near t = 0 (the forcing
    phase is kept in an integer time origin plus a local time)."""
    sigma = 0.5
    osc = ExactOscillator(FIG9["nu"], FIG9["Omega"], sigma)
    errors = []
    for t0 in (THETA, 1e6 + THETA):
        u0, v0 = on_orbit(t0, sigma)
        twin.start(t0=t0, sigma=sigma, u0=u0, v0=v0, **FIG9)
        exact, counts = osc.strobe(u0, v0, [t0 + 1, t0 + 2, t0 + 3], t0=t0)
        got = []
        for k in (1, 2, 3):
            twin.step_to(t0 + k)
            got.append(twin.state())
        errors.append(float(np.max(np.abs(np.array(got) - exact))))
        assert twin.impacts() == counts[-1] > 0
    assert max(errors) < 1e-8, errors


# ---------------------------------------------------------------------------------------------
# the grazing guard's locating step (white box: at the default tolerances CVODE's own root
# finding on v already samples inside a shallow contact, so the guard is a backstop that the
# FMU-level tests above rarely reach)
# ---------------------------------------------------------------------------------------------
def test_guard_locates_a_stepped_over_crossing() -> None:
    """Hand the driver's locating step a free flight whose last good point lies before a 1e-6
    deep contact and a turning point past it: it must return the exact entry time."""
    # Loaded under another name: the twin FMU, running in this process, imports its own copy
    # as ``impact_twin_model`` and must not find this one in sys.modules. The parts it gathers
    # (twin_rules, twin_physics, twin_cvode) are imported by their names from the source folder.
    if str(TWIN_SRC) not in sys.path:
        sys.path.append(str(TWIN_SRC))
    spec = importlib.util.spec_from_file_location("twin_model_under_test",
                                                  TWIN_SRC / "impact_twin_model.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    CvodeDriver, OscillatorModel = mod.CvodeDriver, mod.OscillatorModel
    depth, t_good = 1e-6, 0.97
    m = OscillatorModel()
    m.wall, m.Gamma = 1, 1000.0
    m.set_real("sigma", depth)
    m.u0, m.v0 = on_orbit(t_good, depth)
    drv = CvodeDriver(m)
    drv.start(t_good)
    m.initialize_state(drv.tau)
    drv._reinit()
    found = drv._locate_missed_crossing(1.0)  # the maximum of u is at t = 1 (local time)
    assert found is not None
    tc, yc = found
    # exact entry: (1 + depth) cos(2 pi t) - 1 = 0 just before t = 1
    t_exact = 1.0 - math.acos(1.0 / (1.0 + depth)) / (2.0 * math.pi)
    assert abs(drv.origin + tc - t_exact) < 1e-9
    assert yc[0] >= 0.0 and yc[1] > 0.0


# ---------------------------------------------------------------------------------------------
# bad input
# ---------------------------------------------------------------------------------------------
BAD = [
    (dict(r=1.5), "r"),
    (dict(r=-0.1), "r"),
    (dict(wall="compliant", Gamma=0.0), "Gamma"),
    (dict(Omega=0.0), "Omega"),
    (dict(nu=-1.0), "nu"),
    (dict(sigma=float("nan")), "sigma"),
    (dict(u0=float("inf")), "u0"),
    (dict(wall=3), "wall"),
    (dict(wall="rigid", u0=0.1), "u0"),
]


@pytest.mark.parametrize("params,name", BAD, ids=[b[1] + str(i) for i, b in enumerate(BAD)])
def test_bad_parameters_are_rejected_and_the_instance_survives(twin_fmu, c_fmu, params,
                                                              name) -> None:
    """A bad value stops initialisation with the C FMU's message, naming the variable.
    pythonfmu maps any Python exception to fmi2Fatal (it cannot return fmi2Error), and the same
    instance must still run a good case after fmi2Reset, as the harness reuses instances."""
    messages = {}
    for path in (twin_fmu, c_fmu):
        s = Slave(path, logging=True)
        try:
            with pytest.raises(FMICallException) as info:
                s.start(**params)
            assert info.value.status >= 3  # fmi2Error (C) or fmi2Fatal (pythonfmu)
            messages[path] = [m for st, cat, m in s.messages
                              if st >= 3 and cat == "logStatusError"]
            s.start(t0=0.0, sigma=0.5, **FIG9)
            s.step_to(1.0)
            assert np.all(np.isfinite(s.state()))
        finally:
            s.close()
    assert messages[twin_fmu] and messages[twin_fmu][0].split(": ", 1)[1].startswith(name)
    assert messages[twin_fmu][0] == messages[c_fmu][0]


def test_only_sigma_is_tunable_after_initialisation(twin_fmu, c_fmu) -> None:
    """After initialisation sigma may change, a fixed parameter may not: the same message as
    the C FMU's, with fmi2Error (not Fatal), and up to the refusal the same run."""
    messages, states, statuses = {}, {}, {}
    for path in (twin_fmu, c_fmu):
        s = Slave(path, logging=True)
        try:
            s.start(t0=0.0, **FIG9)
            s.step_to(1.0)
            s.set(sigma=0.3)  # tunable: accepted
            s.step_to(2.0)
            states[path] = s.state()
            with pytest.raises(FMICallException) as refused:
                s.set(r=0.5)
            statuses[path] = refused.value.status
            messages[path] = [m for st, _, m in s.messages if st >= 3][:1]
        finally:
            s.close()
    assert "only sigma is tunable" in messages[twin_fmu][0]
    assert messages[twin_fmu] == messages[c_fmu]
    assert statuses[twin_fmu] == statuses[c_fmu] == 3  # fmi2Error
    np.testing.assert_array_equal(states[twin_fmu], states[c_fmu])


def test_exit_guard_against_pythonfmu_use_after_free(twin_fmu: Path, tmp_path: Path) -> None:
    """pythonfmu 0.7's binary writes into freed memory at process exit (see
    ImpactOscillatorPy._guard_pythonfmu_exit; found with valgrind, an abort in about one pytest
    process in twenty).  In a Python importer the twin must register one atexit handler per
    loaded copy of its binary, and the process must exit cleanly."""
    script = f"""
import atexit, sys
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
md = read_model_description({str(twin_fmu)!r})
before = atexit._ncallbacks()
for copy in range(2):  # two extractions: two loaded copies of the binary
    d = extract({str(twin_fmu)!r})
    for _ in range(2):  # two instances of one copy: one handler for that copy
        s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier="ImpactOscillatorPy",
                      instanceName="exit")
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.exitInitializationMode()
        s.doStep(0.0, 1.0)
        s.terminate()
        s.fmi2FreeInstance(s.component)  # the library stays loaded, as in a harness worker
print("guarded", len(sys.modules["ImpactOscillatorPy"]._EXIT_GUARDED),
      "handlers", atexit._ncallbacks() - before)
"""
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    guarded, handlers = (int(x) for x in proc.stdout.split()[1::2])
    assert guarded == 2 and handlers >= 2, proc.stdout


# ---------------------------------------------------------------------------------------------
# a non-Python importer# ---------------------------------------------------------------------------------------------
# a non-Python importer: the runtime needs stated in fmu_src/pytwin/README.md
# ---------------------------------------------------------------------------------------------
_C_IMPORTER = r"""
#include <dlfcn.h>
#include <stdio.h>
#include <stdarg.h>
#include <stdlib.h>
#include "fmi2Functions.h"
static void logger(fmi2ComponentEnvironment e, fmi2String name, fmi2Status s, fmi2String cat,
                   fmi2String msg, ...) {
    va_list ap;
    (void)e; (void)name; (void)cat;
    printf("log %d: ", (int)s);
    va_start(ap, msg);
    vprintf(msg, ap);
    va_end(ap);
    printf("\n");
}
#define LOAD(f) f##TYPE *f = (f##TYPE *)dlsym(h, #f); if (!f) return 2;
int main(int argc, char **argv) {
    (void)argc;
    void *h = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!h) { printf("dlopen: %s\n", dlerror()); return 1; }
    LOAD(fmi2Instantiate) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode) LOAD(fmi2DoStep) LOAD(fmi2GetReal) LOAD(fmi2SetReal)
    LOAD(fmi2GetInteger)
    LOAD(fmi2Terminate) LOAD(fmi2FreeInstance)
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("c", fmi2CoSimulation, argv[2], argv[3], &cb, fmi2False,
                                      fmi2True);
    if (!c) { printf("instantiate failed\n"); return 1; }
    fmi2SetupExperiment(c, fmi2False, 0.0, 0.5, fmi2False, 0.0);
    fmi2EnterInitializationMode(c);
    fmi2ValueReference vr[2] = {6, 7};  /* u0, v0 */
    fmi2Real x[2] = {-2.2, 0.0};
    fmi2SetReal(c, vr, 2, x);
    if (fmi2ExitInitializationMode(c) != fmi2OK) { printf("init failed\n"); return 1; }
    fmi2ValueReference out[2] = {13, 14};  /* u, v */
    fmi2ValueReference imp[1] = {15};  /* impacts */
    fmi2Real y[2];
    fmi2Integer n[1];
    for (int k = 0; k < 10; ++k) {
        if (fmi2DoStep(c, 0.5 + k, 1.0, fmi2True) != fmi2OK) { printf("step failed\n"); return 1; }
        fmi2GetReal(c, out, 2, y);
        fmi2GetInteger(c, imp, 1, n);
        printf("period %.17g %.17g %.17g %d\n", 1.5 + k, y[0], y[1], (int)n[0]);
    }
    fmi2GetReal(c, out, 2, y);
    printf("state %.17g %.17g\n", y[0], y[1]);
    fmi2Terminate(c);
    fmi2FreeInstance(c);
    return 0;
}
"""


def _c_importer(twin_fmu: Path, tmp_path: Path, cc: str) -> tuple[list[str], dict[str, str]]:
    """Compile the C importer and extract the twin: the command line that runs it, and the
    environment the README's old recipe gave a C host (libpython preloaded, PYTHONHOME,
    PYTHONPATH), which the twin no longer needs."""
    import sysconfig

    src, exe = tmp_path / "importer.c", tmp_path / "importer"
    src.write_text(_C_IMPORTER)
    subprocess.run([cc, "-O1", "-I", str(ROOT / "fmu_src" / "include" / "fmi2"), str(src),
                    "-o", str(exe), "-ldl"], check=True, capture_output=True)
    unzipdir = Path(extract(str(twin_fmu), unzipdir=str(tmp_path / "fmu")))
    guid = read_model_description(str(twin_fmu)).guid
    args = [str(exe), str(unzipdir / "binaries" / "linux64" / "ImpactOscillatorPy.so"), guid,
            (unzipdir / "resources").as_uri()]
    libpython = Path(sysconfig.get_config_var("LIBDIR")) / sysconfig.get_config_var("INSTSONAME")
    # PYTHONHOME: the embedded interpreter would otherwise look for its standard library next
    # to whichever "python3" comes first on PATH (here maybe a different installation).
    python_env = {"LD_PRELOAD": str(libpython), "PYTHONPATH": sysconfig.get_paths()["purelib"],
                  "PYTHONHOME": sys.base_prefix}
    return args, python_env


def _cc() -> str:
    import shutil

    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    return cc


def test_c_host_needs_no_python_environment(twin_fmu: Path, tmp_path: Path) -> None:
    """A C program that dlopens the twin, with no LD_PRELOAD, PYTHONHOME or PYTHONPATH and a
    PATH without the project's Python, runs it (the FMU's front loads the libpython and
    site-packages recorded at build time) and computes what fmpy gets in-process; the old
    recipe of the README (preload and both variables) still works."""
    args, python_env = _c_importer(twin_fmu, tmp_path, _cc())
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path)}
    states, outputs = [], []
    for extra in ({}, python_env):
        run = subprocess.run(args, env={**env, **extra}, capture_output=True, text=True,
                             timeout=120)
        assert run.returncode == 0, run.stdout + run.stderr
        assert "log 3" not in run.stdout and "log 4" not in run.stdout
        states.append([float(x) for x in run.stdout.split("state")[1].split()])
        outputs.append(run.stdout)

    s = Slave(twin_fmu)
    try:
        s.start(t0=0.5, u0=-2.2, v0=0.0)
        for k in range(10):  # the same communication points (CVODE stops at each)
            s.step_to(1.5 + k)
        for got in states:
            np.testing.assert_allclose(got, s.state(), rtol=0, atol=1e-12)
    finally:
        s.close()

    # per period against the closed form, at the FMU's default parameters
    start = {v.name: v.start for v in read_model_description(str(twin_fmu)).modelVariables}
    wall = {v: k for k, v in WALLS.items()}[int(start["wall"])]
    osc = ExactOscillator(float(start["nu"]), float(start["Omega"]), float(start["sigma"]),
                          r=float(start["r"]), Gamma=float(start["Gamma"]), wall=wall)
    rows = np.array([[float(x) for x in line.split()[1:]]
                     for line in outputs[0].splitlines() if line.startswith("period ")])
    exact, counts = osc.strobe(-2.2, 0.0, rows[:, 0], 0.5)
    assert counts[-1] > 0  # the run hits the wall
    np.testing.assert_array_equal(rows[:, 3], counts)
    np.testing.assert_allclose(rows[:, 1:3], exact, rtol=0, atol=1e-8)
    print("C driver vs closed form per period: u", np.abs(rows[:, 1] - exact[:, 0]).max(),
          "v", np.abs(rows[:, 2] - exact[:, 1]).max(), "impacts", int(counts[-1]))


@pytest.mark.parametrize(
    "key, value, expect",
    [
        ("libpython", "/nonexistent/libpython3.11.so.1.0", "cannot load the Python library"),
        ("site", "/nonexistent/site-packages", "No module named"),
    ],
)
def test_c_host_missing_python_is_an_fmi_error(twin_fmu: Path, tmp_path: Path, key: str,
                                               value: str, expect: str) -> None:
    """Without the recorded libpython, or without the packages, the C host gets fmi2Error
    (or a NULL instance) with the reason through its logger, and exits normally."""
    args, _ = _c_importer(twin_fmu, tmp_path, _cc())
    record = tmp_path / "fmu" / "resources" / "python_runtime.txt"
    lines = [f"{key}={value}" if line.startswith(key + "=") else line
             for line in record.read_text().splitlines()]
    record.write_text("\n".join(lines) + "\n")
    # no site-packages of the caller's either: an empty user base, no PYTHONPATH
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "PYTHONNOUSERSITE": "1"}
    run = subprocess.run(args, env=env, capture_output=True, text=True, timeout=120)
    assert run.returncode == 1, run.stdout + run.stderr  # refused, not aborted or crashed
    errors = [line for line in run.stdout.splitlines() if line.startswith("log 3: ")]
    assert any(expect in line for line in errors), run.stdout + run.stderr
    assert "log 4" not in run.stdout


@pytest.mark.skipif(os.environ.get("IMPACT_VALGRIND") != "1",
                    reason="about 70 s under valgrind: set IMPACT_VALGRIND=1")
def test_c_importer_exit_has_no_use_after_free(twin_fmu: Path, tmp_path: Path) -> None:
    """pythonfmu 0.7's library destructor reads the freed PyState at exit in a C host too (an
    abort in about one fmusim run in sixty).  The twin registers pythonfmu's
    finalizePythonInterpreter as a C exit handler there (ImpactOscillatorPy
    ._guard_pythonfmu_exit); valgrind must show no invalid access in it.  (Python's own
    teardown under valgrind reports a read in scipy's _uarray module dealloc and the dynamic
    loader's rpath strncmp, both outside pythonfmu; they are not asserted on.)"""
    import shutil

    cc, vg = shutil.which("cc") or shutil.which("gcc"), shutil.which("valgrind")
    if cc is None or vg is None:
        pytest.skip("needs a C compiler and valgrind")
    args, python_env = _c_importer(twin_fmu, tmp_path, cc)
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), **python_env, "PYTHONMALLOC": "malloc"}
    run = subprocess.run([vg, "-q", *args], env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0 and "state" in run.stdout, run.stdout[-2000:] + run.stderr[-2000:]
    blocks = run.stderr.split("==\n")
    bad = [b for b in blocks if "Invalid" in b and "finalizePythonInterpreter" in b]
    assert not bad, bad[0]


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
