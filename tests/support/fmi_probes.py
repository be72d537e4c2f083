"""Every FMI 2.0 / 3.0 function of the C FMU, callable by name with valid arguments.

The conformance suite (tests/fmu/test_fmi_conformance.py) brings an instance into a state of the
standard's state machine (:func:`drive`) and calls one function there (:func:`call`). Arguments
are valid for this FMU (a real output to read, the input F_ext to set, zero-length arrays for
types it has no variables of), so a refusal can only come from the state. Library loading,
callbacks and instantiation are the fuzzer's (tests/fuzz/bindings.py).
"""
from __future__ import annotations

import ctypes as C
import xml.etree.ElementTree as ET
from typing import Callable

from tests.fuzz.bindings import ERROR, OK, Fmi2, Fmi3, _Fmi2EventInfo, _Fmi3Intermediate
from tests.fuzz.model import ROOT, describe

D, SZ, P = C.c_double, C.c_size_t, C.c_void_p
#: Value references by name, from the FMU's modelDescription.xml (generated from fmu_src/variables.py).
_VRS = {sv.get("name"): int(sv.get("valueReference"))
        for sv in ET.parse(ROOT / "fmu_src" / "modelDescription.xml").getroot().iter("ScalarVariable")}
VR_U, VR_IMPACTS, VR_IN_CONTACT, VR_F_EXT = (_VRS[n] for n in ("u", "impacts", "in_contact", "F_ext"))
STEP = 0.01  # a valid communication step from the start time 0


def _vr(*v: int) -> C.Array:
    return (C.c_uint * len(v))(*v)


def _dbl(*x: float) -> C.Array:
    return (D * len(x))(*x)


def _ok(desc_version: int) -> Fmi2 | Fmi3:
    return (Fmi2 if desc_version == 2 else Fmi3)(describe(ROOT / "build" / "fmu", desc_version))


class Instance:
    """One FMU instance for one conformance case: its binding, pointer and a saved FMU state."""

    def __init__(self, interface: str, binding: Fmi2 | None = None,
                 set_real_vr: int = VR_F_EXT) -> None:
        self.interface = interface
        self.version = 2 if interface.startswith("fmi2") else 3
        self.b = binding or _ok(self.version)
        self.set_real_vr = set_real_vr  # a Real settable in every state that allows setting
        self.lib = self.b.lib
        self.probe_in_update: Callable[[], int | None] | None = None
        self.update_status: int | None = None
        self.update_calls = 0
        if self.version == 3:
            self._install_intermediate()
        me = interface.endswith("-me")
        ok = self.b.instantiate(me, event_mode=interface == "fmi3-cs-event",
                                intermediate=True)
        assert ok, f"{interface}: instantiation failed: {self.b.messages}"
        self.p = self.b.inst
        self.snapshot = P()
        st = getattr(self.lib, f"fmi{self.version}Get{'FMUstate' if self.version == 2 else 'FMUState'}")(
            P(self.p), C.byref(self.snapshot))
        if st != OK:
            self.snapshot = P()  # an FMU without FMU states: the state probes get NULL

    def _install_intermediate(self) -> None:
        def intermediate(env, t, set_req, get_ok, finished, can_return, early_req, early_t):  # noqa: ANN001
            self.update_calls += 1
            if self.update_calls == 1 and self.probe_in_update is not None:
                self.update_status = self.probe_in_update()

        self.b._intermediate = _Fmi3Intermediate(intermediate)
        self.b._keep = (self.b._keep, intermediate)

    def messages(self) -> list[str]:
        return list(self.b.messages)

    def free(self) -> None:
        if self.p:
            getattr(self.lib, f"fmi{self.version}FreeInstance")(P(self.p))
        self.p = None
        self.b.inst = None


def _fmi2_calls(x: Instance, p: P) -> dict[str, Callable[[], int | None]]:
    L, s = x.lib, x.snapshot
    i1, i2, d1, d2 = C.c_int(0), C.c_int(0), D(0.0), _dbl(0.0, 0.0)
    size = SZ(0)
    L.fmi2SerializedFMUstateSize(P(x.p), s, C.byref(size))  # before any state change
    blob = (C.c_char * max(1, size.value))()
    L.fmi2SerializeFMUstate(P(x.p), s, blob, size)
    info = _Fmi2EventInfo()
    null = P()
    c: dict[str, Callable[[], int | None]] = {
        "fmi2SetDebugLogging": lambda: L.fmi2SetDebugLogging(p, 0, SZ(0), None),
        "fmi2SetupExperiment": lambda: L.fmi2SetupExperiment(p, 0, D(0), D(0), 0, D(0)),
        "fmi2EnterInitializationMode": lambda: L.fmi2EnterInitializationMode(p),
        "fmi2ExitInitializationMode": lambda: L.fmi2ExitInitializationMode(p),
        "fmi2Terminate": lambda: L.fmi2Terminate(p),
        "fmi2Reset": lambda: L.fmi2Reset(p),
        "fmi2FreeInstance": lambda: L.fmi2FreeInstance(p),
        "fmi2GetReal": lambda: L.fmi2GetReal(p, _vr(VR_U), SZ(1), _dbl(0.0)),
        "fmi2GetInteger": lambda: L.fmi2GetInteger(p, _vr(VR_IMPACTS), SZ(1), C.byref(i1)),
        "fmi2GetBoolean": lambda: L.fmi2GetBoolean(p, _vr(VR_IN_CONTACT), SZ(1), C.byref(i1)),
        "fmi2GetString": lambda: L.fmi2GetString(p, None, SZ(0), None),
        "fmi2SetReal": lambda: L.fmi2SetReal(p, _vr(x.set_real_vr), SZ(1), _dbl(0.0)),
        "fmi2SetInteger": lambda: L.fmi2SetInteger(p, None, SZ(0), None),
        "fmi2SetBoolean": lambda: L.fmi2SetBoolean(p, None, SZ(0), None),
        "fmi2SetString": lambda: L.fmi2SetString(p, None, SZ(0), None),
        "fmi2GetFMUstate": lambda: L.fmi2GetFMUstate(p, C.byref(P())),
        "fmi2SetFMUstate": lambda: L.fmi2SetFMUstate(p, s),
        "fmi2FreeFMUstate": lambda: L.fmi2FreeFMUstate(p, C.byref(null)),
        "fmi2SerializedFMUstateSize": lambda: L.fmi2SerializedFMUstateSize(p, s, C.byref(size)),
        "fmi2SerializeFMUstate": lambda: L.fmi2SerializeFMUstate(p, s, blob, size),
        "fmi2DeSerializeFMUstate": lambda: L.fmi2DeSerializeFMUstate(p, blob, size,
                                                                     C.byref(P())),
        "fmi2GetDirectionalDerivative": lambda: L.fmi2GetDirectionalDerivative(
            p, None, SZ(0), None, SZ(0), None, None),
        "fmi2SetRealInputDerivatives": lambda: L.fmi2SetRealInputDerivatives(
            p, _vr(VR_F_EXT), SZ(1), C.byref(C.c_int(1)), _dbl(0.0)),
        "fmi2GetRealOutputDerivatives": lambda: L.fmi2GetRealOutputDerivatives(
            p, None, SZ(0), None, None),
        "fmi2DoStep": lambda: L.fmi2DoStep(p, D(0.0), D(STEP), 1),
        "fmi2CancelStep": lambda: L.fmi2CancelStep(p),
        "fmi2GetStatus": lambda: L.fmi2GetStatus(p, 0, C.byref(i1)),
        "fmi2GetRealStatus": lambda: L.fmi2GetRealStatus(p, 2, C.byref(d1)),
        "fmi2GetIntegerStatus": lambda: L.fmi2GetIntegerStatus(p, 0, C.byref(i1)),
        "fmi2GetBooleanStatus": lambda: L.fmi2GetBooleanStatus(p, 0, C.byref(i1)),
        "fmi2GetStringStatus": lambda: L.fmi2GetStringStatus(p, 0, C.byref(C.c_char_p())),
        "fmi2EnterEventMode": lambda: L.fmi2EnterEventMode(p),
        "fmi2NewDiscreteStates": lambda: L.fmi2NewDiscreteStates(p, C.byref(info)),
        "fmi2EnterContinuousTimeMode": lambda: L.fmi2EnterContinuousTimeMode(p),
        "fmi2CompletedIntegratorStep": lambda: L.fmi2CompletedIntegratorStep(
            p, 1, C.byref(i1), C.byref(i2)),
        "fmi2SetTime": lambda: L.fmi2SetTime(p, D(0.0)),
        "fmi2SetContinuousStates": lambda: L.fmi2SetContinuousStates(p, _dbl(-0.5, 0.0), SZ(2)),
        "fmi2GetDerivatives": lambda: L.fmi2GetDerivatives(p, d2, SZ(2)),
        "fmi2GetEventIndicators": lambda: L.fmi2GetEventIndicators(p, _dbl(0.0), SZ(1)),
        "fmi2GetContinuousStates": lambda: L.fmi2GetContinuousStates(p, d2, SZ(2)),
        "fmi2GetNominalsOfContinuousStates": lambda: L.fmi2GetNominalsOfContinuousStates(
            p, d2, SZ(2)),
    }
    return c


TYPES3 = ("Float32", "Float64", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64",
          "UInt64", "Boolean", "String", "Binary")


def _fmi3_calls(x: Instance, p: P) -> dict[str, Callable[[], int | None]]:
    L, s = x.lib, x.snapshot
    b = [C.c_bool(False) for _ in range(6)]
    d1, d2, n = D(0.0), _dbl(0.0, 0.0), SZ(0)
    size = SZ(0)
    L.fmi3SerializedFMUStateSize(P(x.p), s, C.byref(size))
    blob = (C.c_char * max(1, size.value))()
    L.fmi3SerializeFMUState(P(x.p), s, blob, size)
    null = P()
    c: dict[str, Callable[[], int | None]] = {
        "fmi3SetDebugLogging": lambda: L.fmi3SetDebugLogging(p, False, SZ(0), None),
        "fmi3EnterInitializationMode": lambda: L.fmi3EnterInitializationMode(
            p, False, D(0), D(0), False, D(0)),
        "fmi3ExitInitializationMode": lambda: L.fmi3ExitInitializationMode(p),
        "fmi3EnterEventMode": lambda: L.fmi3EnterEventMode(p),
        "fmi3Terminate": lambda: L.fmi3Terminate(p),
        "fmi3Reset": lambda: L.fmi3Reset(p),
        "fmi3FreeInstance": lambda: L.fmi3FreeInstance(p),
        "fmi3GetFMUState": lambda: L.fmi3GetFMUState(p, C.byref(P())),
        "fmi3SetFMUState": lambda: L.fmi3SetFMUState(p, s),
        "fmi3FreeFMUState": lambda: L.fmi3FreeFMUState(p, C.byref(null)),
        "fmi3SerializedFMUStateSize": lambda: L.fmi3SerializedFMUStateSize(p, s, C.byref(size)),
        "fmi3SerializeFMUState": lambda: L.fmi3SerializeFMUState(p, s, blob, size),
        "fmi3DeserializeFMUState": lambda: L.fmi3DeserializeFMUState(p, blob, size,
                                                                     C.byref(P())),
        "fmi3GetNumberOfVariableDependencies": lambda: L.fmi3GetNumberOfVariableDependencies(
            p, C.c_uint(VR_U), C.byref(n)),
        "fmi3GetVariableDependencies": lambda: L.fmi3GetVariableDependencies(
            p, C.c_uint(VR_U), None, None, None, None, SZ(0)),
        "fmi3GetDirectionalDerivative": lambda: L.fmi3GetDirectionalDerivative(
            p, None, SZ(0), None, SZ(0), None, SZ(0), None, SZ(0)),
        "fmi3GetAdjointDerivative": lambda: L.fmi3GetAdjointDerivative(
            p, None, SZ(0), None, SZ(0), None, SZ(0), None, SZ(0)),
        "fmi3EnterConfigurationMode": lambda: L.fmi3EnterConfigurationMode(p),
        "fmi3ExitConfigurationMode": lambda: L.fmi3ExitConfigurationMode(p),
        "fmi3EvaluateDiscreteStates": lambda: L.fmi3EvaluateDiscreteStates(p),
        "fmi3UpdateDiscreteStates": lambda: L.fmi3UpdateDiscreteStates(
            p, *[C.byref(v) for v in b[:5]], C.byref(d1)),
        "fmi3ActivateModelPartition": lambda: L.fmi3ActivateModelPartition(p, C.c_uint(0), D(0)),
        "fmi3EnterContinuousTimeMode": lambda: L.fmi3EnterContinuousTimeMode(p),
        "fmi3CompletedIntegratorStep": lambda: L.fmi3CompletedIntegratorStep(
            p, True, C.byref(b[0]), C.byref(b[1])),
        "fmi3SetTime": lambda: L.fmi3SetTime(p, D(0.0)),
        "fmi3SetContinuousStates": lambda: L.fmi3SetContinuousStates(p, _dbl(-0.5, 0.0), SZ(2)),
        "fmi3GetContinuousStateDerivatives": lambda: L.fmi3GetContinuousStateDerivatives(
            p, d2, SZ(2)),
        "fmi3GetEventIndicators": lambda: L.fmi3GetEventIndicators(p, _dbl(0.0), SZ(1)),
        "fmi3GetContinuousStates": lambda: L.fmi3GetContinuousStates(p, d2, SZ(2)),
        "fmi3GetNominalsOfContinuousStates": lambda: L.fmi3GetNominalsOfContinuousStates(
            p, d2, SZ(2)),
        "fmi3GetNumberOfEventIndicators": lambda: L.fmi3GetNumberOfEventIndicators(
            p, C.byref(n)),
        "fmi3GetNumberOfContinuousStates": lambda: L.fmi3GetNumberOfContinuousStates(
            p, C.byref(n)),
        "fmi3EnterStepMode": lambda: L.fmi3EnterStepMode(p),
        "fmi3GetOutputDerivatives": lambda: L.fmi3GetOutputDerivatives(
            p, None, SZ(0), None, None, SZ(0)),
        "fmi3DoStep": lambda: L.fmi3DoStep(p, D(0.0), D(STEP), True,
                                           *[C.byref(v) for v in b[:3]], C.byref(d1)),
    }
    return {**c, **_fmi3_variable_calls(L, p)}


def _fmi3_variable_calls(L: C.CDLL, p: P) -> dict[str, Callable[[], int | None]]:
    """The FMI 3.0 clock functions and the getters and setters of every type, bound to ``p``:
    empty arrays (the FMU has no clocks), one real variable of each direction for Float64."""
    c: dict[str, Callable[[], int | None]] = {}
    # clock functions (the FMU has no clocks: zero-length arrays), by their number of arrays
    for name, arrays in (("GetClock", 1), ("SetClock", 1), ("GetIntervalDecimal", 2),
                         ("GetIntervalFraction", 3), ("GetShiftDecimal", 1),
                         ("GetShiftFraction", 2), ("SetIntervalDecimal", 1),
                         ("SetIntervalFraction", 2), ("SetShiftDecimal", 1),
                         ("SetShiftFraction", 2)):
        f = getattr(L, "fmi3" + name)
        c["fmi3" + name] = (lambda f=f, k=arrays: f(p, None, SZ(0), *([None] * k)))
    for t in TYPES3:
        if t == "Binary":
            c["fmi3GetBinary"] = lambda: L.fmi3GetBinary(p, None, SZ(0), None, None, SZ(0))
            c["fmi3SetBinary"] = lambda: L.fmi3SetBinary(p, None, SZ(0), None, None, SZ(0))
            continue
        get, set_ = getattr(L, "fmi3Get" + t), getattr(L, "fmi3Set" + t)
        c["fmi3Get" + t] = (lambda g=get: g(p, None, SZ(0), None, SZ(0)))
        c["fmi3Set" + t] = (lambda s_=set_: s_(p, None, SZ(0), None, SZ(0)))
    c["fmi3GetFloat64"] = lambda: L.fmi3GetFloat64(p, _vr(VR_U), SZ(1), _dbl(0.0), SZ(1))
    c["fmi3SetFloat64"] = lambda: L.fmi3SetFloat64(p, _vr(VR_F_EXT), SZ(1), _dbl(0.0), SZ(1))
    c["fmi3GetInt32"] = lambda: L.fmi3GetInt32(p, _vr(VR_IMPACTS), SZ(1),
                                               (C.c_int32 * 1)(), SZ(1))
    c["fmi3GetBoolean"] = lambda: L.fmi3GetBoolean(p, _vr(VR_IN_CONTACT), SZ(1),
                                                   (C.c_bool * 1)(), SZ(1))
    return c


def calls(x: Instance, null: bool = False) -> dict[str, Callable[[], int | None]]:
    """Every FMI function of the instance's version, bound to it (or to NULL)."""
    p = P(None if null else x.p)
    return (_fmi2_calls if x.version == 2 else _fmi3_calls)(x, p)


def _seq(x: Instance, *names: str) -> None:
    c = calls(x)
    for n in names:
        st = c[n]()
        assert st == OK, f"{x.interface}: {n} returned {st} on the way: {x.messages()[-3:]}"


def _to_error(x: Instance) -> None:
    """FMI 2.0 Error: a call refused for its arguments (a negative step / a NaN time)."""
    L, p = x.lib, P(x.p)
    st = (L.fmi2SetTime(p, D(float("nan"))) if x.interface == "fmi2-me"
          else L.fmi2DoStep(p, D(0.0), D(-1.0), 1))
    assert st == ERROR


# the way from Instantiated to each state, per interface
PATHS: dict[str, dict[str, tuple]] = {
    "fmi2-cs": {"Instantiated": (), "Init": ("fmi2SetupExperiment", "fmi2EnterInitializationMode"),
                "Step": ("fmi2SetupExperiment", "fmi2EnterInitializationMode",
                         "fmi2ExitInitializationMode"),
                "Terminated": ("fmi2SetupExperiment", "fmi2EnterInitializationMode",
                               "fmi2ExitInitializationMode", "fmi2Terminate"),
                "Error": ("fmi2SetupExperiment", "fmi2EnterInitializationMode",
                          "fmi2ExitInitializationMode", _to_error)},
    "fmi2-me": {"Instantiated": (), "Init": ("fmi2SetupExperiment", "fmi2EnterInitializationMode"),
                "Event": ("fmi2SetupExperiment", "fmi2EnterInitializationMode",
                          "fmi2ExitInitializationMode"),
                "Continuous": ("fmi2SetupExperiment", "fmi2EnterInitializationMode",
                               "fmi2ExitInitializationMode", "fmi2EnterContinuousTimeMode"),
                "Terminated": ("fmi2SetupExperiment", "fmi2EnterInitializationMode",
                               "fmi2ExitInitializationMode", "fmi2Terminate"),
                "Error": ("fmi2SetupExperiment", "fmi2EnterInitializationMode",
                          "fmi2ExitInitializationMode", "fmi2EnterContinuousTimeMode",
                          _to_error)},
}
_I3 = ("fmi3EnterInitializationMode",)
_R3 = _I3 + ("fmi3ExitInitializationMode",)
_U3 = _I3 + (lambda x: prepare_update(x), "fmi3ExitInitializationMode")
PATHS["fmi3-cs"] = {"Instantiated": (), "Init": _I3, "Step": _R3,
                    "Terminated": _R3 + ("fmi3Terminate",), "Update": _U3}
PATHS["fmi3-cs-event"] = {"Instantiated": (), "Init": _I3, "Event": _R3,
                          "Step": _R3 + ("fmi3EnterStepMode",),
                          "Terminated": _R3 + ("fmi3Terminate",),
                          "Update": _U3 + ("fmi3EnterStepMode",)}
PATHS["fmi3-me"] = {"Instantiated": (), "Init": _I3, "Event": _R3,
                    "Continuous": _R3 + ("fmi3EnterContinuousTimeMode",),
                    "Terminated": _R3 + ("fmi3Terminate",)}


def drive(x: Instance, state: str) -> None:
    """Brings a fresh instance into `state` along the standard's ordinary path."""
    for step in PATHS[x.interface][state]:
        if callable(step):
            step(x)
        else:
            _seq(x, step)


def call_in_update(x: Instance, name: str) -> tuple[int | None, int]:
    """Calls `name` from inside intermediateUpdate (FMI 3.0 Co-Simulation).

    Returns the call's status and the enclosing fmi3DoStep's status. The step (5 periods from a
    start on the wall-free orbit, rigid wall) meets the wall, so the callback is reached.
    """
    L, p = x.lib, P(x.p)
    probe = calls(x)[name]
    x.probe_in_update = probe
    b = [C.c_bool(False) for _ in range(3)]
    st = L.fmi3DoStep(p, D(0.0), D(5.0), True, *[C.byref(v) for v in b], C.byref(D(0.0)))
    assert x.update_calls >= 1, "intermediateUpdate was never called: no wall event in the step"
    return x.update_status, st


def prepare_update(x: Instance) -> None:
    """Parameters for :func:`call_in_update`: a rigid wall the default start state reaches."""
    vr = {"wall": 5, "u0": 6, "v0": 7}
    L, p = x.lib, P(x.p)
    assert L.fmi3SetInt32(p, _vr(vr["wall"]), SZ(1), (C.c_int32 * 1)(2), SZ(1)) == OK
    assert L.fmi3SetFloat64(p, _vr(vr["u0"], vr["v0"]), SZ(2), _dbl(-0.5, 3.0), SZ(2)) == OK
