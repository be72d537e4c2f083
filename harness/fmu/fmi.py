"""FMI layer: read and check an FMU, and drive one reusable Co-Simulation instance.

The rest of the harness talks to a *simulator* (:class:`harness.fmu.simulator.Simulator`),
never to fmpy directly.  This module is the only place that knows about fmpy and FMI:

* :class:`FmuModel` reads the modelDescription once (in the process that plans a run),
  checks that the FMU is Co-Simulation and has the oscillator's variables, and maps
  variable names to value references and types.  Nothing is hard-coded: the value
  references come from the modelDescription.
* :class:`FmuSource` is the small, picklable handle (path + sha256 + optionally the bytes)
  that travels to worker processes and Dask workers.
* :class:`FmuSimulator` owns *one* slave instance and reuses it between runs with
  ``reset`` (instantiating is far more expensive than resetting).
* :func:`harness.fmu.slaves.make_slave` picks the slave class from the FMU's ``fmiVersion``
  (FMI 2.0 or 3.0, :data:`SUPPORTED_FMI_VERSIONS`).
"""
from __future__ import annotations

import hashlib
import os
import threading
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..config.defaults import SOLVERS, WALLS
from ..errors import FmuError, HarnessInputError

#: Names of the oscillator's variables.  They are the interface between the harness and
#: any FMU it drives (the C FMU, its Python twin, an FMI 3.0 build).
STATE_OUTPUTS = ("u", "v")
IMPACT_COUNTER = "impacts"
INITIAL_STATE = ("u0", "v0")
REQUIRED_VARIABLES = (*STATE_OUTPUTS, IMPACT_COUNTER, *INITIAL_STATE)


#: The FMU's derivatives of its last ``doStep``: a Boolean parameter switches the
#: variational equations on, six outputs give d(u, v)_end/d(u, v)_start (J_uv = du/dv_start)
#: and d(u, v)_end/d sigma.  An FMU that has all of them gets exact map Jacobians; one
#: without falls back to finite differences (feature detection by name, no version check).
SENSITIVITY_SWITCH = "sensitivities"
SENSITIVITY_OUTPUTS = ("J_uu", "J_uv", "J_vu", "J_vv", "S_u", "S_v")

#: Integer parameter choosing the FMU's integrator (its names: :data:`harness.config.SOLVERS`).
SOLVER_PARAMETER = "solver"

#: Major FMI versions the harness drives (one slave class each in :mod:`harness.fmu.slaves`).
SUPPORTED_FMI_VERSIONS = ("2", "3")

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
        if major not in SUPPORTED_FMI_VERSIONS:
            raise HarnessInputError(
                argument,
                f"{self.path.name} is an FMI {self.fmi_version} FMU; supported: "
                + ", ".join(f"FMI {v}.x" for v in SUPPORTED_FMI_VERSIONS),
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
            if var.name == "wall" and isinstance(value, str) and value.lower() in WALLS:
                return WALLS[value.lower()]
            if var.name == SOLVER_PARAMETER and isinstance(value, str) and value.lower() in SOLVERS:
                return SOLVERS[value.lower()]
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
        hint = {"wall": " (or one of " + ", ".join(WALLS) + ")",
                SOLVER_PARAMETER: " (or one of " + ", ".join(SOLVERS) + ")"}.get(var.name, "")
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
    from ..io import tempdirs

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
