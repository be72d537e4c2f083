"""The validated views of an experiment's sections: :class:`SamplingSpec`, :class:`SweepSpec` (with
the grid of a swept parameter, :func:`parameter_values`, and its modes, :func:`parse_modes`) and
:class:`RunSpec`."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import HarnessInputError
from .checks import _count, _number, check_count, check_theta
from .defaults import BACKENDS, SWEEP_MODES, default_workers
from .layers import Layered

__all__ = ["SamplingSpec", "SweepSpec", "RunSpec", "parameter_values", "parse_modes", "sweep_directions"]


@dataclass(frozen=True, kw_only=True)
class SamplingSpec:
    """Section phase, transient and sampled periods, classification tolerance.

    Keyword-only, and checked on creation (theta in [0, 1), counts >= 0, tol > 0).
    """

    #: the library's default is the paper's section t = n; every command passes the CLI's
    #: default, :data:`harness.config.SECTION_PHASE`, through the settings' layers
    theta: float = 0.0
    n_transient: int = 300
    n_samples: int = 40
    tol: float = 1e-5
    max_period: int | None = None
    #: extra periods a point may run when its samples are not yet periodic (0: none);
    #: sampled in windows of ``n_samples``, the last window is kept
    extend: int = 0
    #: periods after the samples over which the Lyapunov exponents of the stroboscopic map
    #: are averaged (0: none); the FMU's own derivatives when it has them, else differences
    lyapunov: int = 0

    def __post_init__(self) -> None:
        check_theta(self.theta, "theta")
        check_count(self.n_transient, "n_transient")
        check_count(self.n_samples, "n_samples", minimum=2)
        if not (isinstance(self.tol, (int, float)) and self.tol > 0):
            raise HarnessInputError("tol", f"must be > 0, got {self.tol!r}")
        if self.max_period is not None:
            check_count(self.max_period, "max_period", minimum=1)
        check_count(self.extend, "extend")
        if self.lyapunov:
            check_count(self.lyapunov, "lyapunov", minimum=2)

    @classmethod
    def from_layers(cls, layers: Layered) -> "SamplingSpec":
        """Validated view of ``[sampling]`` (errors name the flag or file key)."""
        from ..errors import ErrorCollector

        c, s = ErrorCollector(), "sampling"  # every bad key at once
        theta = c.check(check_theta, layers.get(s, "theta"), layers.arg(s, "theta"))
        mp = layers.get(s, "max_period")
        fields = dict(
            theta=theta,
            n_transient=c.check(_count, layers, s, "transient"),
            n_samples=c.check(_count, layers, s, "samples", minimum=2),
            tol=c.check(_number, layers, s, "tol", positive=True),
            max_period=None if mp is None else c.check(_count, layers, s, "max_period", minimum=1),
            extend=c.check(_count, layers, s, "extend"),
            lyapunov=c.check(_count, layers, s, "lyapunov"),
        )
        c.raise_if_any()
        return cls(**fields)


def parameter_values(start: Any, stop: Any, num: Any, values: Any, args: tuple[str, str, str, str]) -> np.ndarray:
    """Grid of a swept parameter from ``start/stop/num`` or an explicit ``values`` list.

    Raises
    ------
    HarnessInputError
        For an empty range (``num < 1``, an empty list, or ``start == stop`` with ``num > 1``),
        non-numeric or non-finite values.
    """
    a_start, a_stop, a_num, a_values = args
    if values is not None:
        if isinstance(values, str):
            values = [s for s in values.replace(",", " ").split()]
        try:
            arr = np.array([float(x) for x in values], dtype=float)
        except (TypeError, ValueError):
            raise HarnessInputError(a_values, f"expected a list of numbers, got {values!r}") from None
        if arr.size == 0:
            raise HarnessInputError(a_values, "empty range: no parameter values given")
        if not np.all(np.isfinite(arr)):
            raise HarnessInputError(a_values, "values must be finite")
        if np.unique(arr).size != arr.size:
            raise HarnessInputError(a_values, "values must be distinct")
        return arr
    n = check_count(num, a_num)
    if n < 1:
        raise HarnessInputError(a_num, f"empty range: {a_num} must be >= 1, got {n}")
    try:
        lo, hi = float(start), float(stop)
    except (TypeError, ValueError):
        raise HarnessInputError(a_start, f"expected numbers for {a_start} and {a_stop}, got {start!r}, {stop!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi)):
        raise HarnessInputError(a_start, "start and stop must be finite")
    if n > 1 and lo == hi:
        raise HarnessInputError(a_stop, f"empty range: start = stop = {lo} with {n} points")
    grid = np.linspace(lo, hi, n)
    if n > 1:  # a point that is 0 up to the rounding of lo + k step (-5.55e-17) is 0
        grid[np.abs(grid) < 1e-9 * abs(hi - lo) / (n - 1)] = 0.0
    return grid


@dataclass(frozen=True)
class SweepSpec:
    """Swept parameter(s), their grids and the sweep modes."""

    param: str
    values: np.ndarray
    modes: tuple[str, ...]
    scan_param: str | None = None
    scan_values: np.ndarray | None = None

    @classmethod
    def from_layers(cls, layers: Layered, model: Any = None) -> "SweepSpec":
        """Validated view of ``[sweep]``; parameter names checked against ``model``."""
        s = "sweep"
        param = str(layers.get(s, "param"))
        if model is not None:
            model.check_settable(param, layers.arg(s, "param"))
        values = parameter_values(
            layers.get(s, "start"), layers.get(s, "stop"), layers.get(s, "num"), layers.get(s, "values"),
            (layers.arg(s, "start"), layers.arg(s, "stop"), layers.arg(s, "num"), layers.arg(s, "values")),
        )
        modes = parse_modes(layers.get(s, "mode"), layers.arg(s, "mode"))
        scan_param = layers.get(s, "scan_param")
        scan_values = None
        if scan_param is not None:
            scan_param = str(scan_param)
            if model is not None:
                model.check_settable(scan_param, layers.arg(s, "scan_param"))
            if scan_param == param:
                raise HarnessInputError(layers.arg(s, "scan_param"), f"the second axis repeats {param!r}")
            raw = layers.get(s, "scan_values")
            if raw is None:
                raise HarnessInputError(layers.arg(s, "scan_param"), "a second axis needs scan_values")
            scan_values = parameter_values(None, None, None, raw, (layers.arg(s, "scan_values"),) * 4)
        return cls(param, values, modes, scan_param, scan_values)


def parse_modes(mode: Any, argument: str) -> tuple[str, ...]:
    """A list or comma string of fresh/up/down/both, checked and without repeats.

    ``both`` is the hysteresis loop (up, then down from the state where the up scan ended);
    ``up,down`` are two independent scans, each from the initial state.
    """
    items = mode.replace(",", " ").split() if isinstance(mode, str) else list(mode)
    out: list[str] = []
    for m in items:
        m = str(m).lower()
        if m not in SWEEP_MODES:
            raise HarnessInputError(argument, f"unknown sweep mode {m!r}; choose from fresh, up, down, both")
        if m not in out:
            out.append(m)
    if not out:
        raise HarnessInputError(argument, "no sweep mode given")
    if "both" in out and ("up" in out or "down" in out):
        raise HarnessInputError(argument, "'both' is the up-then-down loop already; give it alone, or "
                                "'up,down' for two independent scans from the initial state")
    return tuple(out)


def sweep_directions(modes: tuple[str, ...] | list[str]) -> list[str]:
    """The directions of a sweep's results: ``both`` stands for up and down."""
    out: list[str] = []
    for m in modes:
        out.extend(("up", "down") if m == "both" else (m,))
    return out


@dataclass(frozen=True)
class RunSpec:
    """Where and how a run executes, and where its results go."""

    backend: str = "processes"
    workers: int = 1
    scheduler: str | None = None
    out: str | None = None
    plot: str | None = None
    checkpoint: str | None = None
    progress: bool = True

    @classmethod
    def from_layers(cls, layers: Layered) -> "RunSpec":
        """Validated view of ``[run]`` (backend, workers, scheduler, outputs)."""
        from ..errors import ErrorCollector

        r, c = "run", ErrorCollector()  # every bad key at once
        scheduler = layers.get(r, "scheduler") or None
        backend = layers.get(r, "backend")
        if backend is None:
            backend = "dask" if scheduler else "processes"
        backend = str(backend).lower()
        if backend not in BACKENDS:
            c.add(HarnessInputError(layers.arg(r, "backend"), f"unknown backend {backend!r}; choose from {', '.join(BACKENDS)}"))
        elif scheduler is not None:
            if backend != "dask":
                c.add(HarnessInputError(layers.arg(r, "scheduler"), f"a scheduler address needs the dask backend, not {backend!r}"))
            elif "://" not in str(scheduler):
                c.add(HarnessInputError(layers.arg(r, "scheduler"), f"expected an address like tcp://HOST:PORT, got {scheduler!r}"))
        workers = layers.get(r, "workers")
        workers = default_workers() if workers is None else c.check(_count, layers, r, "workers", minimum=1)
        c.raise_if_any()
        return cls(
            backend=backend,
            workers=workers,
            scheduler=str(scheduler) if scheduler else None,
            out=layers.get(r, "out"),
            plot=layers.get(r, "plot"),
            checkpoint=layers.get(r, "checkpoint"),
            progress=bool(layers.get(r, "progress")),
        )
