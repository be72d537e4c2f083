"""The coordinate s in which sigma is continued along a curve in (sigma, p2).

Far above grazing the edges of the windows spread over decades of sigma, so the curves are
followed in s = ln sigma (steps of one size in every decade).  Below grazing sigma reaches 0 and
negative values (sigma > -1 always: the wall-free orbit's amplitude is 1 + sigma), where ln sigma
does not exist; there s = sigma.  :func:`sigma_axis` picks the log axis whenever the searched range
is positive, so that every positive-range computation is the same, number for number, as on a
log axis alone.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["SigmaAxis", "sigma_axis", "LOG", "LINEAR"]


@dataclass(frozen=True)
class SigmaAxis:
    """s = ln sigma (``log``) or s = sigma.

    Attributes
    ----------
    log : bool
        True: s = ln sigma (sigma > 0 only).
    """

    log: bool

    def to(self, sigma: float) -> float:
        """s of ``sigma``."""
        return math.log(sigma) if self.log else float(sigma)

    def of(self, s: float) -> float:
        """sigma at ``s``."""
        return math.exp(s) if self.log else float(s)

    def dsigma_ds(self, s: float) -> float:
        """d sigma / d s at ``s`` (sigma itself on the log axis)."""
        return math.exp(s) if self.log else 1.0

    def of_array(self, s: np.ndarray) -> np.ndarray:
        """sigma at each of ``s`` (numpy's exp on the log axis, as the curves always used)."""
        return np.exp(s) if self.log else np.asarray(s, dtype=float)


LOG = SigmaAxis(True)
LINEAR = SigmaAxis(False)


def sigma_axis(sigma_range: tuple[float, float]) -> SigmaAxis:
    """The log axis where the whole range is above grazing (sigma > 0), else the linear one."""
    return LOG if float(sigma_range[0]) > 0 else LINEAR
