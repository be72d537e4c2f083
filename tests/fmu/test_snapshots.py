"""FMU-state snapshots: versioned, tagged with the interface (FMI 2.0/3.0, CS/ME),
checksummed and validated field by field. A bad state is refused with a message and leaves the
instance exactly as it was; nothing non-finite ever comes back with OK.

The serialised layout is the core's Snapshot struct (fmu_snapshot.c): a 16-byte header (magic,
version, interface, size), the FMI state word at byte 16, ..., and a 64-bit FNV-1a checksum of
all preceding bytes in the last 8 bytes. Tests that corrupt a field on purpose re-seal the
checksum (as a careless or hostile importer could) to reach the field-by-field checks.
"""
from __future__ import annotations

from typing import Any

import struct

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model
from fmpy.fmi3 import FMU3Slave

from tests.support.fmu import (FMU3_PATH, FMU_PATH, LoggedSlave, expect_error,
                               refused_and_restored)

UNDERDAMPED = dict(nu=0.196, Omega=7.368)


def fnv1a(data: bytes) -> int:
    h = 1469598103934665603
    for b in data:
        h = ((h ^ b) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return h


def reseal(blob: bytearray) -> bytes:
    """Recompute the trailing checksum after an edit."""
    blob[-8:] = struct.pack("<Q", fnv1a(bytes(blob[:-8])))
    return bytes(blob)


def put_double(blob: bytes, old: float, new: float) -> bytearray:
    """Replace the (unique) occurrence of the double `old` by `new`."""
    b = bytearray(blob)
    pat = struct.pack("<d", old)
    i = bytes(b).find(pat)
    assert i >= 0 and bytes(b).find(pat, i + 1) < 0, "value not unique in the snapshot"
    b[i:i + 8] = struct.pack("<d", new)
    return b


@pytest.fixture
def running():
    """A CS instance mid-run (rigid wall, impacts) and its serialised state."""
    s = LoggedSlave(name="snap")
    s.start(wall=2, sigma=0.1, r=0.8, u0=-0.5, v0=1.0, **UNDERDAMPED)
    s.step_to(2.37)
    st = s.slave.getFMUstate()
    blob = s.slave.serializeFMUstate(st)
    s.slave.freeFMUstate(st)
    yield s, blob
    s.close()


def _refused(s: LoggedSlave, blob: bytes, words: str) -> None:
    """The blob is refused with a message containing `words`, and the instance is unchanged."""
    before = (s.state().tolist(), s.impacts(), s.get("F_contact"))
    # refused with fmi2Error: the instance is then in Error (FMI 2.0.4 2.1.3), its variables
    # as they were, and a state saved before brings it back
    refused_and_restored(s, s.slave.deSerializeFMUstate, blob)
    assert words in s.errors()[-1], s.errors()[-1]
    assert (s.state().tolist(), s.impacts(), s.get("F_contact")) == before
    s.step_to(s.t + 1.0)  # running again
    assert np.all(np.isfinite(s.state()))


def test_round_trip_is_exact(running):
    s, blob = running
    ref = LoggedSlave(name="ref")
    try:
        ref.start(wall=2, sigma=0.1, r=0.8, u0=-0.5, v0=1.0, **UNDERDAMPED)
        ref.step_to(2.37)
        ref.slave.freeFMUstate(ref.slave.getFMUstate())  # a snapshot restarts CVODE here
        ref.step_to(5.0)
        st = s.slave.deSerializeFMUstate(blob)
        s.step_to(4.0)  # move on, then restore
        s.slave.setFMUstate(st)
        s.slave.freeFMUstate(st)
        s.t = 2.37
        s.step_to(5.0)
        assert np.array_equal(s.state(), ref.state()) and s.impacts() == ref.impacts()
    finally:
        ref.close()


def test_every_single_byte_flip_is_refused(running):
    """Without re-sealing, a change anywhere (header, body, checksum) is caught."""
    s, blob = running
    saved = s.slave.getFMUstate()
    for i in range(len(blob)):
        b = bytearray(blob)
        b[i] ^= 0x5A
        expect_error(s.slave.deSerializeFMUstate, bytes(b))  # allowed in Error too
    assert "checksum" in s.errors()[-1] or "state" in s.errors()[-1]
    s.slave.setFMUstate(saved)
    s.slave.freeFMUstate(saved)
    _refused(s, blob[:-1], "bytes are not a serialised state")


def test_nan_in_the_body_is_refused_even_with_a_valid_checksum(running):
    s, blob = running
    u = s.state()[0]
    st = s.slave.getFMUstate()  # the snapshot holds the state of this moment
    blob = s.slave.serializeFMUstate(st)
    s.slave.freeFMUstate(st)
    _refused(s, reseal(put_double(blob, u, float("nan"))), "not finite")
    _refused(s, reseal(put_double(blob, u, 1e300)), "beyond 1e15")


def test_out_of_range_parameters_in_a_state_are_refused(running):
    s, blob = running
    _refused(s, reseal(put_double(blob, 0.1, 1e308)), "sigma")          # sigma
    _refused(s, reseal(put_double(blob, 7.368, 1.8e308)), "Omega")      # Omega
    _refused(s, reseal(put_double(blob, 0.8, 2.0)), "field r")          # r


def test_bad_fmi_state_word_is_refused_and_the_instance_is_not_bricked(running):
    s, blob = running
    # none, two states, Intermediate Update Mode (FMI 3.0 only, never saved), ME's continuous
    # mode, all bits. (Error is a state an FMI 2.0 state can be saved in: fmi2GetFMUstate is
    # allowed there.)
    for word in (0, 3, 1 << 7, 1 << 4, -1):
        b = bytearray(blob)
        b[16:20] = struct.pack("<i", word)
        _refused(s, reseal(b), "FMI state word")
    # reset and free still work, and a good state still restores
    st = s.slave.deSerializeFMUstate(blob)
    s.slave.setFMUstate(st)
    s.slave.freeFMUstate(st)
    s.slave.reset()


def test_version_and_size_are_checked(running):
    s, blob = running
    b = bytearray(blob)
    b[4:8] = struct.pack("<I", 1)
    _refused(s, reseal(b), "version")


def _me_instance(name: str) -> tuple[FMU2Model, list[str], Any]:
    """An instantiated FMI 2 Model Exchange instance of the FMU, its log messages collected, and
    the logger callbacks (release them after freeInstance)."""
    from harness.fmu.fmi2_logging import Fmi2Callbacks

    md = read_model_description(str(FMU_PATH))
    me = FMU2Model(guid=md.guid, unzipDirectory=extract(str(FMU_PATH)),
                   modelIdentifier=md.modelExchange.modelIdentifier, instanceName=name)
    msgs: list[str] = []
    cb = Fmi2Callbacks(lambda _name, _status, _category, text: msgs.append(text))
    me.instantiate(callbacks=cb.functions)
    return me, msgs, cb


def test_a_cs_state_is_refused_by_a_model_exchange_instance(running):
    _, blob = running
    me, msgs, cb = _me_instance("me")
    try:
        me.setupExperiment(startTime=0.0)
        me.enterInitializationMode()
        me.exitInitializationMode()
        own = me.getFMUstate()
        with pytest.raises(Exception):
            me.deSerializeFMUstate(blob)
        assert any("Co-Simulation instance cannot be set into an FMI 2.0 Model Exchange"
                   in m for m in msgs), msgs
        me.setFMUstate(own)  # out of Error (FMI 2.0.4 2.1.3)
        me.freeFMUstate(own)
        # the ME instance's own states round-trip
        st = me.getFMUstate()
        me.setFMUstate(me.deSerializeFMUstate(me.serializeFMUstate(st)))
        me.freeFMUstate(st)
        # and it still does not accept fmi2DoStep-like calls: its event mode is intact
        me.enterContinuousTimeMode()
    finally:
        me.terminate()
        me.freeInstance()
        cb.release()


def test_fmi3_refuses_fmi2_states_and_corrupted_ones(running):
    _, blob2 = running
    md = read_model_description(str(FMU3_PATH))
    s = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(FMU3_PATH)),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="s3")
    s.instantiate()
    try:
        s.enterInitializationMode(startTime=0.0)
        s.exitInitializationMode()
        s.doStep(0.0, 1.0)
        st = s.getFMUState()
        blob = s.serializeFMUState(st)
        s.freeFMUState(st)
        with pytest.raises(Exception):
            s.deserializeFMUState(blob2)  # an FMI 2.0 state
        b = bytearray(blob)
        b[len(b) // 2] ^= 1
        with pytest.raises(Exception):
            s.deserializeFMUState(bytes(b))
        s.setFMUState(s.deserializeFMUState(blob))
        s.doStep(1.0, 1.0)
    finally:
        s.terminate()
        s.freeInstance()


def test_own_states_always_round_trip_after_reset():
    """The fuzzer's F12 family: an instance's own state must always be accepted back, here
    after a run started at a negative time and a reset (the time origins were left apart)."""
    s = LoggedSlave(name="own")
    try:
        s.start(t0=-5.962808076885404)
        s.step_to(-4.5)
        s.slave.reset()
        st = s.slave.getFMUstate()
        back = s.slave.deSerializeFMUstate(s.slave.serializeFMUstate(st))
        s.slave.setFMUstate(back)
        s.slave.freeFMUstate(st)
        s.slave.freeFMUstate(back)
        s.start(t0=2.5)
        s.step_to(3.7)
        st = s.slave.getFMUstate()
        back = s.slave.deSerializeFMUstate(s.slave.serializeFMUstate(st))
        s.slave.setFMUstate(back)
        s.step_to(4.0)
    finally:
        s.close()


# -- the input ramps: F_ext, u_wall with their derivatives and reference time --------
DF, DW = 0.3725, -0.0193  # distinct doubles, so that their place in the state is found


@pytest.fixture
def ramped():
    """A CS instance between two steps with both ramps set (fmi2SetRealInputDerivatives), and
    its serialised state; the offset of dF_ext in it.  ModelData holds F_ext, u_wall, dF_ext,
    du_wall, in_tau in this order (model.h), so in_tau is 16 bytes after dF_ext."""
    s = LoggedSlave(name="ramps")
    s.start(wall=2, sigma=0.1, r=0.8, u0=-0.5, v0=1.0, F_ext=0.5, u_wall=0.1, **UNDERDAMPED)
    s.step_to(2.37)
    s.slave.setRealInputDerivatives([s.vr["F_ext"], s.vr["u_wall"]], [1, 1], [DF, DW])
    st = s.slave.getFMUstate()
    blob = s.slave.serializeFMUstate(st)
    s.slave.freeFMUstate(st)
    at = bytes(blob).find(struct.pack("<d", DF))
    assert at > 0 and struct.unpack_from("<d", blob, at + 8)[0] == DW
    yield s, blob, at
    s.close()


def _with(blob: bytes, offset: int, value: float) -> bytes:
    b = bytearray(blob)
    b[offset:offset + 8] = struct.pack("<d", value)
    return reseal(b)


def test_a_ramped_state_round_trips_and_runs_the_ramps(ramped):
    """The state with ramps restores and the ramps act after it: the run from the restored state
    equals the run that went on (the same instance's computation)."""
    s, blob, _ = ramped
    s.step_to(3.0)
    want = (s.state().tolist(), s.get("F_ext"), s.get("u_wall"))
    assert want[1] == pytest.approx(0.5 + DF * 0.63, rel=1e-12)  # the ramp ran over the step
    st = s.slave.deSerializeFMUstate(blob)
    s.slave.setFMUstate(st)
    s.slave.freeFMUstate(st)
    s.t = 2.37
    s.step_to(3.0)
    assert (s.state().tolist(), s.get("F_ext"), s.get("u_wall")) == want


@pytest.mark.parametrize("field,delta,values", [
    ("dF_ext", 0, [float("nan"), float("inf"), -float("inf"), 1.01e12, -2e12]),
    ("du_wall", 8, [float("nan"), float("inf"), 1.01e6, -3e6]),
    ("in_tau", 16, [float("nan"), -float("inf"), 2.1e9, -5e9]),
])
def test_each_ramp_field_out_of_range_is_refused(ramped, field, delta, values):
    """Each ramp field set non-finite or beyond its bound (the input derivatives' bounds of
    fmi2SetRealInputDerivatives, the time range for in_tau), the checksum resealed: refused,
    the instance unchanged."""
    s, blob, at = ramped
    for x in values:
        _refused(s, _with(blob, at + delta, x), "input derivatives or impact record")


@pytest.mark.parametrize("delta,value", [(8, 1e6), (8, -1e6), (16, -1.9e9), (16, 1.9e9),
                                         (0, 1e12)])
def test_ramps_that_put_the_inputs_out_of_range_are_refused(ramped, delta, value):
    """Each field within its own bound, but together they put u_wall (or F_ext) at the state's
    time far outside its range (a slope of 1e6 from a reference time 2e9 away): refused, as
    setting that value would be."""
    s, blob, at = ramped
    b = bytearray(blob)
    b[at + delta:at + delta + 8] = struct.pack("<d", value)
    if delta != 16:  # a slope alone: move the reference time far away too
        b[at + 16:at + 24] = struct.pack("<d", -1.9e9)
    _refused(s, reseal(b), "at the state's time")


def test_a_model_exchange_state_with_ramps_is_refused():
    """Model Exchange has no input derivatives: its own state with a ramp written in (resealed)
    is refused, and the instance goes on from a good state."""
    vr = {v.name: v.valueReference for v in read_model_description(str(FMU_PATH)).modelVariables}
    me, msgs, cb = _me_instance("me-ramp")
    try:
        me.setupExperiment(startTime=0.0)
        me.enterInitializationMode()
        me.setReal([vr["F_ext"]], [0.4321])
        me.exitInitializationMode()
        own = me.getFMUstate()
        blob = me.serializeFMUstate(own)
        at = bytes(blob).find(struct.pack("<d", 0.4321))
        for delta in (16, 24):  # dF_ext, du_wall (ModelData: F_ext, u_wall, dF_ext, du_wall)
            b = bytearray(blob)
            b[at + delta:at + delta + 8] = struct.pack("<d", 0.01)
            with pytest.raises(Exception):
                me.deSerializeFMUstate(reseal(b))
            assert "input derivatives in a Model Exchange state" in msgs[-1], msgs[-1]
            me.setFMUstate(own)  # out of Error (FMI 2.0.4 2.1.3)
        assert me.getReal([vr["F_ext"]]) == [0.4321]
        me.freeFMUstate(own)
        me.enterContinuousTimeMode()
    finally:
        me.terminate()
        me.freeInstance()
        cb.release()
