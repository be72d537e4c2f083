"""The version-specific part of driving an FMU: :class:`Fmi2Slave` (fmpy's ``FMU2Slave``) and
:class:`Fmi3Slave` (``FMU3Slave``) share one small interface, and :func:`make_slave` picks one
by the FMU's ``fmiVersion``; another version is one more entry in :data:`SLAVE_CLASSES`.
"""
from __future__ import annotations

import collections
import contextlib
import os
import threading
from typing import Any, Callable, Iterator, Mapping

from ..errors import FmuError, HarnessInputError
from .fmi import BOOLEAN_TYPES, INTEGER_TYPES, REAL_TYPES, SUPPORTED_FMI_VERSIONS, FmuModel, VariableInfo

# ----------------------------------------------------------------------------------------
@contextlib.contextmanager
def _keeping_cwd() -> Iterator[None]:
    """Restore the working directory afterwards: fmpy changes into the binary's folder to load it
    and changes back only when the load succeeds, so a broken binary left the caller's process
    in the (soon deleted) extraction folder, and every relative path after it failed."""
    cwd = os.getcwd()
    try:
        yield
    finally:
        if os.getcwd() != cwd:
            os.chdir(cwd)


class _LogMixin:
    """The FMU's log messages, kept instead of printed, so errors can quote them."""

    messages: collections.deque

    def _log(self, status: int, category: bytes | str, message: bytes | str) -> None:
        def text(x: bytes | str) -> str:
            return x.decode("utf-8", "replace") if isinstance(x, bytes) else str(x)

        self.messages.append((int(status), text(category), text(message)))

    def last_error(self) -> str:
        """The most recent message with status Warning or worse ('' if none)."""
        for status, _, message in reversed(self.messages):
            if status >= 1:
                return message
        return ""


class _SlaveBase(_LogMixin):
    """What the FMI 2 and FMI 3 slaves share: ``self._fmu`` (fmpy's slave) and its release."""

    _fmu: Any
    _needs_reset: bool

    def close(self) -> None:
        try:
            if self._needs_reset:
                self._fmu.terminate()
        except Exception:  # an instance in Error state cannot terminate; free it anyway
            pass
        finally:
            self._fmu.freeInstance()
            release = getattr(getattr(self, "_callbacks", None), "release", None)
            if release is not None:  # FMI 2.0 (fmi2_logging): the handler is not needed now
                release()


def _group_by_type(values: Mapping[VariableInfo, Any]) -> dict[str, tuple[list[int], list[Any]]]:
    """Value references and values per FMI type, so that each type is set in one call."""
    by_type: dict[str, tuple[list[int], list[Any]]] = {}
    for var, value in values.items():
        vrs, vals = by_type.setdefault(var.type, ([], []))
        vrs.append(var.value_reference)
        vals.append(value)
    return by_type


def _bound_getter(fmu: Any, get: Callable[..., Any], vr_type: Any, value_type: Any, variables: list[VariableInfo],
                  counted: bool) -> Callable[[], list]:
    """``() -> list``: fmpy's ``get`` (the checked FMI function) on arrays made once; ``counted``:
    FMI 3.0's extra argument, the number of values."""
    n = len(variables)
    vrs = (vr_type * n)(*[v.value_reference for v in variables])
    out = (value_type * n)()
    extra = (n,) if counted else ()

    def read() -> list:
        get(fmu.component, vrs, n, out, *extra)
        return list(out)

    return read


class Fmi2Slave(_SlaveBase):
    """One FMI 2.0 Co-Simulation instance (fmpy's low-level ``FMU2Slave``).

    The interface (``initialize``, ``reset``, ``set``, ``do_step``, ``getter``,
    ``last_error``, ``close``) is all the simulator uses; :class:`Fmi3Slave` provides the
    same methods.
    """

    def __init__(self, model: FmuModel, unzipdir: str, instance_name: str) -> None:
        from fmpy.fmi2 import FMU2Slave

        from harness.fmu.fmi2_logging import Fmi2Callbacks

        self.messages = collections.deque(maxlen=50)
        with _keeping_cwd():
            self._fmu = FMU2Slave(guid=model.guid, unzipDirectory=unzipdir,
                                  modelIdentifier=model.model_identifier, instanceName=instance_name)
        # Not a ctypes logger of our own: fmpy's proxy keeps one process-wide pointer to it,
        # which dangled once this slave was collected (harness/fmu/fmi2_logging.py).
        self._callbacks = Fmi2Callbacks(  # must outlive the instance; released by close()
            lambda _name, status, category, message: self._log(status, category, message))
        self._fmu.instantiate(callbacks=self._callbacks.functions, loggingOn=False)
        self._needs_reset = False

    def initialize(self, t0: float, values: Mapping[VariableInfo, Any]) -> None:
        """setupExperiment(t0), enter initialization, set ``values``, exit initialization."""
        self._needs_reset = True  # also after a failure part-way: reset is allowed in Error
        self._fmu.setupExperiment(startTime=t0)
        self._fmu.enterInitializationMode()
        self.set(values)
        self._fmu.exitInitializationMode()

    def set(self, values: Mapping[VariableInfo, Any]) -> None:
        """Set variables grouped by type (one FMI call per type)."""
        for typ, (vrs, vals) in _group_by_type(values).items():
            if typ in REAL_TYPES:
                self._fmu.setReal(vrs, [float(x) for x in vals])
            elif typ in INTEGER_TYPES:
                self._fmu.setInteger(vrs, [int(x) for x in vals])
            elif typ in BOOLEAN_TYPES:
                self._fmu.setBoolean(vrs, [bool(x) for x in vals])
            else:  # pragma: no cover - rejected earlier by coerce_value
                raise FmuError(f"cannot set variables of type {typ}")

    def reset(self) -> None:
        """fmi2Reset: back to the instantiated state, instance and library kept."""
        if self._needs_reset:
            self._fmu.reset()
            self._needs_reset = False

    def do_step(self, t: float, h: float) -> None:
        self._fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)

    def getter(self, variables: list[VariableInfo]) -> Callable[[], list]:
        """A function returning the current values of ``variables`` (all of one type family),
        bound once so that the per-period read is a single FMI call: its value references and
        result array are built here, not at every call as fmpy's ``getReal`` builds them (a
        third of a read's cost)."""
        from fmpy.fmi2 import fmi2Boolean, fmi2Integer, fmi2Real, fmi2ValueReference

        family = variables[0].type
        ctype, name = ((fmi2Real, "fmi2GetReal") if family in REAL_TYPES else
                       (fmi2Integer, "fmi2GetInteger") if family in INTEGER_TYPES else
                       (fmi2Boolean, "fmi2GetBoolean"))
        return _bound_getter(self._fmu, getattr(self._fmu, name), fmi2ValueReference, ctype, variables, False)



class Fmi3Slave(_SlaveBase):
    """One FMI 3.0 Co-Simulation instance (fmpy's ``FMU3Slave``), same interface as
    :class:`Fmi2Slave`.

    By default instantiated without event mode and without early return, so ``doStep``
    integrates the whole communication step and handles wall events inside it, as the FMI 2
    build does. With ``record_events`` it asks for event mode and early return: ``doStep``
    then stops at every wall event the FMU locates, the time it reports
    (``lastSuccessfulTime``) is appended to :attr:`event_times`, the jump is applied in event
    mode, and the step goes on to its end.
    """

    def __init__(self, model: FmuModel, unzipdir: str, instance_name: str,
                 record_events: bool = False) -> None:
        from fmpy.fmi3 import FMU3Slave

        self.record_events = bool(record_events)
        self.event_times: list[float] = []
        self.messages = collections.deque(maxlen=50)
        with _keeping_cwd():
            self._fmu = FMU3Slave(guid=model.guid, unzipDirectory=unzipdir,
                                  modelIdentifier=model.model_identifier, instanceName=instance_name)

        def log_message(env: Any, status: int, category: bytes, message: bytes) -> None:
            self._log(status, category, message)

        self._fmu.instantiate(loggingOn=False, eventModeUsed=self.record_events,
                              earlyReturnAllowed=self.record_events, logMessage=log_message)
        self._log_message = log_message  # keep the callback alive
        self._needs_reset = False

    def initialize(self, t0: float, values: Mapping[VariableInfo, Any]) -> None:
        self._needs_reset = True
        self._fmu.enterInitializationMode(startTime=t0)
        self.set(values)
        self._fmu.exitInitializationMode()
        self.event_times = []
        if self.record_events:  # with eventModeUsed the FMU leaves initialization in event mode
            self._settle_events()

    def _settle_events(self) -> None:
        """Event mode: let the FMU apply its jumps until it needs no more, then step mode."""
        for _ in range(1000):
            need_update, terminate, *_ = self._fmu.updateDiscreteStates()
            if terminate:
                raise FmuError("the FMU asked to terminate in event mode")
            if not need_update:
                break
        self._fmu.enterStepMode()

    _SETTERS = {"Float64": "setFloat64", "Float32": "setFloat32", "Int8": "setInt8", "Int16": "setInt16",
                "Int32": "setInt32", "Int64": "setInt64", "UInt8": "setUInt8", "UInt16": "setUInt16",
                "UInt32": "setUInt32", "UInt64": "setUInt64", "Boolean": "setBoolean", "Enumeration": "setInt64"}

    def set(self, values: Mapping[VariableInfo, Any]) -> None:
        for typ, (vrs, vals) in _group_by_type(values).items():
            setter = self._SETTERS.get(typ)
            if setter is None:  # pragma: no cover - rejected earlier by coerce_value
                raise FmuError(f"cannot set variables of type {typ}")
            convert = float if typ in REAL_TYPES else (bool if typ in BOOLEAN_TYPES else int)
            getattr(self._fmu, setter)(vrs, [convert(x) for x in vals])

    def reset(self) -> None:
        if self._needs_reset:
            self._fmu.reset()
            self._needs_reset = False

    def do_step(self, t: float, h: float) -> None:
        target = t + h
        while True:
            need, terminate, early, reached = self._fmu.doStep(currentCommunicationPoint=t, communicationStepSize=target - t)
            if terminate:
                raise FmuError(f"the FMU asked to terminate at t={reached}")
            if self.record_events and (need or early):
                if early:
                    self.event_times.append(float(reached))
                self._fmu.enterEventMode()
                self._settle_events()
            if not early or reached >= target:
                return
            t = reached  # continue the step after the event

    def getter(self, variables: list[VariableInfo]) -> Callable[[], list]:
        """As :meth:`Fmi2Slave.getter` (``fmi3Get<Type>``, arrays bound once)."""
        from fmpy import fmi3

        typ = {"Enumeration": "Int64"}.get(variables[0].type, variables[0].type)
        return _bound_getter(self._fmu, getattr(self._fmu, f"fmi3Get{typ}"), fmi3.fmi3ValueReference,
                             getattr(fmi3, f"fmi3{typ}"), variables, True)



#: Slave class per FMI major version.
SLAVE_CLASSES: dict[str, type] = {"2": Fmi2Slave, "3": Fmi3Slave}
assert tuple(SLAVE_CLASSES) == SUPPORTED_FMI_VERSIONS


_INSTANTIATE_LOCK = threading.Lock()


def make_slave(model: FmuModel, unzipdir: str, instance_name: str,
               record_events: bool = False) -> Fmi2Slave | Fmi3Slave:
    """Instantiate the slave class matching the FMU's ``fmiVersion``.

    ``record_events`` (FMI 3.0 only: event mode and early return) records the time of every
    wall event the FMU reports.

    Serialized: fmpy changes the process's working directory while it loads the library,
    which is not safe with several threads (a Dask worker with ``--nthreads > 1``).
    """
    cls = SLAVE_CLASSES[model.fmi_version.split(".")[0]]
    if record_events and cls is not Fmi3Slave:
        raise HarnessInputError(
            "--fmu", f"recording wall-event times needs an FMI 3.0 FMU with event mode and early "
            f"return; {model.path} is FMI {model.fmi_version}")
    with _INSTANTIATE_LOCK:
        try:
            if record_events:
                return cls(model, unzipdir, instance_name, record_events=True)
            return cls(model, unzipdir, instance_name)
        except Exception as exc:
            # fmpy raises a plain Exception when the shared library cannot be loaded (not an
            # ELF file, wrong architecture, missing symbols) or instantiate returns NULL: a
            # broken FMU is bad input, told in one line naming the file, never a traceback
            reason = " ".join(str(exc).split()) or type(exc).__name__
            if str(unzipdir) in reason:
                reason = reason.replace(str(unzipdir) + os.sep, "")
            raise HarnessInputError(
                "--fmu", f"cannot load the binary of {model.path.name}: {reason}") from None
