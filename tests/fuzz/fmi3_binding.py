"""ctypes binding of the FMU's FMI 3.0 functions (see tests/fuzz/bindings.py)."""
from __future__ import annotations

import ctypes as C

from tests.fuzz.binding_base import ERROR, OK, _D, _DP, _P, _SZ, _UP, _Base, _arr

_B = C.c_bool
_BP = C.POINTER(C.c_bool)
_Fmi3Logger = C.CFUNCTYPE(None, _P, C.c_int, C.c_char_p, C.c_char_p)
_Fmi3Intermediate = C.CFUNCTYPE(None, _P, _D, _B, _B, _B, _B, _BP, _DP)


class Fmi3(_Base):
    """The FMI 3.0 binary (Co-Simulation with event mode/early return, Model Exchange)."""

    version = 3
    _TYPES = {"real": (C.c_double, "Float64"), "int": (C.c_int32, "Int32"), "bool": (C.c_bool, "Boolean")}

    def _declare(self) -> None:
        i, f = C.c_int, self._fn
        f("fmi3InstantiateCoSimulation", _P, C.c_char_p, C.c_char_p, C.c_char_p, _B, _B, _B, _B,
          _UP, _SZ, _P, _Fmi3Logger, _Fmi3Intermediate)
        f("fmi3InstantiateModelExchange", _P, C.c_char_p, C.c_char_p, C.c_char_p, _B, _B, _P,
          _Fmi3Logger)
        f("fmi3FreeInstance", None, _P)
        f("fmi3EnterInitializationMode", i, _P, _B, _D, _D, _B, _D)
        for n in ("ExitInitializationMode", "Terminate", "Reset", "EnterEventMode",
                  "EnterContinuousTimeMode", "EnterStepMode"):
            f("fmi3" + n, i, _P)
        for t, (ct, name) in self._TYPES.items():
            f("fmi3Get" + name, i, _P, _UP, _SZ, C.POINTER(ct), _SZ)
            f("fmi3Set" + name, i, _P, _UP, _SZ, C.POINTER(ct), _SZ)
        f("fmi3GetFMUState", i, _P, C.POINTER(_P))
        f("fmi3SetFMUState", i, _P, _P)
        f("fmi3FreeFMUState", i, _P, C.POINTER(_P))
        f("fmi3SerializedFMUStateSize", i, _P, _P, C.POINTER(_SZ))
        f("fmi3SerializeFMUState", i, _P, _P, C.c_char_p, _SZ)
        f("fmi3DeserializeFMUState", i, _P, C.c_char_p, _SZ, C.POINTER(_P))
        f("fmi3DoStep", i, _P, _D, _D, _B, _BP, _BP, _BP, _DP)
        f("fmi3UpdateDiscreteStates", i, _P, _BP, _BP, _BP, _BP, _BP, _DP)
        f("fmi3CompletedIntegratorStep", i, _P, _B, _BP, _BP)
        f("fmi3SetTime", i, _P, _D)
        f("fmi3SetContinuousStates", i, _P, _DP, _SZ)
        for n in ("GetContinuousStateDerivatives", "GetEventIndicators", "GetContinuousStates",
                  "GetNominalsOfContinuousStates"):
            f("fmi3" + n, i, _P, _DP, _SZ)

        def logger(env, status, category, message):  # noqa: ANN001 (ctypes callback)
            self.log(status, category, message)

        def intermediate(env, t, set_req, get_ok, finished, can_return, early_req, early_t):  # noqa: ANN001
            # ask for an early return at every other event, when allowed (exercises both paths)
            self._n_intermediate += 1
            if can_return and self._n_intermediate % 2 and early_req:
                early_req[0] = True

        self._logger = _Fmi3Logger(logger)
        self._intermediate = _Fmi3Intermediate(intermediate)
        self._keep = (logger, intermediate)
        self._n_intermediate = 0

    # -- life cycle -----------------------------------------------------------------------
    def instantiate(self, me: bool, token_ok: bool = True, event_mode: bool = False,
                    early_return: bool = False, intermediate: bool = False) -> bool:
        token = (self.desc.token if token_ok else "{bad}").encode()
        if me:
            p = self.lib.fmi3InstantiateModelExchange(b"fuzz", token, b"/tmp", False, True, None,
                                                      self._logger)
        else:
            cb = self._intermediate if intermediate else _Fmi3Intermediate()
            p = self.lib.fmi3InstantiateCoSimulation(b"fuzz", token, b"/tmp", False, True,
                                                     event_mode, early_return, None, 0, None,
                                                     self._logger, cb)
        self.inst = p or None
        return self.inst is not None

    def free(self) -> None:
        if self.inst:
            self.lib.fmi3FreeInstance(self.inst)
        self.inst = None

    def setup(self, start: float, tol: float | None) -> int:
        return OK  # FMI 3.0 takes start time and tolerance in fmi3EnterInitializationMode

    def enter_init(self, start: float, tol: float | None) -> int:
        return self.lib.fmi3EnterInitializationMode(self.inst, tol is not None, tol or 0.0, start,
                                                    False, 0.0)

    def exit_init(self) -> int:
        return self.lib.fmi3ExitInitializationMode(self.inst)

    def terminate(self) -> int:
        return self.lib.fmi3Terminate(self.inst)

    def reset(self) -> int:
        return self.lib.fmi3Reset(self.inst)

    # -- values ---------------------------------------------------------------------------
    def get(self, kind: str, vrs: list[int]) -> tuple[int, list]:
        ct, name = self._TYPES[kind]
        out = (ct * max(1, len(vrs)))()
        st = getattr(self.lib, "fmi3Get" + name)(self.inst, _arr(C.c_uint, vrs), len(vrs), out,
                                                  len(vrs))
        return st, list(out)[: len(vrs)]

    def set(self, kind: str, vrs: list[int], values: list) -> int:
        ct, name = self._TYPES[kind]
        return getattr(self.lib, "fmi3Set" + name)(self.inst, _arr(C.c_uint, vrs), len(vrs),
                                                    _arr(ct, values), len(values))

    def set_input_derivatives(self, vrs: list[int], order: int, values: list[float]) -> int:
        return OK  # FMI 3.0 has no input derivatives in Co-Simulation without clocks

    # -- FMU state ------------------------------------------------------------------------
    def get_state(self, into: int | None) -> tuple[int, int | None]:
        p = _P(into)
        st = self.lib.fmi3GetFMUState(self.inst, C.byref(p))
        return st, p.value

    def set_state(self, state: int | None) -> int:
        return self.lib.fmi3SetFMUState(self.inst, state)

    def free_state(self, state: int | None) -> tuple[int, int | None]:
        p = _P(state)
        st = self.lib.fmi3FreeFMUState(self.inst, C.byref(p))
        return st, p.value

    def serialize(self, state: int | None) -> tuple[int, bytes]:
        n = _SZ(0)
        st = self.lib.fmi3SerializedFMUStateSize(self.inst, state, C.byref(n))
        if st != OK:
            return st, b""
        if n.value > 1 << 20:
            return ERROR, b""
        buf = C.create_string_buffer(max(1, n.value))
        st = self.lib.fmi3SerializeFMUState(self.inst, state, buf, n.value)
        return st, buf.raw[: n.value]

    def deserialize(self, data: bytes, into: int | None) -> tuple[int, int | None]:
        p = _P(into)
        st = self.lib.fmi3DeserializeFMUState(self.inst, data, len(data), C.byref(p))
        return st, p.value

    # -- Co-Simulation --------------------------------------------------------------------
    def do_step(self, t: float, h: float) -> tuple[int, float | None, bool]:
        ev, term, early, last = C.c_bool(False), C.c_bool(False), C.c_bool(False), _D(t)
        st = self.lib.fmi3DoStep(self.inst, t, h, True, C.byref(ev), C.byref(term),
                                 C.byref(early), C.byref(last))
        return st, last.value, bool(ev.value)

    def last_time(self) -> tuple[int, float]:
        return ERROR, 0.0

    def enter_step_mode(self) -> int:
        return self.lib.fmi3EnterStepMode(self.inst)

    # -- Model Exchange -------------------------------------------------------------------
    def enter_event_mode(self) -> int:
        return self.lib.fmi3EnterEventMode(self.inst)

    def update_discrete(self) -> tuple[int, bool]:
        b = [C.c_bool(False) for _ in range(5)]
        t = _D(0.0)
        st = self.lib.fmi3UpdateDiscreteStates(self.inst, *[C.byref(x) for x in b], C.byref(t))
        return st, bool(b[3].value)

    def enter_cont(self) -> int:
        return self.lib.fmi3EnterContinuousTimeMode(self.inst)

    def completed_step(self) -> int:
        a, b = C.c_bool(False), C.c_bool(False)
        return self.lib.fmi3CompletedIntegratorStep(self.inst, True, C.byref(a), C.byref(b))

    def set_time(self, t: float) -> int:
        return self.lib.fmi3SetTime(self.inst, t)

    def set_states(self, x: list[float]) -> int:
        return self.lib.fmi3SetContinuousStates(self.inst, _arr(C.c_double, x), len(x))

    def me_get(self, what: str, n: int) -> tuple[int, list[float]]:
        name = {"der": "GetContinuousStateDerivatives", "ind": "GetEventIndicators",
                "x": "GetContinuousStates", "nominal": "GetNominalsOfContinuousStates"}[what]
        out = (C.c_double * max(1, n))()
        st = getattr(self.lib, "fmi3" + name)(self.inst, out, n)
        return st, list(out)[:n]
