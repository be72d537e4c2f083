"""The batch kernel over a parameter plane, from Python: many pixels (parameter sets) times a few
starts each, every start run by the FMU's closed form in C until its stroboscopic orbit is
periodic, then the orbit's Lyapunov exponent from the exact Jacobian of its M-period map
(``fmu_src/batch_atlas.c``, in ``build/fmu/libimpact_batch.so`` beside :mod:`.batch_kernel`).

No physics here: numpy arrays in and out.
"""
from __future__ import annotations

import ctypes
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from ..errors import HarnessInputError
from .batch_kernel import default_threads, kernel_parameters, load_library

#: Per-start status codes of the atlas kernel (``fmu_src/batch_atlas.c``).
PERIODIC, APERIODIC, INVALID, FAILED, ESCAPED = 0, 1, 2, 3, 4
STATUS_NAMES = ("periodic", "aperiodic", "invalid", "failed", "escaped")


@dataclass
class AtlasBatch:
    """What the kernel returns for n_pix pixels x k starts (arrays of shape (n_pix, k) unless said).

    Attributes
    ----------
    pixel_ok : numpy.ndarray of bool, shape (n_pix,)
        False where the pixel's parameters are refused (its starts: FAILED).
    status : numpy.ndarray of int
        PERIODIC, APERIODIC (not periodic after ``n_max`` periods), INVALID, FAILED, ESCAPED.
    period, impacts : numpy.ndarray of int
        The orbit's period M (0: none found) and wall entries per orbit period.
    periods_run : numpy.ndarray of int
        Forcing periods run (the exponent's included).
    sticks : numpy.ndarray of bool
        The orbit sticks on a rigid wall at a sample, or chatters (>= 8 entries in a period).
    lyapunov : numpy.ndarray of float
        Largest Lyapunov exponent per forcing period: ln|mu|/M of the orbit's M-period map
        (periodic), or of a tangent vector over ``n_lyap`` periods (aperiodic); NaN otherwise.
    points : numpy.ndarray, shape (n_pix, k, m_max, 2)
        The orbit's stroboscopic points in time order (NaN beyond M; aperiodic: the last state).
    error : str
        The first refusal or failure ('' if none).
    """

    pixel_ok: np.ndarray
    status: np.ndarray
    period: np.ndarray
    impacts: np.ndarray
    periods_run: np.ndarray
    sticks: np.ndarray
    lyapunov: np.ndarray
    points: np.ndarray
    error: str


def _library(path: str | Path | None) -> ctypes.CDLL:
    lib = load_library(path)
    if not hasattr(lib, "_atlas_typed"):
        i32, f64, ptr, lng = ctypes.c_int, ctypes.c_double, ctypes.c_void_p, ctypes.c_long
        lib.impact_atlas_run.restype = i32
        lib.impact_atlas_run.argtypes = [i32, ptr, ptr, i32, ptr, lng, ptr, i32, ptr, ptr, f64, i32, i32, i32, f64,
                                         f64, i32, i32, ptr, ptr, ptr, ptr, ptr, ptr, ptr, ptr, ctypes.c_char_p, i32]
        lib.impact_atlas_max_period.restype = i32
        lib._atlas_typed = True
    return lib


def max_period(library: str | Path | None = None) -> int:
    """The largest period the kernel searches."""
    return int(_library(library).impact_atlas_max_period())


def run_atlas(params: Mapping[str, Any], vary: Sequence[str], values: np.ndarray, u0: np.ndarray, v0: np.ndarray,
              theta: float, n_min: int, n_max: int, m_max: int, tol: float, n_lyap: int,
              match_tol: float = 1e-4, threads: int | None = None, library: str | Path | None = None) -> AtlasBatch:
    """Run every pixel's starts to their attractors.

    Parameters
    ----------
    params : mapping
        The FMU parameters every pixel shares.
    vary : sequence of str
        The parameters set per pixel (e.g. ``("sigma", "Gamma")``).
    values : numpy.ndarray, shape (n_pix, len(vary))
        Their values per pixel.
    u0, v0 : numpy.ndarray, shape (n_pix, k)
        The starts at t = theta.
    theta : float
        Section phase.
    n_min, n_max : int
        Periods before the periodicity test starts, and at most before a start counts as aperiodic.
    m_max : int
        Largest period searched (at most :func:`max_period`).
    tol : float
        Periodicity tolerance, relative to 1 + |u| + |v|.
    n_lyap : int
        Periods of the exponent of an aperiodic start.
    match_tol : float
        A later start of a pixel within this (relative, as ``tol``) of an earlier start's orbit,
        following it for two rounds, is that orbit and stops.

    Raises
    ------
    HarnessInputError
        The shared parameters refused (nothing run).
    """
    lib = _library(library)
    values = np.ascontiguousarray(values, dtype=np.float64)
    u0 = np.ascontiguousarray(u0, dtype=np.float64)
    v0 = np.ascontiguousarray(v0, dtype=np.float64)
    n_pix, k = u0.shape
    if values.shape != (n_pix, len(vary)) or v0.shape != u0.shape:
        raise HarnessInputError("values", f"shapes {values.shape}, {u0.shape}, {v0.shape} do not fit {len(vary)} "
                                "parameters per pixel")
    names, base = kernel_parameters({n: x for n, x in params.items() if n not in vary})
    c_names = (ctypes.c_char_p * max(1, len(names)))(*[n.encode() for n in names])
    c_vary = (ctypes.c_char_p * max(1, len(vary)))(*[n.encode() for n in vary])
    c_base = np.ascontiguousarray(base, dtype=np.float64)
    ok = np.zeros(n_pix, np.int32)
    out = [np.zeros((n_pix, k), np.int32) for _ in range(4)]
    sticks = np.zeros((n_pix, k), np.uint8)
    lyap = np.full((n_pix, k), np.nan)
    points = np.full((n_pix, k, m_max, 2), np.nan)
    err = ctypes.create_string_buffer(1024)
    a = lambda x: x.ctypes.data  # noqa: E731 - the arrays outlive the call
    rc = lib.impact_atlas_run(len(names), c_names, a(c_base), len(vary), c_vary, n_pix, a(values), k, a(u0), a(v0),
                              float(theta), int(n_min), int(n_max), int(m_max), float(tol), float(match_tol), int(n_lyap),
                              int(threads or default_threads()), a(ok), *(a(x) for x in out), a(sticks), a(lyap),
                              a(points), err, len(err))
    error = err.value.decode(errors="replace")
    if rc != 0 and not ok.any() and not np.any(out[0] == FAILED):
        raise HarnessInputError("params", error)
    status, period, impacts, periods = out
    return AtlasBatch(ok.astype(bool), status, period, impacts, periods, sticks.astype(bool), lyap, points, error)
