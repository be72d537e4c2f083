"""ctypes binding of the FMU's FMI 2.0 functions (see tests/fuzz/bindings.py)."""
from __future__ import annotations

import ctypes as C
from typing import Any

from tests.fuzz.binding_base import ERROR, OK, _D, _DP, _P, _SZ, _UP, _Base, _arr, _libc

# fmi2CallbackLogger is variadic; this FMU always calls it with the format "%s" and one string,
# which on the SysV x86-64 and AArch64 ABIs arrives in the register of a sixth named argument.
_Fmi2Logger = C.CFUNCTYPE(None, _P, C.c_char_p, C.c_int, C.c_char_p, C.c_char_p, C.c_char_p)
_Fmi2Alloc = C.CFUNCTYPE(_P, _SZ, _SZ)
_Fmi2Free = C.CFUNCTYPE(None, _P)


class _Fmi2Callbacks(C.Structure):
    _fields_ = [("logger", _Fmi2Logger), ("allocateMemory", _Fmi2Alloc),
                ("freeMemory", _Fmi2Free), ("stepFinished", _P), ("componentEnvironment", _P)]


class _Fmi2EventInfo(C.Structure):
    _fields_ = [("newDiscreteStatesNeeded", C.c_int), ("terminateSimulation", C.c_int),
                ("nominalsOfContinuousStatesChanged", C.c_int),
                ("valuesOfContinuousStatesChanged", C.c_int), ("nextEventTimeDefined", C.c_int),
                ("nextEventTime", C.c_double)]


class Fmi2(_Base):
    """The FMI 2.0 binary (Co-Simulation and Model Exchange in one library)."""

    version = 2
    _TYPES = {"real": (C.c_double, "Real"), "int": (C.c_int, "Integer"), "bool": (C.c_int, "Boolean")}

    def _declare(self) -> None:
        i, f = C.c_int, self._fn
        f("fmi2Instantiate", _P, C.c_char_p, i, C.c_char_p, C.c_char_p,
          C.POINTER(_Fmi2Callbacks), i, i)
        f("fmi2FreeInstance", None, _P)
        f("fmi2SetupExperiment", i, _P, i, _D, _D, i, _D)
        for n in ("EnterInitializationMode", "ExitInitializationMode", "Terminate", "Reset",
                  "EnterEventMode", "EnterContinuousTimeMode", "CancelStep"):
            f("fmi2" + n, i, _P)
        for t, (ct, name) in self._TYPES.items():
            f("fmi2Get" + name, i, _P, _UP, _SZ, C.POINTER(ct))
            f("fmi2Set" + name, i, _P, _UP, _SZ, C.POINTER(ct))
        f("fmi2GetFMUstate", i, _P, C.POINTER(_P))
        f("fmi2SetFMUstate", i, _P, _P)
        f("fmi2FreeFMUstate", i, _P, C.POINTER(_P))
        f("fmi2SerializedFMUstateSize", i, _P, _P, C.POINTER(_SZ))
        f("fmi2SerializeFMUstate", i, _P, _P, C.c_char_p, _SZ)
        f("fmi2DeSerializeFMUstate", i, _P, C.c_char_p, _SZ, C.POINTER(_P))
        f("fmi2DoStep", i, _P, _D, _D, i)
        f("fmi2GetRealStatus", i, _P, i, _DP)
        f("fmi2SetRealInputDerivatives", i, _P, _UP, _SZ, C.POINTER(i), _DP)
        f("fmi2GetRealOutputDerivatives", i, _P, _UP, _SZ, C.POINTER(i), _DP)
        f("fmi2NewDiscreteStates", i, _P, C.POINTER(_Fmi2EventInfo))
        f("fmi2CompletedIntegratorStep", i, _P, i, C.POINTER(i), C.POINTER(i))
        f("fmi2SetTime", i, _P, _D)
        f("fmi2SetContinuousStates", i, _P, _DP, _SZ)
        for n in ("GetDerivatives", "GetEventIndicators", "GetContinuousStates",
                  "GetNominalsOfContinuousStates"):
            f("fmi2" + n, i, _P, _DP, _SZ)

        def logger(env, name, status, category, fmt, arg):  # noqa: ANN001 (ctypes callback)
            self.log(status, category, arg if fmt == b"%s" else fmt)

        self._cb = _Fmi2Callbacks(_Fmi2Logger(logger), _Fmi2Alloc(_libc.calloc),
                                  _Fmi2Free(_libc.free), None, None)
        self._keep = logger

    # -- life cycle -----------------------------------------------------------------------
    def instantiate(self, me: bool, token_ok: bool = True, **_: Any) -> bool:
        token = self.desc.token if token_ok else "{bad}"
        p = self.lib.fmi2Instantiate(b"fuzz", 0 if me else 1, token.encode(), b"file:///tmp",
                                     C.byref(self._cb), 0, 1)
        self.inst = p or None
        return self.inst is not None

    def free(self) -> None:
        if self.inst:
            self.lib.fmi2FreeInstance(self.inst)
        self.inst = None

    def setup(self, start: float, tol: float | None) -> int:
        return self.lib.fmi2SetupExperiment(self.inst, tol is not None, tol or 0.0, start, 0, 0.0)

    def enter_init(self, start: float, tol: float | None) -> int:
        return self.lib.fmi2EnterInitializationMode(self.inst)

    def exit_init(self) -> int:
        return self.lib.fmi2ExitInitializationMode(self.inst)

    def terminate(self) -> int:
        return self.lib.fmi2Terminate(self.inst)

    def reset(self) -> int:
        return self.lib.fmi2Reset(self.inst)

    # -- values ---------------------------------------------------------------------------
    def get(self, kind: str, vrs: list[int]) -> tuple[int, list]:
        ct, name = self._TYPES[kind]
        out = (ct * max(1, len(vrs)))()
        st = getattr(self.lib, "fmi2Get" + name)(self.inst, _arr(C.c_uint, vrs), len(vrs), out)
        return st, list(out)[: len(vrs)]

    def set(self, kind: str, vrs: list[int], values: list) -> int:
        ct, name = self._TYPES[kind]
        return getattr(self.lib, "fmi2Set" + name)(self.inst, _arr(C.c_uint, vrs), len(vrs),
                                                    _arr(ct, values))

    def set_input_derivatives(self, vrs: list[int], order: int, values: list[float]) -> int:
        return self.lib.fmi2SetRealInputDerivatives(
            self.inst, _arr(C.c_uint, vrs), len(vrs), _arr(C.c_int, [order] * len(vrs)),
            _arr(C.c_double, values))

    # -- FMU state ------------------------------------------------------------------------
    def get_state(self, into: int | None) -> tuple[int, int | None]:
        p = _P(into)
        st = self.lib.fmi2GetFMUstate(self.inst, C.byref(p))
        return st, p.value

    def set_state(self, state: int | None) -> int:
        return self.lib.fmi2SetFMUstate(self.inst, state)

    def free_state(self, state: int | None) -> tuple[int, int | None]:
        p = _P(state)
        st = self.lib.fmi2FreeFMUstate(self.inst, C.byref(p))
        return st, p.value

    def serialize(self, state: int | None) -> tuple[int, bytes]:
        n = _SZ(0)
        st = self.lib.fmi2SerializedFMUstateSize(self.inst, state, C.byref(n))
        if st != OK:
            return st, b""
        if n.value > 1 << 20:
            return ERROR, b""
        buf = C.create_string_buffer(max(1, n.value))
        st = self.lib.fmi2SerializeFMUstate(self.inst, state, buf, n.value)
        return st, buf.raw[: n.value]

    def deserialize(self, data: bytes, into: int | None) -> tuple[int, int | None]:
        p = _P(into)
        st = self.lib.fmi2DeSerializeFMUstate(self.inst, data, len(data), C.byref(p))
        return st, p.value

    # -- Co-Simulation --------------------------------------------------------------------
    def do_step(self, t: float, h: float) -> tuple[int, float | None, bool]:
        st = self.lib.fmi2DoStep(self.inst, t, h, 1)
        return st, None, False

    def last_time(self) -> tuple[int, float]:
        x = _D(0.0)
        st = self.lib.fmi2GetRealStatus(self.inst, 2, C.byref(x))  # fmi2LastSuccessfulTime
        return st, x.value

    def enter_step_mode(self) -> int:
        return self.lib.fmi2CancelStep(self.inst)  # FMI 2.0 has no step mode: a harmless call

    # -- Model Exchange -------------------------------------------------------------------
    def enter_event_mode(self) -> int:
        return self.lib.fmi2EnterEventMode(self.inst)

    def update_discrete(self) -> tuple[int, bool]:
        info = _Fmi2EventInfo()
        st = self.lib.fmi2NewDiscreteStates(self.inst, C.byref(info))
        return st, bool(info.valuesOfContinuousStatesChanged)

    def enter_cont(self) -> int:
        return self.lib.fmi2EnterContinuousTimeMode(self.inst)

    def completed_step(self) -> int:
        a, b = C.c_int(0), C.c_int(0)
        return self.lib.fmi2CompletedIntegratorStep(self.inst, 1, C.byref(a), C.byref(b))

    def set_time(self, t: float) -> int:
        return self.lib.fmi2SetTime(self.inst, t)

    def set_states(self, x: list[float]) -> int:
        return self.lib.fmi2SetContinuousStates(self.inst, _arr(C.c_double, x), len(x))

    def me_get(self, what: str, n: int) -> tuple[int, list[float]]:
        name = {"der": "GetDerivatives", "ind": "GetEventIndicators", "x": "GetContinuousStates",
                "nominal": "GetNominalsOfContinuousStates"}[what]
        out = (C.c_double * max(1, n))()
        st = getattr(self.lib, "fmi2" + name)(self.inst, out, n)
        return st, list(out)[:n]
