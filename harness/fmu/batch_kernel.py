"""The batch kernel: the FMU's closed-form stepper run for many starts at once, from Python.

``build/fmu/libimpact_batch.so`` (``fmu_src/batch.c``, built with the FMUs) runs each start
through the same C calls as the FMU's closed-form mode (``solver = 1``) -- the same model.c and
closed_form.c, one advance per forcing period -- on all cores (OpenMP threads; ctypes releases
the GIL), with an optional early stop when a start's stroboscopic orbit recurs on an attractor
already found.  No physics is written here: this module only moves numpy arrays in and out.
"""
from __future__ import annotations

import ctypes
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..errors import HarnessInputError
from ..config.defaults import WALLS

#: Per-start status codes of the kernel (``fmu_src/batch.c``).
RAN, MATCHED, INVALID, FAILED, ESCAPED, APERIODIC = 0, 1, 2, 3, 4, 5
LIBRARY_NAME = "libimpact_batch.so"
_VERSION = 5
_LIBS: dict[str, ctypes.CDLL] = {}


def default_library() -> Path:
    """``build/fmu/libimpact_batch.so`` of this checkout (beside the FMUs)."""
    return Path(__file__).resolve().parents[2] / "build" / "fmu" / LIBRARY_NAME


def load_library(path: str | Path | None = None) -> ctypes.CDLL:
    """The kernel's shared library, loaded once per process.

    Raises
    ------
    HarnessInputError
        When it is missing (not built: ``cmake --build build/fmu``) or of another version.
    """
    p = Path(path) if path is not None else default_library()
    key = str(p.resolve()) if p.exists() else str(p)
    if key in _LIBS:
        return _LIBS[key]
    if not p.exists():
        raise HarnessInputError("kernel", f"the batch kernel {p} is not built (cmake --build build/fmu)")
    # idle OpenMP threads sleep rather than spin: between the kernel's calls the process runs
    # Python on one core, and a spinning thread would burn the other cores' time (read once,
    # when the OpenMP runtime loads; a value the user set is kept)
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    lib = ctypes.CDLL(str(p))
    if lib.impact_batch_version() != _VERSION:
        raise HarnessInputError("kernel", f"{p} is a stale build of the batch kernel (cmake --build build/fmu)")
    i32, f64, ptr = ctypes.c_int, ctypes.c_double, ctypes.c_void_p
    lib.impact_batch_run.restype = i32
    lib.impact_batch_run.argtypes = [i32, ptr, ptr, ctypes.c_long, ptr, ptr, f64, i32, i32, i32, i32, ptr, ptr, ptr,
                                     f64, ptr, f64, i32, f64, i32, ptr, ptr, ptr, ptr, ptr, ptr, ptr, ctypes.c_char_p,
                                     i32]
    _LIBS[key] = lib
    return lib


@dataclass
class BatchResult:
    """What the kernel returns for n starts.

    Attributes
    ----------
    label : numpy.ndarray of int, shape (n,)
        The known attractor a start was recognised as (early stop), or -1.
    periods : numpy.ndarray of int, shape (n,)
        Forcing periods run.
    status : numpy.ndarray of int, shape (n,)
        :data:`RAN`, :data:`MATCHED`, :data:`INVALID`, :data:`FAILED`, :data:`ESCAPED` or
        :data:`APERIODIC` (stopped once its samples ruled out a period: ``aperiodic_tol``).
    u, v : numpy.ndarray, shape (n, samples)
        The stroboscopic samples after the transient (NaN where not reached).
    impacts : numpy.ndarray of int, shape (n, samples)
        Wall entries in the period ending at each sample (-1 where not reached).
    stuck : numpy.ndarray of bool, shape (n, samples)
        Sticking on the rigid wall at the sample.
    error : str
        The first failure's message ('' if none).
    """

    label: np.ndarray
    periods: np.ndarray
    status: np.ndarray
    u: np.ndarray
    v: np.ndarray
    impacts: np.ndarray
    stuck: np.ndarray
    error: str


@dataclass(frozen=True)
class KnownAttractors:
    """Attractors for the early stop: points (k, width, 2) in orbit order, NaN-padded, the wall
    entries of the period ending on each point (k, width), the periods (k,), the tolerance (max
    norm) and, per attractor (or one number for all), how many consecutive periods on the orbit
    recognise a start."""

    points: np.ndarray
    entries: np.ndarray
    period: np.ndarray
    tol: float
    confirm: np.ndarray | int

    @classmethod
    def none(cls, tol: float = 1.0) -> "KnownAttractors":
        """No attractor known: every start runs in full (``tol``: for matching its orbits later)."""
        return cls(np.zeros((0, 1, 2)), np.zeros((0, 1), dtype=np.int32), np.zeros(0, dtype=np.int32), float(tol), 1)


def kernel_parameters(params: Mapping[str, Any]) -> tuple[list[str], list[float]]:
    """FMU parameters as the kernel's (names, values): the wall by its number."""
    names, values = [], []
    for name, value in params.items():
        if name == "wall" and isinstance(value, str):
            value = WALLS[value]
        names.append(str(name))
        values.append(float(value))
    return names, values


def default_threads() -> int:
    """Threads per kernel call: the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def run_batch(params: Mapping[str, Any], u0: np.ndarray, v0: np.ndarray, theta: float, n_transient: int,
              n_samples: int, known: KnownAttractors | None = None, threads: int | None = None,
              library: str | Path | None = None, recur_tol: float = 0.0, max_period: int | None = None,
              aperiodic_tol: float = 0.0) -> BatchResult:
    """Run every start (u0[i], v0[i]) at t = theta through the closed form.

    Parameters
    ----------
    params : mapping
        FMU parameters (the kernel knows the model's physical ones; others are refused).
    u0, v0 : numpy.ndarray
        The starts, same length.
    theta : float
        Section phase (start time and sample times n + theta).
    n_transient, n_samples : int
        Periods run before sampling, and sampled.
    known : KnownAttractors, optional
        The early stop's attractors (none: every start runs in full).
    threads : int, optional
        OpenMP threads (default: this process's cores).
    recur_tol : float
        > 0: a start also stops once its last ``n_samples`` states repeat with a shift up to
        ``max_period`` (default ``n_samples // 2``) to this tolerance, relative to 1 + their
        largest peak-to-peak range (the test of
        :func:`harness.dynamics.maps.classify.classify_orbit`); those states are its samples
        (status :data:`RAN`, ``periods`` says when it stopped).
    aperiodic_tol : float
        > 0: a start also stops (status :data:`APERIODIC`, its samples so far filled in) once
        they rule out every shift up to ``max_period`` -- for each a pair of samples with other
        wall entries or farther apart than this tolerance times 1 + their largest range so far
        -- and no known attractor can recognise it before its last period
        (``fmu_src/batch.c``).

    Raises
    ------
    HarnessInputError
        Parameters the kernel (or the model's checks) refuses, named in the message.
    """
    lib = load_library(library)
    known = known or KnownAttractors.none()
    names, values = kernel_parameters(params)
    c_names = (ctypes.c_char_p * max(1, len(names)))(*[n.encode() for n in names])
    c_values = np.ascontiguousarray(values, dtype=np.float64)
    u0 = np.ascontiguousarray(u0, dtype=np.float64)
    v0 = np.ascontiguousarray(v0, dtype=np.float64)
    n = u0.size
    out = BatchResult(np.full(n, -1, np.int32), np.zeros(n, np.int32), np.zeros(n, np.int32),
                      np.full((n, n_samples), np.nan), np.full((n, n_samples), np.nan),
                      np.full((n, n_samples), -1, np.int32), np.zeros((n, n_samples), np.uint8), "")
    pts = np.ascontiguousarray(np.nan_to_num(known.points, nan=np.inf), dtype=np.float64)
    ent = np.ascontiguousarray(known.entries, dtype=np.int32)
    per = np.ascontiguousarray(known.period, dtype=np.int32)
    confirm = np.ascontiguousarray(np.broadcast_to(np.asarray(known.confirm, dtype=np.int32), per.shape))
    err = ctypes.create_string_buffer(1024)
    a = lambda x: x.ctypes.data  # noqa: E731 - the arrays outlive the call
    rc = lib.impact_batch_run(len(names), c_names, a(c_values), n, a(u0), a(v0), float(theta), int(n_transient),
                              int(n_samples), per.size, pts.shape[1], a(per), a(pts), a(ent), float(known.tol),
                              a(confirm), float(recur_tol), int(max_period or n_samples // 2), float(aperiodic_tol),
                              int(threads or default_threads()), a(out.label), a(out.periods),
                              a(out.status), a(out.u), a(out.v), a(out.impacts), a(out.stuck), err, len(err))
    out.error = err.value.decode(errors="replace")
    if rc != 0 and not np.any(out.status == FAILED):
        raise HarnessInputError("params", out.error)
    return out
