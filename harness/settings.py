"""Where settings come from: built-in defaults, TOML experiment files and CLI flags, layered with
the origin of every value so that an error names the flag or file key the user wrote.

Part of the ground of the package (with :mod:`harness.config` and :mod:`harness.errors`): it imports
nothing from the subpackages.
"""
from __future__ import annotations

import copy
import os
import sys
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
        from .errors import ErrorCollector

        found = ErrorCollector()  # every unknown section and key of the layer, not just the first
        for section, entries in layer.items():
            if section not in DEFAULTS:
                found.add(HarnessInputError(
                    f"{source}: [{section}]",
                    f"unknown section; known sections: {', '.join(DEFAULTS)}",
                ))
                continue
            if not isinstance(entries, Mapping):
                found.add(HarnessInputError(f"{source}: {section}", "must be a table"))
                continue
            for key, value in entries.items():
                if section != "model" and key not in DEFAULTS[section]:
                    found.add(HarnessInputError(
                        f"{source}: {section}.{key}",
                        f"unknown key; known keys of [{section}]: {', '.join(DEFAULTS[section])}",
                    ))
                    continue
                if value is None:
                    continue  # "not given": keeps the lower layer
                self.values[section][key] = value
                self.origin[(section, key)] = source
        found.raise_if_any()

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
def check_theta(theta: float, argument: str = "theta") -> float:
    """Return ``theta`` as float if it lies in [0, 1), else raise naming ``argument``."""
    try:
        theta = float(theta)
    except (TypeError, ValueError):
        raise HarnessInputError(argument, f"{theta!r} is not a number") from None
    if not (0.0 <= theta < 1.0):
        raise HarnessInputError(argument, f"the section phase must lie in [0, 1), got {theta}")
    return theta


def check_count(value: Any, argument: str, minimum: int = 0) -> int:
    """Return ``value`` as int if it is an integer >= ``minimum``, else raise."""
    if isinstance(value, bool):
        raise HarnessInputError(argument, f"expected an integer, got {value!r}")
    try:
        as_float = float(value)
    except (TypeError, ValueError):
        raise HarnessInputError(argument, f"expected an integer, got {value!r}") from None
    if not np.isfinite(as_float) or as_float != int(as_float):
        raise HarnessInputError(argument, f"expected a finite integer, got {value!r}")
    n = int(as_float)
    if n < minimum:
        what = "negative" if n < 0 else "too small"
        raise HarnessInputError(argument, f"{what} count {n}; must be >= {minimum}")
    return n


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
    return check_count(layers.get(section, key), layers.arg(section, key), minimum)
