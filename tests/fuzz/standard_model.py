"""The standard's state machine as the fuzzer's oracle.

Every FMI call the executor makes goes through :class:`RecordingLibrary`, which records the
function's name and status. :class:`StateModel` replays them against tests/support/fmi_standard.py (the
table written from the standards' text): a call the standard does not allow in the modelled
state that the FMU answers OK or Warning is a finding (``illegal-ok``). The model then follows
the standard's transitions: any Error puts the instance in the error state (FMI 2.0: Error; FMI
3.0: Terminated); ``SetFMUState`` makes the state unknown until the next Reset (the model does
not track which state a snapshot holds), and unknown states are not judged.
"""
from __future__ import annotations

from typing import Any, Callable

from tests.support import fmi_standard as std

OK, WARNING, ERROR = 0, 1, 3

# the fuzzer's interface names -> the standard table's
INTERFACE = {"fmi2cs": "fmi2-cs", "fmi2me": "fmi2-me", "fmi3cs": "fmi3-cs",
             "fmi3cs_event": "fmi3-cs-event", "fmi3cs_intermediate": "fmi3-cs",
             "fmi3me": "fmi3-me"}


class RecordingLibrary:
    """A ctypes library whose fmi* calls are recorded as (name, status) in `calls`."""

    def __init__(self, lib: Any) -> None:
        self._lib = lib
        self.calls: list[tuple[str, Any]] = []

    def __getattr__(self, name: str) -> Any:
        f = getattr(self._lib, name)
        if not name.startswith("fmi") or not callable(f):
            return f

        def recorded(*args: Any) -> Any:
            st = f(*args)
            self.calls.append((name, st))
            return st
        return recorded


class StateModel:
    """The standard's state of one instance, fed with the calls it received."""

    def __init__(self, interface: str) -> None:
        self.interface = INTERFACE[interface]
        self.state: str | None = "Instantiated"
        self.judged = 0

    def allows(self, function: str) -> bool | None:
        """Whether the standard allows `function` now (None: state unknown, or not in table)."""
        if self.state is None:
            return None
        try:
            return self.state in std.allowed(self.interface, function)
        except KeyError:
            return None

    def getters_allowed(self) -> bool:
        """Whether reading variables is allowed now (unknown: yes, the FMU will tell)."""
        f = "fmi2GetReal" if self.interface.startswith("fmi2") else "fmi3GetFloat64"
        return self.allows(f) is not False

    def feed(self, name: str, status: int, fail: Callable[[str], None]) -> None:
        """One call and its status: judge it, then move to the standard's next state."""
        if name.endswith("FreeInstance") or name.startswith(("fmi2Instantiate",
                                                             "fmi3Instantiate")):
            return
        allowed = self.allows(name)
        if allowed is False and status in (OK, WARNING):
            fail(f"{name} answered {'OK' if status == OK else 'Warning'} in {self.state}, "
                 f"where the standard does not allow it ({self.interface})")
        if allowed is not None:
            self.judged += 1
        if status == ERROR:
            self.state = std.error_state(self.interface)
            return
        if status not in (OK, WARNING):
            self.state = None  # Discard/Pending: states this model does not follow
            return
        if name.endswith("Reset"):
            self.state = "Instantiated"
        elif self.state is None:
            return
        elif name.endswith("EnterInitializationMode"):
            self.state = "Init"
        elif name.endswith("ExitInitializationMode"):
            event = self.interface in ("fmi2-me", "fmi3-me", "fmi3-cs-event")
            self.state = "Event" if event else "Step"
        elif name.endswith("Terminate"):
            self.state = "Terminated"
        elif name.endswith("EnterEventMode"):
            self.state = "Event"
        elif name.endswith("EnterContinuousTimeMode"):
            self.state = "Continuous"
        elif name.endswith("EnterStepMode"):
            self.state = "Step"
        elif name in ("fmi2SetFMUstate", "fmi3SetFMUState"):
            self.state = None
