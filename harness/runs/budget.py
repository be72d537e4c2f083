"""Memory and work of a run, estimated from its settings before anything is allocated.

A mistyped count (``--num 1e9``, ``--samples 1e9``, ``--transient 1e12``, ``--dt 1e-9``)
would otherwise grow to gigabytes or run for days before saying anything.  Every command
computes an :class:`Estimate` from plain numbers (grid sizes, periods, output points) and
checks it against a :class:`Budget` first; the refusal is one line naming the estimate,
the limit and the flag that raises it.

Work is counted in *FMU periods* (forcing periods integrated, one ``doStep`` each by
default; about 0.3 ms each at Figure 9's parameters) plus output points for time series.
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from typing import Any

from ..errors import HarnessInputError

#: Default work limit: 1e8 FMU periods, about 8 CPU hours at Figure 9's parameters (the
#: full Figure 9 reproduction needs ~1e6).
DEFAULT_MAX_WORK = 1e8

#: Bytes per stored sample of a sweep or strobe run (u, v, t as float64, impacts as int64).
_SAMPLE_BYTES = 4 * 8
#: Copies of the sample arrays alive at once: per-task results, the assembled grid, and the
#: NetCDF encoder's buffer.
_COPIES = 3
#: Seconds per FMU period used only to put the work limit into words.
_PERIOD_SECONDS = 3e-4


def physical_memory() -> int:
    """Bytes of RAM of this machine (8 GiB if unknown)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - not POSIX
        return 8 << 30


def default_max_memory() -> int:
    """Half the machine's RAM: the run, the plot and the rest of the machine must fit."""
    return physical_memory() // 2


_UNITS = {"": 1, "b": 1, "k": 1 << 10, "m": 1 << 20, "g": 1 << 30, "t": 1 << 40}


def parse_size(text: str) -> int:
    """``"512M"``, ``"8G"``, ``"1.5GiB"``, ``"100000"`` -> bytes (binary units)."""
    m = re.fullmatch(r"\s*([0-9.eE+]+)\s*([kKmMgGtT]?)(?:i?[bB])?\s*", str(text))
    if not m:
        raise ValueError(f"expected a size like 512M or 8G, got {text!r}")
    value = float(m.group(1)) * _UNITS[m.group(2).lower()]
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"expected a positive size, got {text!r}")
    return int(value)


def human_bytes(n: float) -> str:
    """``1.5e9`` -> ``"1.4 GiB"``."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} EiB"  # pragma: no cover


def human_seconds(s: float) -> str:
    """Rough duration in words (``"3 CPU hours"``)."""
    for unit, size in (("CPU years", 3.15e7), ("CPU days", 86400.0), ("CPU hours", 3600.0), ("CPU minutes", 60.0)):
        if s >= size:
            return f"{s / size:.3g} {unit}"
    return f"{s:.2g} CPU s"


@dataclass(frozen=True)
class Estimate:
    """What a run would need: bytes held at once and FMU periods integrated.

    Attributes
    ----------
    memory : float
        Bytes of result arrays alive at the peak.
    work : float
        FMU periods (plus output points of a time series).
    what : str
        The run in words, for the message (``"sweep of 1e+09 points x 340 periods"``).
    argument : str
        The flag to blame (the one that makes the run big).
    """

    memory: float
    work: float
    what: str
    argument: str


@dataclass(frozen=True)
class Budget:
    """Limits a run is checked against (``--max-memory``, ``--max-work``, ``--force``)."""

    max_memory: float
    max_work: float = DEFAULT_MAX_WORK
    force: bool = False

    @classmethod
    def from_args(cls, args: Any) -> "Budget":
        """From the CLI namespace (flags absent: the defaults)."""
        mem = getattr(args, "max_memory", None)
        work = getattr(args, "max_work", None)
        return cls(
            max_memory=default_max_memory() if mem is None else float(mem),
            max_work=DEFAULT_MAX_WORK if work is None else float(work),
            force=bool(getattr(args, "force", False)),
        )

    def check(self, est: Estimate) -> Estimate:
        """Return ``est`` if it fits, else raise one line with the estimate and the way out.

        ``--force`` lifts the work limit only: memory that is not there cannot be forced.
        """
        if est.memory > self.max_memory:
            raise HarnessInputError(
                est.argument,
                f"the {est.what} needs about {human_bytes(est.memory)} of memory, more than the limit "
                f"{human_bytes(self.max_memory)} (half the RAM unless --max-memory SIZE is given)",
            )
        if est.work > self.max_work and not self.force:
            raise HarnessInputError(
                est.argument,
                f"the {est.what} is about {est.work:.3g} FMU periods (~{human_seconds(est.work * _PERIOD_SECONDS)}), "
                f"more than the limit {self.max_work:.3g} (--max-work N, or --force to run it anyway)",
            )
        return est


# ----------------------------------------------------------------------------------------
# Sizes from settings, without building arrays
# ----------------------------------------------------------------------------------------
def grid_count(num: Any, values: Any) -> float:
    """Points of a grid given as ``num`` or an explicit ``values`` list/string (not built).

    Returns a float so that absurd counts (1e300) do not overflow; non-numbers are left
    to the grid's own validation (0 returned).
    """
    if values is not None:
        if isinstance(values, str):
            return float(len(values.replace(",", " ").split()))
        try:
            return float(len(values))
        except TypeError:
            return 0.0
    try:
        n = float(num)
    except (TypeError, ValueError):
        return 0.0
    return n if math.isfinite(n) and n > 0 else 0.0


def sweep_estimate(n_values: float, n_modes: int, n_scan: float, transient: float, samples: float,
                   extend: float, argument: str = "--num") -> Estimate:
    """A sweep or 2D scan: every point runs ``transient + samples`` periods (up to
    ``extend`` more) and stores ``samples`` samples."""
    points = n_values * n_modes * max(n_scan, 1.0)
    periods = transient + samples + extend
    return Estimate(
        memory=_COPIES * _SAMPLE_BYTES * points * samples,
        work=points * periods,
        what=f"sweep of {points:.3g} point(s) x {periods:.3g} periods",
        argument=argument,
    )


#: One period of the batch kernel (the closed form in C, no FMI) in FMU periods of work: about
#: 3 us against about 300 us (BENCHMARKS.md), rounded up.
KERNEL_PERIOD_COST = 0.02


def basin_kernel_estimate(starts: float, transient: float, samples: float, tile: float,
                          argument: str = "--u0-grid") -> Estimate:
    """A basin scan on the batch kernel: every start at most ``transient + samples`` periods of
    the kernel; a tile's samples and the grid's labels held at once."""
    periods = transient + samples
    return Estimate(
        memory=min(tile, starts) * samples * 21.0 + starts * 40.0,
        work=starts * periods * KERNEL_PERIOD_COST,
        what=f"batch-kernel basin scan of {starts:.3g} start(s) x {periods:.3g} periods",
        argument=argument,
    )


def strobe_estimate(transient: float, samples: float, argument: str = "--samples") -> Estimate:
    """One stroboscopic run."""
    return Estimate(memory=_COPIES * _SAMPLE_BYTES * samples, work=transient + samples,
                    what=f"run of {transient + samples:.3g} periods", argument=argument)


def simulate_estimate(t0: float, t_end: float, dt: float, argument: str = "--dt") -> Estimate:
    """A time series: ``(t_end - t0) / dt`` output points (u, v, impacts, t), one doStep each."""
    span = max(t_end - t0, 0.0)
    points = span / dt + 1 if dt > 0 else 1.0
    return Estimate(memory=_COPIES * _SAMPLE_BYTES * points, work=points + span,
                    what=f"time series of {points:.3g} points", argument=argument)


def jacobian_estimate(x_num: float, argument: str = "--x-num") -> Estimate:
    """J(x): per x a central-difference Jacobian (5 one-period runs from t = measure_theta,
    a few periods each)."""
    return Estimate(memory=_COPIES * 8 * 16 * x_num, work=x_num * 5 * 3,
                    what=f"Jacobian scan of {x_num:.3g} states", argument=argument)
