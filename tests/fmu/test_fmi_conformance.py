"""State-machine conformance of the C FMU, every (state, function) pair.

For each interface (FMI 2.0 CS, FMI 2.0 ME, FMI 3.0 CS without and with eventModeUsed, FMI 3.0
ME), each state of its state machine and each function of its version, a fresh instance of the
real built FMU is driven into the state and the function called once with valid arguments. The
reference is tests/support/fmi_standard.py, written from the standards' text (not from fmu_states.c):

* allowed there: the call is not refused for its state (no "not allowed in" in the log; OK or
  Warning, except for the functions this FMU does not provide, which fail for that reason);
* not allowed: fmi2Error/fmi3Error, and the instance is then in the standard's error state
  (FMI 2.0: Error; FMI 3.0: Terminated), seen from outside: a getter works there, Terminate is
  refused.

FMI 3.0 Co-Simulation also has Intermediate Update Mode: the call is made from inside the
intermediateUpdate callback; nothing is allowed there (no variable declares intermediateUpdate),
so each call must fail and the enclosing fmi3DoStep with it. Every function also gets a NULL
instance (Error, no crash). The number of cases per interface is printed (pytest -s) and
checked against the table's size.
"""
from __future__ import annotations

import ctypes as C

import pytest

from tests.support import fmi_standard as std
from tests.support.fmi_probes import Instance, call_in_update, calls, drive
from tests.fuzz.bindings import ERROR, OK, WARNING

INTERFACES = ("fmi2-cs", "fmi2-me", "fmi3-cs", "fmi3-cs-event", "fmi3-me")

# Functions this FMU does not provide (no asynchronous step, no structural parameters, no
# dependency information): where allowed they fail, but not for the state. The directional and
# adjoint derivatives are provided: where allowed they must succeed.
NOT_PROVIDED = {
    "fmi2GetRealOutputDerivatives", "fmi2CancelStep",
    "fmi2GetStatus", "fmi2GetIntegerStatus", "fmi2GetBooleanStatus", "fmi2GetStringStatus",
    "fmi3EnterConfigurationMode",
    "fmi3GetNumberOfVariableDependencies", "fmi3GetVariableDependencies",
    "fmi3GetOutputDerivatives",
}


def _functions(interface: str) -> list[str]:
    return sorted(std.FMI2 if interface.startswith("fmi2") else std.FMI3)


def _cases() -> list[tuple[str, str, str]]:
    return [(i, s, f) for i in INTERFACES for s in std.STATES[i] for f in _functions(i)]


CASES = _cases()


def _in_error_state(x: Instance) -> tuple[bool, str]:
    """Whether the instance behaves as in the standard's error state: a getter is answered,
    Terminate (allowed in every running state, not in Error/Terminated) is refused."""
    c = calls(x)
    getter = c["fmi2GetReal" if x.version == 2 else "fmi3GetFloat64"]()
    term = c["fmi2Terminate" if x.version == 2 else "fmi3Terminate"]()
    return getter == OK and term == ERROR, f"getter {getter}, terminate {term}"


def _state_refusal(x: Instance, before: int) -> bool:
    return any("not allowed in" in m for m in x.messages()[before:])


@pytest.mark.parametrize("interface,state,function", CASES,
                         ids=[f"{i}-{s}-{f}" for i, s, f in CASES])
def test_state_machine(interface: str, state: str, function: str) -> None:
    x = Instance(interface)
    try:
        drive(x, state)
        before = len(x.messages())
        allowed = state in std.allowed(interface, function)
        if state == "Update":
            status, step = call_in_update(x, function)
            assert not allowed  # the standard allows nothing here for this FMU
            if function.endswith("FreeInstance"):
                status = ERROR  # void: refused means not freed, the step fails below
            assert status == ERROR, f"{function} inside intermediateUpdate returned {status}"
            assert step == ERROR, "the enclosing fmi3DoStep must fail with the call inside it"
        else:
            status = calls(x)[function]()
            if function.endswith("FreeInstance"):
                if allowed:
                    x.p = None  # freed
                    return
                status = ERROR
            if allowed:
                assert not _state_refusal(x, before), x.messages()[before:]
                if function not in NOT_PROVIDED:
                    assert status in (OK, WARNING), (status, x.messages()[before:])
                return
            assert status == ERROR, f"{function} in {state} returned {status}"
            assert _state_refusal(x, before), x.messages()[before:]
        ok, why = _in_error_state(x)
        assert ok, f"after the refused {function} the instance is not in " \
                   f"{std.error_state(interface)}: {why}"
    finally:
        x.free()


@pytest.mark.parametrize("interface", ("fmi2-cs", "fmi3-cs"))
def test_null_instance_is_an_error_for_every_function(interface: str) -> None:
    """Every function, fmi2EnterEventMode and fmi3EnterEventMode included,
    answers Error (FreeInstance: returns) for a NULL instance."""
    x = Instance(interface)
    try:
        for name, f in calls(x, null=True).items():
            st = f()  # FreeInstance is void: returning at all is the test
            assert name.endswith("FreeInstance") or st == ERROR, (name, st)
    finally:
        x.free()


def test_case_counts(capsys: pytest.CaptureFixture) -> None:
    """The suite covers every (state, function) pair of the standard table, per interface."""
    counts = {i: sum(1 for c in CASES if c[0] == i) for i in INTERFACES}
    for i in INTERFACES:
        assert counts[i] == len(std.STATES[i]) * len(_functions(i))
    with capsys.disabled():
        print("\nconformance cases per interface:", counts, "total", sum(counts.values()))


def test_the_fmu_table_agrees_with_the_standard_table() -> None:
    """Both directions: every function of the standard table is exported by the binaries (the
    conformance cases call them all), and every exported fmi function is in the table."""
    for version, table in ((2, std.FMI2), (3, std.FMI3)):
        x = Instance("fmi2-cs" if version == 2 else "fmi3-cs")
        try:
            assert set(calls(x)) == set(table)
            for name in table:
                assert hasattr(x.lib, name), name
        finally:
            x.free()


def test_fmi3_nested_do_step_fails_the_outer_one() -> None:
    """A nested fmi3DoStep inside intermediateUpdate once left the instance in Error
    while the outer one returned OK."""
    x = Instance("fmi3-cs")
    try:
        drive(x, "Update")
        status, step = call_in_update(x, "fmi3DoStep")
        assert (status, step) == (ERROR, ERROR)
        assert x.lib.fmi3GetFloat64(C.c_void_p(x.p), (C.c_uint * 1)(13), C.c_size_t(1),
                                    (C.c_double * 1)(), C.c_size_t(1)) == OK
    finally:
        x.free()


@pytest.mark.parametrize("interface", ("fmi2-cs", "fmi3-cs"))
def test_debug_logging_categories_are_checked(interface: str) -> None:
    """SetDebugLogging(n = 3, categories = NULL) returned OK. Now n > 0 with a NULL
    array, or a category not in the modelDescription's LogCategories, is an error; the declared
    ones are accepted."""
    fn = "fmi2SetDebugLogging" if interface == "fmi2-cs" else "fmi3SetDebugLogging"
    for categories, expected in ((None, ERROR), ([b"logEvents", b"logStatusWarning"], OK),
                                 ([b"logEverything"], ERROR)):
        x = Instance(interface)
        try:
            n = 3 if categories is None else len(categories)
            arr = None if categories is None else (C.c_char_p * n)(*categories)
            st = getattr(x.lib, fn)(C.c_void_p(x.p), 1, C.c_size_t(n), arr)
            assert st == expected, (categories, st, x.messages()[-1:])
        finally:
            x.free()


@pytest.mark.parametrize("interface,state,expected", [
    ("fmi2-me", "Continuous", ERROR), ("fmi2-me", "Event", OK),
    ("fmi3-me", "Continuous", ERROR), ("fmi3-me", "Event", OK)])
def test_tunable_parameter_only_in_event_mode_for_model_exchange(interface: str, state: str,
                                                                 expected: int) -> None:
    """FMI 2.0 Continuous-Time Mode accepted SetReal(sigma). There only continuous
    inputs may be set (FMI 2.0.4 3.2.3, FMI 3.0 3.2); a tunable parameter changes in Event
    Mode."""
    x = Instance(interface)
    try:
        drive(x, state)
        p, vr, val = C.c_void_p(x.p), (C.c_uint * 1)(2), (C.c_double * 1)(0.3)
        st = (x.lib.fmi2SetReal(p, vr, C.c_size_t(1), val) if interface == "fmi2-me"
              else x.lib.fmi3SetFloat64(p, vr, C.c_size_t(1), val, C.c_size_t(1)))
        assert st == expected, x.messages()[-1:]
    finally:
        x.free()
