"""Checks of single values: a section phase, a count, a finite number; the errors name the
argument (a Python argument, a flag or a file key)."""
from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import HarnessInputError
from .layers import Layered

__all__ = ["check_theta", "check_count"]


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
