"""Runs one action sequence against a loaded FMU binary and checks the oracle.

The oracle: the process does not crash, no sanitizer reports (both are seen by the
parent process, runner.py), and in this process

* ``nonfinite``: no call returns OK (or Warning) with a non-finite value: every getter's result,
  and all variables after every successful doStep, set, state restore and event update;
* ``me-dostep`` / ``cs-me-call``: an instance does not accept the other interface's calls;
* ``not-atomic``: a refused set leaves the variable as it was; a refused state restore leaves all
  variables as they were;
* ``roundtrip``: a state serialised and deserialised restores the very same variables;
* ``fatal``: no call answers fmi2Fatal/fmi3Fatal;
* ``illegal-ok``: no call the standard's state machine does not allow in the instance's state
  (tests/support/fmi_standard.py, followed by tests/fuzz/standard_model.py) is answered OK or Warning;
* ``bricked``: at the end of every sequence, whatever happened, reset + a fresh initialisation +
  one step work and give finite values.

Hand-written regression sequences (tests/fuzz_corpus/) may add expectations: ``"must_pass"`` on
an action (``refused-valid``: a valid call, e.g. a tiny step or valid physics, must not fail) and
``"expect_error"`` on the sequence (``accepted-extreme``: some call must refuse the input).
"""
from __future__ import annotations

import math
import time
from typing import Any

from tests.fuzz.bindings import DISCARD, ERROR, FATAL, OK, WARNING, Fmi2, Fmi3
from tests.fuzz.fmu_states import StateActions
from tests.fuzz.oracle import PASSED, Violation, same_values
from tests.fuzz.sequences import interface_is_me
from tests.fuzz.standard_model import RecordingLibrary, StateModel

__all__ = ["Executor", "Violation"]


class Executor(StateActions):
    """One instance of one interface, driven action by action."""

    def __init__(self, lib: Fmi2 | Fmi3, interface: str) -> None:
        self.lib = lib
        if not isinstance(lib.lib, RecordingLibrary):
            lib.lib = RecordingLibrary(lib.lib)
        self.recorder: RecordingLibrary = lib.lib
        self.model = StateModel(interface)
        self.interface = interface
        self.me = interface_is_me(interface)
        self.calls = 0
        self.slots: list[int | None] = [None, None, None]
        self.slot_values: list[list | None] = [None, None, None]
        self.blobs: dict[str, bytes] = {}
        self.me_time = 0.0
        self.start = 0.0
        self.slowest = (0.0, "")
        self.errors: list[str] = []  # every refused call with the FMU's message, in order
        desc = lib.desc
        self.reals = [v.vr for v in desc.of_kind("real")]
        self.ints = [v.vr for v in desc.of_kind("int")]
        self.bools = [v.vr for v in desc.of_kind("bool")]
        self.time_vr = next((v.vr for v in desc.variables if v.causality == "independent"), None)

    # -- helpers --------------------------------------------------------------------------
    def _instantiate(self, token_ok: bool = True) -> bool:
        self.calls += 1
        return self.lib.instantiate(
            self.me, token_ok=token_ok, event_mode=self.interface == "fmi3cs_event",
            early_return=self.interface in ("fmi3cs_event", "fmi3cs_intermediate"),
            intermediate=self.interface == "fmi3cs_intermediate")

    def _judge(self) -> None:
        """Replays the FMI calls made since the last judgement through the standard's model."""
        def fail(message: str) -> None:
            raise Violation("illegal-ok", message)
        calls, self.recorder.calls = self.recorder.calls, []
        for name, status in calls:
            self.model.feed(name, status, fail)

    def _check(self, fn: str, status: int) -> int:
        self._judge()
        self.calls += 1
        if status == FATAL:
            raise Violation("fatal", f"{fn} returned Fatal: {self.last_message()}")
        if status not in (OK, WARNING, DISCARD, ERROR):
            raise Violation("fatal", f"{fn} returned status {status}")
        if status >= DISCARD:
            self.errors.append(f"{fn}: {self.last_message()}")
        return status

    def last_message(self) -> str:
        return self.lib.messages[-1] if self.lib.messages else "(no message)"

    def snapshot(self) -> list | None:
        """All variables' values, or None where the FMU does not give them now (or the standard
        does not allow reading them: Instantiated)."""
        self._judge()
        if not self.model.getters_allowed():
            return None
        out: list = []
        for kind, vrs in (("real", self.reals), ("int", self.ints), ("bool", self.bools)):
            if not vrs:
                continue
            st, vals = self.lib.get(kind, vrs)
            self._check(f"get {kind}", st)
            if st not in PASSED:
                return None
            if kind == "real":
                bad = [(vr, x) for vr, x in zip(vrs, vals) if not math.isfinite(x)]
                if bad:
                    raise Violation("nonfinite", f"get {kind} OK with {bad}")
            out += vals
        return out

    def now(self) -> float:
        if self.me:
            return self.me_time
        self._judge()
        if not self.model.getters_allowed():
            return 0.0
        if self.time_vr is not None:
            st, vals = self.lib.get("real", [self.time_vr])
            self._check("get time", st)
            return vals[0] if st in PASSED else 0.0
        st, t = self.lib.last_time()
        self._check("last time", st)
        return t if st in PASSED else 0.0

    # -- actions --------------------------------------------------------------------------
    def run(self, actions: list[dict[str, Any]], expect_error: bool = False) -> None:
        """Instantiate, run every action, probe that the instance still works, free it."""
        try:
            if not self._instantiate():
                raise Violation("instantiate", f"valid instantiation refused: {self.last_message()}")
            for a in actions:
                t0 = time.perf_counter()
                self.act(a)
                dt = time.perf_counter() - t0
                if dt > self.slowest[0]:
                    self.slowest = (dt, repr(a))
            self._judge()
            self.final = self.snapshot_quiet()
            if expect_error and not self.errors:
                raise Violation("accepted-extreme", "every call of the sequence returned OK")
            self.probe()
        finally:
            for i, s in enumerate(self.slots):
                if s is not None and self.lib.inst:
                    self.lib.free_state(s)
                    self.slots[i] = None
            self.lib.free()

    def act(self, a: dict[str, Any]) -> None:
        n_err = len(self.errors)
        for _ in range(int(a.get("repeat", 1))):
            self._act(a)
        if a.get("must_pass") and len(self.errors) > n_err:
            raise Violation("refused-valid", f"{a['op']} refused: {self.errors[n_err]}")

    def _act(self, a: dict[str, Any]) -> None:
        op = a["op"]
        L = self.lib
        if op == "instantiate_bad_token":
            other = type(L)(L.desc)
            self.calls += 1
            if other.instantiate(self.me, token_ok=False):
                other.free()
                raise Violation("token", "instantiated with a wrong GUID/token")
        elif op == "foreign":
            self.blobs["foreign"] = self._foreign_state(a["h"])
        elif op == "setup":
            self.start = a["start"]
            self._check("setup", L.setup(a["start"], a["tol"]))
        elif op == "enter_init":
            self.me_time = self.start = a["start"]
            self._check("enter_init", L.enter_init(a["start"], a["tol"]))
        elif op == "exit_init":
            if self._check("exit_init", L.exit_init()) in PASSED:
                self.me_time = self.start
                self.snapshot()
        elif op == "terminate":
            self._check("terminate", L.terminate())
        elif op == "reset":
            self._check("reset", L.reset())
        elif op == "set":
            self._set(a)
        elif op == "set_der":
            self._check("set_der", L.set_input_derivatives(a["vrs"], a["order"], a["values"]))
        elif op == "get_all":
            self.snapshot()
        elif op == "step":
            self._step(a)
        elif op == "last_time":
            st, t = L.last_time()
            if self._check("last_time", st) in PASSED and not math.isfinite(t):
                raise Violation("nonfinite", f"lastSuccessfulTime {t}")
        elif op == "get_state":
            before = self.snapshot_quiet()
            st, p = L.get_state(self.slots[a["slot"]])
            if self._check("get_state", st) in PASSED:
                self.slots[a["slot"]] = p
                self.slot_values[a["slot"]] = before
        elif op == "set_state":
            self._set_state(self.slots[a["slot"]], "set_state")
        elif op == "free_state":
            st, p = L.free_state(self.slots[a["slot"]])
            if self._check("free_state", st) in PASSED:
                self.slots[a["slot"]] = p
        elif op == "roundtrip":
            self._roundtrip(a["slot"])
        elif op == "deser":
            self._deser(a)
        elif op == "update":
            st, _ = L.update_discrete()
            if self._check("update", st) in PASSED:
                self.snapshot()
        elif op == "enter_event":
            self._check("enter_event", L.enter_event_mode())
        elif op == "enter_cont":
            self._me_only("enter_cont", L.enter_cont())
        elif op == "enter_step_mode":
            self._check("enter_step_mode", L.enter_step_mode())
        elif op == "completed":
            self._me_only("completed", L.completed_step())
        elif op == "set_time":
            t = a["t"]
            t = self.me_time + t[1] if isinstance(t, (list, tuple)) else t
            if self._me_only("set_time", L.set_time(t)) in PASSED:
                self.me_time = t
        elif op == "set_x":
            self._me_only("set_x", L.set_states(a["x"]))
        elif op == "me_get":
            self._me_get(a["what"], a.get("n_delta", 0))
        elif op == "integrate":
            self._integrate(a["h"], a["n"])
        else:
            raise ValueError(f"unknown action {op}")

    def snapshot_quiet(self) -> list | None:
        try:
            return self.snapshot()
        except Violation:
            return None

    def _set(self, a: dict[str, Any]) -> None:
        vrs, kind = a["vrs"], a["kind"]
        values = [bool(x) for x in a["values"]] if kind == "bool" else a["values"]
        before = None
        self._judge()
        if len(vrs) == 1 and self.model.getters_allowed():
            st, b = self.lib.get(kind, vrs)
            before = b if self._check("get", st) in PASSED else None
        st = self._check("set", self.lib.set(kind, vrs, values))
        if st in PASSED:
            self.snapshot()
        elif before is not None and self.model.getters_allowed():
            st2, after = self.lib.get(kind, vrs)
            if self._check("get", st2) in PASSED and not same_values(before, after):
                raise Violation("not-atomic", f"refused set {kind} {vrs}={values} changed the "
                                f"value {before} -> {after}")

    def _step(self, a: dict[str, Any]) -> None:
        t = a["t"]
        now = self.now()
        t = now if t == "now" else now * (1 + 1e-12) + 1e-12 if t == "now+eps" else t
        st, last, _ = self.lib.do_step(t, a["h"])
        st = self._check(f"doStep({t!r}, {a['h']!r})", st)
        if st in PASSED:
            if self.me:
                raise Violation("me-dostep", "a Model Exchange instance accepted doStep")
            if last is not None and not math.isfinite(last):
                raise Violation("nonfinite", f"doStep OK with lastSuccessfulTime {last}")
            self.snapshot()

    def _me_only(self, fn: str, status: int) -> int:
        st = self._check(fn, status)
        if st in PASSED and not self.me:
            raise Violation("cs-me-call", f"a Co-Simulation instance accepted {fn}")
        return st

    def _me_get(self, what: str, n_delta: int = 0) -> tuple[int, list[float]]:
        n = (self.lib.desc.n_states if what != "ind" else self.lib.desc.n_indicators) + n_delta
        st, vals = self.lib.me_get(what, max(0, n))
        st = self._me_only(f"me_get {what}", st)
        if st in PASSED and not all(math.isfinite(x) for x in vals):
            raise Violation("nonfinite", f"me_get {what} OK with {vals}")
        return st, vals

    def _integrate(self, h: float, n: int) -> None:
        """A valid Model Exchange importer: explicit Euler with event detection on g0."""
        if not self.me:
            return
        L = self.lib
        st, g = self._me_get("ind")
        if st not in PASSED:
            return
        for _ in range(n):
            st, x = self._me_get("x")
            st2, dx = self._me_get("der")
            if st not in PASSED or st2 not in PASSED:
                return
            t = self.me_time + h
            if self._me_only("set_time", L.set_time(t)) not in PASSED:
                return
            self.me_time = t
            if self._me_only("set_x", L.set_states([xi + h * di for xi, di in zip(x, dx)])) not in PASSED:
                return
            self._me_only("completed", L.completed_step())
            st, g2 = self._me_get("ind")
            if st not in PASSED:
                return
            if any((a > 0) != (b > 0) for a, b in zip(g, g2)):
                self._check("enter_event", L.enter_event_mode())
                st, _ = L.update_discrete()
                self._check("update", st)
                self._check("enter_cont", L.enter_cont())
                st, g2 = self._me_get("ind")
            g = g2
        self.snapshot()

    # -- the end-of-sequence probe ----------------------------------------------------------
    def probe(self) -> None:
        """After anything: reset, initialise with defaults and take one step or evaluation."""
        L = self.lib
        steps = [("reset", L.reset), ("setup", lambda: L.setup(0.0, None)),
                 ("enter_init", lambda: L.enter_init(0.0, None)), ("exit_init", L.exit_init)]
        if self.interface == "fmi3cs_event":
            steps.append(("enter_step_mode", L.enter_step_mode))
        for fn, call in steps:
            if self._check(fn, call()) not in PASSED:
                raise Violation("bricked", f"{fn} after the sequence failed: {self.last_message()}")
        self.me_time = 0.0
        if self.me:
            self._integrate(1e-3, 3)
        else:
            st, _, _ = L.do_step(0.0, 0.1)
            if self._check("doStep(0, 0.1)", st) not in PASSED:
                raise Violation("bricked", f"doStep after reset failed: {self.last_message()}")
        if self.snapshot() is None:
            raise Violation("bricked", "values not readable after reset and initialisation")
