"""FMI layer: read and check an FMU, and drive one reusable Co-Simulation instance.

The rest of the harness talks to a *simulator* (:class:`harness.simulator.Simulator`),
never to fmpy directly.  This module is the only place that knows about fmpy and FMI:

* :class:`FmuModel` reads the modelDescription once (in the process that plans a run),
  checks that the FMU is Co-Simulation and has the oscillator's variables, and maps
  variable names to value references and types.  Nothing is hard-coded: the value
  references come from the modelDescription.
* :class:`FmuSource` is the small, picklable handle (path + sha256 + optionally the bytes)
  that travels to worker processes and Dask workers.
* :class:`FmuSimulator` owns *one* slave instance and reuses it between runs with
  ``reset`` (instantiating is far more expensive than resetting).
* :func:`make_slave` picks the slave class from the FMU's ``fmiVersion``:
  :class:`Fmi2Slave` (fmpy's ``FMU2Slave``) or :class:`Fmi3Slave` (``FMU3Slave``), which
  share one small interface; another version is one more entry in :data:`SLAVE_CLASSES`.
"""
from __future__ import annotations

import collections
import hashlib
import os
import threading
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

from .errors import FmuError, HarnessInputError

#: Names of the oscillator's variables.  They are the interface between the harness and
#: any FMU it drives (the C FMU, its Python twin, an FMI 3.0 build).
STATE_OUTPUTS = ("u", "v")
IMPACT_COUNTER = "impacts"
INITIAL_STATE = ("u0", "v0")
REQUIRED_VARIABLES = (*STATE_OUTPUTS, IMPACT_COUNTER, *INITIAL_STATE)

#: Symbolic values accepted for the Integer parameter ``wall``.
WALL_NAMES = {"none": 0, "compliant": 1, "rigid": 2}

#: The FMU's derivatives of its last ``doStep`` (issue 11): a Boolean parameter switches the
#: variational equations on, six outputs give d(u, v)_end/d(u, v)_start (J_uv = du/dv_start)
#: and d(u, v)_end/d sigma.  An FMU that has all of them gets exact map Jacobians; one
#: without falls back to finite differences (feature detection by name, no version check).
SENSITIVITY_SWITCH = "sensitivities"
SENSITIVITY_OUTPUTS = ("J_uu", "J_uv", "J_vu", "J_vv", "S_u", "S_v")

#: Integer parameter choosing the FMU's integrator, and the names the CLI accepts for it.
SOLVER_PARAMETER = "solver"
SOLVER_NAMES = {"cvode": 0, "closed-form": 1}

_SETTABLE_CAUSALITIES = {"parameter", "input"}

#: FMI 2 and FMI 3 type names, by family.
REAL_TYPES = {"Real", "Float64", "Float32"}
INTEGER_TYPES = {"Integer", "Enumeration", "Int8", "Int16", "Int32", "Int64", "UInt8", "UInt16", "UInt32", "UInt64"}
BOOLEAN_TYPES = {"Boolean"}


def sha256_of(path: str | os.PathLike) -> str:
    """Return the hex sha256 of a file (used to identify the exact FMU of a result)."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def check_archive(path: str | os.PathLike, argument: str = "--fmu") -> None:
    """Read every member of the FMU's zip archive once (CRC checked; ~1 ms for this FMU).

    A damaged archive (a bit flipped in the binary) is bad input found here, in one line,
    rather than as a ``BadZipFile`` traceback when a worker extracts it.
    """
    try:
        with zipfile.ZipFile(path) as archive:
            bad = archive.testzip()
    except (zipfile.BadZipFile, zlib.error, OSError, EOFError, RuntimeError,
            NotImplementedError) as exc:  # zlib.error: a flip inside the deflate stream
        raise HarnessInputError(argument, f"{str(path)!r} is a damaged FMU archive: {exc}") from None
    if bad is not None:
        raise HarnessInputError(argument, f"{str(path)!r} is a damaged FMU archive: bad CRC-32 for {bad!r}")


@dataclass(frozen=True)
class VariableInfo:
    """What the harness needs to know about one FMU variable."""

    name: str
    value_reference: int
    type: str  # "Real", "Integer", "Boolean", ...
    causality: str
    variability: str
    start: Any = None

    @property
    def settable(self) -> bool:
        """True when the harness may set it before a run (parameters and inputs)."""
        return self.causality in _SETTABLE_CAUSALITIES and self.variability != "constant"

    @property
    def tunable(self) -> bool:
        """True when it may change between communication points, the state carried on."""
        return self.causality == "input" or (
            self.causality == "parameter" and self.variability == "tunable"
        )


class FmuModel:
    """Static description of a Co-Simulation FMU, checked for use by the harness.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.fmu`` file.
    argument : str
        How the caller names this argument in error messages (``"--fmu"`` in the CLI).

    Raises
    ------
    HarnessInputError
        If the file is missing, is not an FMU, is not Co-Simulation, has an FMI version
        the harness cannot drive, or lacks one of :data:`REQUIRED_VARIABLES`.
    """

    def __init__(self, path: str | os.PathLike, argument: str = "fmu") -> None:
        from fmpy import read_model_description

        self.argument = argument
        self.path = Path(path).expanduser().resolve()
        if not self.path.is_file():
            what = "is a directory, not an FMU file" if self.path.is_dir() else "no such file"
            raise HarnessInputError(argument, f"{what}: {str(path)!r}" if what == "no such file"
                                    else f"{str(path)!r} {what}")
        if not zipfile.is_zipfile(self.path):
            raise HarnessInputError(argument, f"{str(path)!r} is not an FMU (not a zip archive)")
        check_archive(self.path, argument)
        try:
            md = read_model_description(str(self.path), validate=False)
        except Exception as exc:  # fmpy raises plain Exceptions with useful text
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise HarnessInputError(argument, f"{str(path)!r} is not a valid FMU: {reason}") from None
        self.description = md
        self.fmi_version: str = md.fmiVersion
        if md.coSimulation is None:
            raise HarnessInputError(
                argument,
                f"{self.path.name} is not a Co-Simulation FMU (it only provides Model Exchange); "
                "the harness needs fmiModelDescription/CoSimulation",
            )
        major = self.fmi_version.split(".")[0]
        if major not in SLAVE_CLASSES:
            raise HarnessInputError(
                argument,
                f"{self.path.name} is an FMI {self.fmi_version} FMU; supported: "
                + ", ".join(f"FMI {v}.x" for v in sorted(SLAVE_CLASSES)),
            )
        self.model_identifier: str = md.coSimulation.modelIdentifier
        self.guid: str = md.guid
        self.variables: dict[str, VariableInfo] = {
            v.name: VariableInfo(
                name=v.name,
                value_reference=int(v.valueReference),
                type=v.type,
                causality=v.causality,
                variability=v.variability,
                start=v.start,
            )
            for v in md.modelVariables
        }
        missing = [n for n in REQUIRED_VARIABLES if n not in self.variables]
        if missing:
            raise HarnessInputError(
                argument,
                f"{self.path.name} lacks the oscillator variable(s) {', '.join(map(repr, missing))}",
            )
        self._sha256: str | None = None

    @property
    def has_sensitivities(self) -> bool:
        """True when the FMU can report the derivatives of its map (:data:`SENSITIVITY_OUTPUTS`)."""
        return all(n in self.variables for n in (SENSITIVITY_SWITCH, *SENSITIVITY_OUTPUTS))

    # -- identity ------------------------------------------------------------------------
    @property
    def sha256(self) -> str:
        """The FMU file's sha256 (computed once)."""
        if self._sha256 is None:
            self._sha256 = sha256_of(self.path)
        return self._sha256

    def source(self, embed: bool = False) -> "FmuSource":
        """A picklable handle for workers; ``embed`` ships the bytes (remote Dask workers)."""
        data = self.path.read_bytes() if embed else None
        return FmuSource(str(self.path), self.sha256, data)

    # -- variables -----------------------------------------------------------------------
    def parameter_names(self) -> list[str]:
        """Names of the variables the harness may set (parameters and inputs)."""
        return [n for n, v in self.variables.items() if v.settable]

    def variable(self, name: str, argument: str | None = None) -> VariableInfo:
        """Look up a variable by name, with a clear error naming ``argument`` if unknown."""
        try:
            return self.variables[name]
        except KeyError:
            raise HarnessInputError(
                argument or name,
                f"unknown FMU variable {name!r}; settable variables of {self.path.name}: "
                + ", ".join(self.parameter_names()),
            ) from None

    def check_settable(self, name: str, argument: str | None = None) -> VariableInfo:
        """Return the variable if the harness may set it, else raise naming the reason."""
        var = self.variable(name, argument)
        if not var.settable:
            raise HarnessInputError(
                argument or name,
                f"FMU variable {name!r} has causality {var.causality!r} and variability "
                f"{var.variability!r}; only parameters and inputs can be set",
            )
        return var

    def coerce(self, name: str, value: Any, argument: str | None = None) -> float | int | bool:
        """Convert ``value`` to the Python type of FMU variable ``name`` (checked settable)."""
        var = self.check_settable(name, argument)
        return coerce_value(var, value, argument or name)

    def defaults(self) -> dict[str, float | int | bool]:
        """Start values of all settable parameters, as given by the modelDescription."""
        out: dict[str, float | int | bool] = {}
        for name in self.parameter_names():
            var = self.variables[name]
            if var.start is not None and var.type in REAL_TYPES | INTEGER_TYPES | BOOLEAN_TYPES:
                out[name] = coerce_value(var, var.start, name)
        return out


def coerce_value(var: VariableInfo, value: Any, argument: str) -> float | int | bool:
    """Convert a user value (number, string from TOML or CLI) to the variable's type."""
    try:
        if var.type in REAL_TYPES:
            if isinstance(value, bool):
                raise ValueError
            return float(value)
        if var.type in INTEGER_TYPES:
            if var.name == "wall" and isinstance(value, str) and value.lower() in WALL_NAMES:
                return WALL_NAMES[value.lower()]
            if var.name == SOLVER_PARAMETER and isinstance(value, str) and value.lower() in SOLVER_NAMES:
                return SOLVER_NAMES[value.lower()]
            if isinstance(value, bool):
                raise ValueError
            f = float(value)
            if f != int(f):
                raise ValueError
            return int(f)
        if var.type in BOOLEAN_TYPES:
            if isinstance(value, str):
                if value.lower() in ("true", "1", "yes"):
                    return True
                if value.lower() in ("false", "0", "no"):
                    return False
                raise ValueError
            return bool(value)
    except (TypeError, ValueError):
        hint = {"wall": " (or one of none, compliant, rigid)",
                SOLVER_PARAMETER: " (or one of " + ", ".join(SOLVER_NAMES) + ")"}.get(var.name, "")
        raise HarnessInputError(
            argument, f"{value!r} is not a valid {var.type} value for FMU variable {var.name!r}{hint}"
        ) from None
    raise HarnessInputError(argument, f"FMU variable {var.name!r} has type {var.type}, which the harness cannot set")


# ----------------------------------------------------------------------------------------
# Picklable handle and per-process extraction
# ----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FmuSource:
    """What a worker needs to open the same FMU: its path, its sha256, maybe its bytes.

    On a worker that shares the file system the path is used after its sha256 is checked;
    on a remote Dask worker ``data`` (the FMU's bytes) is written to a local cache instead.
    The sha256 guarantees every backend runs the very same binary.
    """

    path: str
    sha256: str
    data: bytes | None = field(default=None, repr=False, compare=False)


_EXTRACT_LOCK = threading.Lock()
_EXTRACTED: dict[str, tuple[str, "FmuModel"]] = {}


def _tmp_root() -> str:
    # one folder per process, removed on exit, SIGTERM, or by the next run after a SIGKILL
    from . import tempdirs

    return tempdirs.root()


def open_source(source: FmuSource) -> tuple[str, FmuModel]:
    """Extract the FMU once per process and return (unzip directory, model).

    Raises
    ------
    FmuError
        If the file at ``source.path`` is not the FMU the run was planned with (its sha256
        differs) and no bytes were shipped.
    """
    from fmpy import extract

    with _EXTRACT_LOCK:
        hit = _EXTRACTED.get(source.sha256)
        if hit is not None:
            return hit
        path = source.path
        if not (os.path.isfile(path) and sha256_of(path) == source.sha256):
            if source.data is None:
                raise FmuError(
                    f"FMU {path} is missing on this worker or differs from the one the run "
                    f"was planned with (sha256 {source.sha256[:12]}...)"
                )
            path = os.path.join(_tmp_root(), source.sha256 + ".fmu")
            with open(path, "wb") as fh:
                fh.write(source.data)
        model = FmuModel(path, argument="--fmu")  # checks the archive before extracting it
        try:
            unzipdir = extract(path, unzipdir=os.path.join(_tmp_root(), source.sha256))
        except (zipfile.BadZipFile, OSError, EOFError) as exc:
            raise HarnessInputError("--fmu", f"cannot extract {path}: {exc}") from None
        _EXTRACTED[source.sha256] = (unzipdir, model)
        return unzipdir, model


# ----------------------------------------------------------------------------------------
# Slaves: the version-specific part
# ----------------------------------------------------------------------------------------
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


class Fmi2Slave(_SlaveBase):
    """One FMI 2.0 Co-Simulation instance (fmpy's low-level ``FMU2Slave``).

    The interface (``initialize``, ``reset``, ``set``, ``do_step``, ``getter``,
    ``last_error``, ``close``) is all the simulator uses; :class:`Fmi3Slave` provides the
    same methods.
    """

    def __init__(self, model: FmuModel, unzipdir: str, instance_name: str) -> None:
        from fmpy.fmi2 import FMU2Slave

        from harness.fmi2_logging import Fmi2Callbacks

        self.messages = collections.deque(maxlen=50)
        self._fmu = FMU2Slave(
            guid=model.guid,
            unzipDirectory=unzipdir,
            modelIdentifier=model.model_identifier,
            instanceName=instance_name,
        )
        # Not a ctypes logger of our own: fmpy's proxy keeps one process-wide pointer to it,
        # which dangled once this slave was collected (harness/fmi2_logging.py).
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
        bound once so that the per-period read is a single FMI call."""
        vrs = [v.value_reference for v in variables]
        family = variables[0].type
        if family in REAL_TYPES:
            return lambda: self._fmu.getReal(vrs)
        if family in INTEGER_TYPES:
            return lambda: self._fmu.getInteger(vrs)
        return lambda: self._fmu.getBoolean(vrs)



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
        self._fmu = FMU3Slave(
            guid=model.guid,
            unzipDirectory=unzipdir,
            modelIdentifier=model.model_identifier,
            instanceName=instance_name,
        )

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
        vrs = [v.value_reference for v in variables]
        typ = variables[0].type
        name = {"Enumeration": "getInt64"}.get(typ, f"get{typ}")
        get = getattr(self._fmu, name)
        return lambda: get(vrs)



#: Slave class per FMI major version.
SLAVE_CLASSES: dict[str, type] = {"2": Fmi2Slave, "3": Fmi3Slave}


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
