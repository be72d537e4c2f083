"""Experiment description: defaults, TOML experiment files, CLI overrides, validation.

An experiment file holds every parameter of a run::

    [fmu]
    path = "build/fmu/ImpactOscillator.fmu"

    [model]            # any settable FMU variable, by name
    sigma = 0.2
    Gamma = 10.0
    wall = "compliant" # or 0/1/2

    [initial]
    u0 = -1.0
    v0 = 0.0

    [sampling]
    theta = 0.0        # section phase in [0, 1)
    transient = 300    # periods discarded
    samples = 40       # periods sampled
    tol = 1e-5         # periodicity tolerance (relative)
    extend = 0         # extra periods for points not yet periodic (slow near window edges)
    lyapunov = 0       # periods of Lyapunov exponents after the samples (0: none)

    [sweep]
    param = "sigma"
    start = 1.0
    stop = 0.1
    num = 91           # or: values = [...]
    mode = "both"      # fresh | up | down | both
    scan_param = "Gamma"        # optional second axis (2D scan)
    scan_values = [10.0, 100.0]

    [jacobian]
    theta = 0.0        # phase of the coordinates J is expressed in
    x_start = 1e-6
    x_stop = 1e-2
    x_num = 25

    [simulate]
    t0 = 0.0
    t_end = 20.0
    dt = 0.01

    [run]
    backend = "processes"   # serial | processes | dask
    workers = 2
    scheduler = ""          # tcp://host:port -> dask
    out = "results/sweep.nc"
    plot = "results/sweep.png"
    progress = true

Values come from three layers, later ones winning: built-in defaults (and the FMU's own
start values for ``[model]``), the TOML file, the CLI flags.  Each value remembers where it
came from so an error names the flag (``--theta``) or the file key
(``exp.toml: sampling.theta``) the user actually wrote.
"""
from __future__ import annotations

import copy
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .errors import HarnessInputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

SWEEP_MODES = ("fresh", "up", "down", "both")
BACKENDS = ("serial", "processes", "dask")


def project_root() -> Path:
    """The checkout the package lives in (an editable install points here)."""
    return Path(__file__).resolve().parent.parent


def default_fmu_path() -> str:
    """``$IMPACT_HARNESS_FMU`` or ``build/fmu/ImpactOscillator.fmu`` in the checkout."""
    env = os.environ.get("IMPACT_HARNESS_FMU")
    if env:
        return env
    return str(project_root() / "build" / "fmu" / "ImpactOscillator.fmu")


def default_workers() -> int:
    """Cores this process may use (respects CPU affinity and container limits)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


#: Built-in defaults of every section except ``[model]`` (which come from the FMU).
DEFAULTS: dict[str, dict[str, Any]] = {
    "fmu": {"path": None},
    "model": {},
    "initial": {"u0": None, "v0": None},
    # 300 transient periods: the slow free-flight mode decays like 0.98^n at Figure 9's
    # parameters, and orbits near window edges converge slowly.
    "sampling": {"theta": 0.0, "transient": 300, "samples": 40, "tol": 1e-5, "max_period": None, "extend": 0,
                 "lyapunov": 0},
    # Default sweep: Figure 9 from period 1 (sigma > ~0.85) down through period 2 and 3.
    "sweep": {
        "param": "sigma",
        "start": 1.0,
        "stop": 0.1,
        "num": 91,
        "values": None,
        "mode": "both",
        "scan_param": None,
        "scan_values": None,
    },
    "jacobian": {
        "theta": 0.0,
        "measure_theta": 0.5,
        "x_start": 1e-6,
        "x_stop": 1e-2,
        "x_num": 25,
        "state": None,
        "method": "auto",  # exact (the FMU's derivatives), fd (differences), auto (exact when available)
        "rtol": None,  # None: the FMU's own (tight) default tolerances
        "atol": None,
    },
    "simulate": {"t0": 0.0, "t_end": 10.0, "dt": 0.01},
    "run": {
        "backend": None,
        "workers": None,
        "scheduler": None,
        "out": None,
        "plot": None,
        "checkpoint": None,
        "progress": True,
    },
}

#: The CLI flag of each key, for error messages.
CLI_FLAGS: dict[tuple[str, str], str] = {
    ("fmu", "path"): "--fmu",
    ("initial", "u0"): "--u0",
    ("initial", "v0"): "--v0",
    ("sampling", "theta"): "--theta",
    ("sampling", "transient"): "--transient",
    ("sampling", "samples"): "--samples",
    ("sampling", "tol"): "--tol",
    ("sampling", "max_period"): "--max-period",
    ("sampling", "extend"): "--extend",
    ("sampling", "lyapunov"): "--lyapunov",
    ("sweep", "param"): "--param",
    ("sweep", "start"): "--start",
    ("sweep", "stop"): "--stop",
    ("sweep", "num"): "--num",
    ("sweep", "values"): "--values",
    ("sweep", "mode"): "--mode",
    ("sweep", "scan_param"): "--scan",
    ("sweep", "scan_values"): "--scan",
    ("jacobian", "theta"): "--theta",
    ("jacobian", "measure_theta"): "--measure-theta",
    ("jacobian", "x_start"): "--x-start",
    ("jacobian", "x_stop"): "--x-stop",
    ("jacobian", "x_num"): "--x-num",
    ("jacobian", "state"): "--state",
    ("jacobian", "method"): "--method",
    ("simulate", "t0"): "--t0",
    ("simulate", "t_end"): "--t-end",
    ("simulate", "dt"): "--dt",
    ("run", "backend"): "--backend",
    ("run", "workers"): "--workers",
    ("run", "scheduler"): "--scheduler",
    ("run", "out"): "--out",
    ("run", "plot"): "--plot",
    ("run", "checkpoint"): "--checkpoint",
}


class Layered:
    """Nested settings with the origin of each value (for error messages)."""

    def __init__(self) -> None:
        self.values: dict[str, dict[str, Any]] = copy.deepcopy(DEFAULTS)
        self.origin: dict[tuple[str, str], str] = {}

    def merge(self, layer: Mapping[str, Mapping[str, Any]], source: str) -> None:
        """Overlay ``layer`` (``{section: {key: value}}``); ``source`` is ``"cli"`` or a file name.

        Unknown sections and keys are rejected (except in ``[model]``, whose keys are FMU
        variables checked later against the modelDescription).
        """
        for section, entries in layer.items():
            if section not in DEFAULTS:
                raise HarnessInputError(
                    f"{source}: [{section}]",
                    f"unknown section; known sections: {', '.join(DEFAULTS)}",
                )
            if not isinstance(entries, Mapping):
                raise HarnessInputError(f"{source}: {section}", "must be a table")
            for key, value in entries.items():
                if section != "model" and key not in DEFAULTS[section]:
                    raise HarnessInputError(
                        f"{source}: {section}.{key}",
                        f"unknown key; known keys of [{section}]: {', '.join(DEFAULTS[section])}",
                    )
                if value is None:
                    continue  # "not given": keeps the lower layer
                self.values[section][key] = value
                self.origin[(section, key)] = source

    def arg(self, section: str, key: str) -> str:
        """How to name ``section.key`` in an error: its CLI flag or its file key."""
        src = self.origin.get((section, key))
        if src == "cli":
            return CLI_FLAGS.get((section, key), f"--{key.replace('_', '-')}")
        if src is None:
            return f"{section}.{key}"
        return f"{src}: {section}.{key}"

    def get(self, section: str, key: str) -> Any:
        """The current value of ``section.key``."""
        return self.values[section][key]


def load_toml(path: str | os.PathLike, argument: str = "--config") -> dict[str, Any]:
    """Read an experiment file, turning I/O and syntax problems into clear errors."""
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise HarnessInputError(argument, f"no such file: {str(path)!r}") from None
    except IsADirectoryError:
        raise HarnessInputError(argument, f"{str(path)!r} is a directory, not an experiment file") from None
    except UnicodeDecodeError as exc:  # TOML is UTF-8 by definition
        raise HarnessInputError(argument, f"{path} is not UTF-8 text (byte {exc.start}: {exc.reason})") from None
    except tomllib.TOMLDecodeError as exc:
        raise HarnessInputError(argument, f"{path} is not valid TOML: {exc}") from None
    except OSError as exc:  # permission denied, I/O errors
        raise HarnessInputError(argument, f"cannot read {str(path)!r}: {exc.strerror or exc}") from None


# ----------------------------------------------------------------------------------------
# Typed, validated views
# ----------------------------------------------------------------------------------------
def _number(layers: Layered, section: str, key: str, positive: bool = False) -> float:
    value = layers.get(section, key)
    try:
        if isinstance(value, bool):
            raise ValueError
        x = float(value)
    except (TypeError, ValueError):
        raise HarnessInputError(layers.arg(section, key), f"expected a number, got {value!r}") from None
    if not np.isfinite(x):
        raise HarnessInputError(layers.arg(section, key), f"must be finite, got {value!r}")
    if positive and not x > 0:
        raise HarnessInputError(layers.arg(section, key), f"must be > 0, got {value!r}")
    return x


def _count(layers: Layered, section: str, key: str, minimum: int = 0) -> int:
    from .sampling import check_count

    return check_count(layers.get(section, key), layers.arg(section, key), minimum)


@dataclass(frozen=True, kw_only=True)
class SamplingSpec:
    """Section phase, transient and sampled periods, classification tolerance.

    Keyword-only, and checked on creation (theta in [0, 1), counts >= 0, tol > 0).
    """

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
        from .sampling import check_count, check_theta

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
        from .sampling import check_theta

        theta = check_theta(layers.get("sampling", "theta"), layers.arg("sampling", "theta"))
        mp = layers.get("sampling", "max_period")
        return cls(
            theta=theta,
            n_transient=_count(layers, "sampling", "transient"),
            n_samples=_count(layers, "sampling", "samples", minimum=2),
            tol=_number(layers, "sampling", "tol", positive=True),
            max_period=None if mp is None else _count(layers, "sampling", "max_period", minimum=1),
            extend=_count(layers, "sampling", "extend"),
            lyapunov=_count(layers, "sampling", "lyapunov"),
        )


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
    from .sampling import check_count

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
    return np.linspace(lo, hi, n)


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
        r = "run"
        scheduler = layers.get(r, "scheduler") or None
        backend = layers.get(r, "backend")
        if backend is None:
            backend = "dask" if scheduler else "processes"
        backend = str(backend).lower()
        if backend not in BACKENDS:
            raise HarnessInputError(layers.arg(r, "backend"), f"unknown backend {backend!r}; choose from {', '.join(BACKENDS)}")
        if scheduler is not None:
            if backend != "dask":
                raise HarnessInputError(layers.arg(r, "scheduler"), f"a scheduler address needs the dask backend, not {backend!r}")
            if "://" not in str(scheduler):
                raise HarnessInputError(layers.arg(r, "scheduler"), f"expected an address like tcp://HOST:PORT, got {scheduler!r}")
        workers = layers.get(r, "workers")
        workers = default_workers() if workers is None else _count(layers, r, "workers", minimum=1)
        return cls(
            backend=backend,
            workers=workers,
            scheduler=str(scheduler) if scheduler else None,
            out=layers.get(r, "out"),
            plot=layers.get(r, "plot"),
            checkpoint=layers.get(r, "checkpoint"),
            progress=bool(layers.get(r, "progress")),
        )


@dataclass
class Experiment:
    """Everything a run needs, validated against the FMU.

    Build it with :meth:`from_sources`; ``params`` maps FMU variable names to values of the
    right type, ``state0`` is (u0, v0) at the first section time.
    """

    fmu_path: str
    model: Any  # harness.fmi.FmuModel
    params: dict[str, Any]
    state0: tuple[float, float]
    sampling: SamplingSpec
    run: RunSpec
    layers: Layered = field(repr=False)

    @classmethod
    def from_sources(
        cls,
        config: str | os.PathLike | None = None,
        overrides: Mapping[str, Mapping[str, Any]] | None = None,
        model: Any = None,
    ) -> "Experiment":
        """Defaults < TOML file ``config`` < ``overrides`` (CLI), validated.

        Parameters
        ----------
        config : path, optional
            Experiment file (TOML).
        overrides : mapping, optional
            ``{section: {key: value}}``; ``None`` values mean "not given".
        model : FmuModel, optional
            Already opened FMU (otherwise opened from ``fmu.path``).
        """
        from .fmi import FmuModel, INITIAL_STATE, SOLVER_PARAMETER

        layers = Layered()
        if config is not None:
            layers.merge(load_toml(config), Path(config).name)
        if overrides:
            layers.merge(overrides, "cli")
        path = layers.get("fmu", "path") or default_fmu_path()
        if model is None:
            model = FmuModel(path, argument=layers.arg("fmu", "path") if layers.origin.get(("fmu", "path")) else "--fmu")
        params = model.defaults()
        for name, value in layers.values["model"].items():
            arg = (f"--set {name}" if layers.origin.get(("model", name)) == "cli"
                   else layers.arg("model", name))
            if name == SOLVER_PARAMETER and layers.origin.get(("model", name)) == "cli":
                arg = "--solver"
            if name == SOLVER_PARAMETER and name not in model.variables:
                # an FMU without the parameter integrates with CVODE: that choice is a no-op
                if str(value).lower() in ("cvode", "0"):
                    continue
                raise HarnessInputError(arg, f"{model.path.name} has no closed-form solver mode (no parameter "
                                        f"{SOLVER_PARAMETER!r}); it integrates with CVODE only")
            params[name] = model.coerce(name, value, arg)
        state = []
        for key in INITIAL_STATE:
            given = layers.get("initial", key)
            if given is None:
                state.append(float(params.get(key, -1.0 if key == "u0" else 0.0)))
            else:
                state.append(_number(layers, "initial", key))
        for key in INITIAL_STATE:
            params.pop(key, None)  # the state travels separately
        return cls(
            fmu_path=str(model.path),
            model=model,
            params=params,
            state0=(state[0], state[1]),
            sampling=SamplingSpec.from_layers(layers),
            run=RunSpec.from_layers(layers),
            layers=layers,
        )

    def sweep_spec(self) -> SweepSpec:
        """The ``[sweep]`` section, validated against this experiment's FMU."""
        return SweepSpec.from_layers(self.layers, self.model)

    def as_attrs(self) -> dict[str, Any]:
        """Flat record of every setting (for the results' attributes)."""
        out: dict[str, Any] = {"fmu_path": self.fmu_path}
        for name, value in self.params.items():
            out[f"model.{name}"] = value
        out["initial.u0"], out["initial.v0"] = self.state0
        for section in ("sampling", "run"):
            for key, value in self.layers.values[section].items():
                out[f"{section}.{key}"] = value
        return out
