"""The FMI 3.0 FMU (build/fmu/ImpactOscillator_fmi3.fmu): packaging, capability flags, early
return at every wall event with event mode (impact times against the closed-form oracle), and
agreement of FMI 2.0 CS, FMI 3.0 CS (with and without event mode) and Model Exchange."""
from __future__ import annotations

import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

from mapcheck.exact import ExactOscillator
from tests.support.fmu import FMU3_PATH, FMU_PATH, WALLS, at_times, on_orbit, simulate

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)
UNDERDAMPED = dict(nu=0.196, Omega=7.368)
T0 = 0.5


def test_fmpy_validate_reports_no_problem_on_both_fmus():
    assert validate_fmu(str(FMU3_PATH)) == []
    assert validate_fmu(str(FMU_PATH)) == []


def test_capability_flags():
    import xml.etree.ElementTree as ET
    md = read_model_description(str(FMU3_PATH))
    assert md.fmiVersion == "3.0"
    with zipfile.ZipFile(FMU3_PATH) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    cs = root.find("CoSimulation").attrib
    for flag in ("hasEventMode", "mightReturnEarlyFromDoStep", "providesIntermediateUpdate",
                 "canReturnEarlyAfterIntermediateUpdate", "canGetAndSetFMUState",
                 "canSerializeFMUState", "canHandleVariableCommunicationStepSize"):
        assert cs.get(flag) == "true", flag
    me = root.find("ModelExchange").attrib
    assert me["canGetAndSetFMUState"] == "true" and me["canSerializeFMUState"] == "true"
    assert md.modelExchange is not None
    md2 = read_model_description(str(FMU_PATH))
    assert md.guid == md2.guid  # one model, one token
    v3 = {v.name: v.valueReference for v in md.modelVariables}
    v2 = {v.name: v.valueReference for v in md2.modelVariables}
    assert all(v3[k] == v2[k] for k in v2)


def test_binary_is_separate_static_and_exports_fmi3_only(tmp_path):
    with zipfile.ZipFile(FMU3_PATH) as z:
        z.extract("binaries/x86_64-linux/ImpactOscillator.so", tmp_path)
    so = tmp_path / "binaries/x86_64-linux/ImpactOscillator.so"
    assert "sundials" not in subprocess.run(["ldd", str(so)], capture_output=True, text=True,
                                            check=True).stdout.lower()
    exported = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True,
                              text=True, check=True).stdout.split()
    assert "fmi3DoStep" in exported and "fmi3UpdateDiscreteStates" in exported
    assert not [s for s in exported if s.startswith(("fmi2", "CVode", "N_V", "SUN"))]


def event_rows(res) -> np.ndarray:
    """Times at which fmpy recorded two rows (before and after the event handling)."""
    t = res["time"]
    return t[1:][np.diff(t) == 0.0]


CASES = [
    ("compliant", 0.5, FIG9, 10.0, 10),
    ("compliant", 0.2, FIG9, 10.0, 10),
    ("rigid", 0.3, FIG9, 10.0, 10),
    ("compliant", 0.05, UNDERDAMPED, 1000.0, 5),
]


@pytest.mark.parametrize("wall,sigma,lin,Gamma,n", CASES)
def test_early_return_impact_times_match_the_oracle(wall, sigma, lin, Gamma, n):
    start = dict(wall=wall, sigma=sigma, Gamma=Gamma, **on_orbit(sigma, T0), **lin)
    res = simulate(FMU3_PATH, "CoSimulation", T0, T0 + n, 1.0, use_event_mode=True,
                   early_return_allowed=True, **start)
    got = event_rows(res)
    osc = ExactOscillator(lin["nu"], lin["Omega"], sigma, Gamma=Gamma, wall=wall)
    want = np.array([t for t, kind in osc.crossings(start["u0"], start["v0"], T0, T0 + n)
                     if kind in ("enter", "exit", "impact")])
    assert len(want) >= 1 and len(got) == len(want), (len(got), len(want))
    err = np.abs(got - want).max()
    print(f"{wall} sigma={sigma}: {len(got)} wall events, max |t_FMU - t_oracle| = {err:.2e}")
    assert err < 1e-9
    # the rows after each entry carry the new impact count; in_contact flips at each event
    k = res["impacts"]
    assert k[-1] == sum(1 for t, kind in osc.crossings(start["u0"], start["v0"], T0, T0 + n)
                        if kind in ("enter", "impact"))


@pytest.mark.parametrize("wall,sigma,lin,Gamma,n", CASES)
def test_fmi2_cs_fmi3_cs_and_me_agree_on_stroboscopic_states(wall, sigma, lin, Gamma, n):
    start = dict(wall=wall, sigma=sigma, Gamma=Gamma, **on_orbit(sigma, T0), **lin)
    times = T0 + np.arange(n + 1, dtype=float)
    runs = {
        "fmi2 cs": simulate(FMU_PATH, "CoSimulation", T0, times[-1], 1.0, **start),
        "fmi3 cs": simulate(FMU3_PATH, "CoSimulation", T0, times[-1], 1.0, **start),
        "fmi3 cs events": simulate(FMU3_PATH, "CoSimulation", T0, times[-1], 1.0,
                                   use_event_mode=True, early_return_allowed=True, **start),
        "fmi2 me": simulate(FMU_PATH, "ModelExchange", T0, times[-1], 1.0, **start),
        "fmi3 me": simulate(FMU3_PATH, "ModelExchange", T0, times[-1], 1.0, **start),
    }
    x = {k: at_times(r, times) for k, r in runs.items()}
    ref, k_ref = x["fmi2 cs"]
    exact, counts = osc_strobe(wall, sigma, lin, Gamma, start, times)
    assert list(k_ref) == list(counts)
    # the same CVODE path: FMI 3.0 CS without event mode is the FMI 2.0 FMU, bit for bit
    assert np.array_equal(x["fmi3 cs"][0], ref)
    assert np.abs(x["fmi3 cs events"][0] - ref).max() < 1e-10
    scale = max(1.0, np.abs(exact).max())
    for k in ("fmi2 me", "fmi3 me"):
        assert np.abs(x[k][0] - ref).max() < 2e-6 * scale, k  # fmpy's CVODE at rtol 1e-10
    for k, (_, kk) in x.items():
        assert list(kk) == list(counts), k


def osc_strobe(wall, sigma, lin, Gamma, start, times):
    osc = ExactOscillator(lin["nu"], lin["Omega"], sigma, Gamma=Gamma, wall=wall)
    return osc.strobe(start["u0"], start["v0"], times, t0=T0)


def make_slave(**kw):
    md = read_model_description(str(FMU3_PATH))
    s = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(FMU3_PATH)),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="fmi3")
    s.instantiate(**kw)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    return s, vr


def start_slave(s, vr, sigma=0.5, **extra):
    s.enterInitializationMode(startTime=T0)
    st = dict(sigma=sigma, **on_orbit(sigma, T0), **FIG9)
    s.setFloat64([vr[k] for k in st], list(st.values()))
    for k, x in extra.items():
        s.setInt32([vr[k]], [WALLS.get(x, x) if isinstance(x, str) else x])
    s.exitInitializationMode()


def test_without_event_mode_doStep_never_returns_early():
    s, vr = make_slave(eventModeUsed=False, earlyReturnAllowed=True)
    try:
        start_slave(s, vr)
        t = T0
        for _ in range(3):
            need, term, early, last = s.doStep(t, 1.0)
            assert not need and not term and not early and last == t + 1.0
            t += 1.0
        assert s.getInt32([vr["impacts"]])[0] >= 2
    finally:
        s.terminate()
        s.freeInstance()


def test_early_return_protocol_pre_and_post_event_states():
    """With event mode: doStep stops at the entry with the pre-jump state (u = 0, v = v_c);
    fmi3UpdateDiscreteStates applies v -> r v; the next doStep continues from there."""
    s, vr = make_slave(eventModeUsed=True, earlyReturnAllowed=True)
    try:
        start_slave(s, vr)
        s.updateDiscreteStates()
        s.enterStepMode()
        need, term, early, last = s.doStep(T0, 1.0)
        assert need and early and T0 < last < T0 + 1.0
        u, v = s.getFloat64([vr["u"], vr["v"]])
        assert abs(u) < 1e-9 and v > 0 and s.getInt32([vr["impacts"]])[0] == 0
        s.enterEventMode()
        _, _, _, changed, _, _ = s.updateDiscreteStates()
        assert changed
        u2, v2 = s.getFloat64([vr["u"], vr["v"]])
        assert v2 == pytest.approx(0.9 * v, rel=1e-14) and s.getInt32([vr["impacts"]])[0] == 1
        s.enterStepMode()
        need, term, early, last2 = s.doStep(last, T0 + 1.0 - last)
        assert need and early and last < last2 < T0 + 1.0  # the exit
    finally:
        s.terminate()
        s.freeInstance()


def test_intermediate_update_is_called_at_each_event_and_can_request_early_return():
    calls = []

    def cb(env, t, set_req, get_ok, finished, can_return, early_req, early_time):
        calls.append(t)
        if len(calls) == 2:
            early_req[0] = True
            early_time[0] = t

    s, vr = make_slave(eventModeUsed=False, earlyReturnAllowed=True, intermediateUpdate=cb)
    try:
        start_slave(s, vr)
        need, term, early, last = s.doStep(T0, 3.0)
        assert early and not need and len(calls) == 2 and last == calls[1]
        assert not s.getBoolean([vr["in_contact"]])[0]  # the exit, applied (no event mode)
    finally:
        s.terminate()
        s.freeInstance()


def test_fmu_state_round_trip_in_fmi3():
    s, vr = make_slave()
    try:
        start_slave(s, vr)
        s.doStep(T0, 1.0)
        st = s.getFMUState()
        blob = s.serializeFMUState(st)
        s.doStep(T0 + 1.0, 2.0)
        a = s.getFloat64([vr["u"], vr["v"]])
        s.setFMUState(s.deserializeFMUState(blob))
        s.doStep(T0 + 1.0, 2.0)
        assert s.getFloat64([vr["u"], vr["v"]]) == a
        s.freeFMUState(st)
    finally:
        s.terminate()
        s.freeInstance()
