"""The command line's argument helpers: the parser class with one-line errors, the argparse types
of counts, sizes and positive numbers, the option groups shared by the subcommands, and the CLI
flags as a settings layer (:func:`overrides_from_args`, read by :mod:`harness.config`)."""
from __future__ import annotations

import argparse
import builtins
from typing import Any

from ..config.defaults import DEFAULT_SOLVER, MODEL_SHORTCUTS, SECTION_PHASE, SOLVERS, WALLS
from ..errors import HarnessInputError

__all__ = ["OneLineParser", "count", "size", "positive", "common_parent", "sampling_parent", "execution_options",
           "experiment_options",
           "overrides_from_args", "model_shortcuts", "solver_option", "theta_option", "SOLVER_HELP", "THETA_HELP"]

#: --help of the shared defaults, written once (harness/config/defaults.py holds the values).
SOLVER_HELP = (f"the FMU's integrator: {DEFAULT_SOLVER} (default, every command; every FMU and contact law) or "
               "closed-form (the exact flow of the linear contact law, ~30x faster)")
THETA_HELP = (f"section phase in [0, 1): samples at t = n + theta (default {SECTION_PHASE:g}, every command: half a "
              "period from the impacts of near-grazing orbits, where the stroboscopic map is smooth)")


class OneLineParser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line (no usage dump), exit status 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def count(text: str) -> int:
    """argparse type of counts: an integer, also written like ``1e9`` (so that a huge count
    reaches the memory and work check and is refused with an estimate, not as a typo)."""
    try:
        return builtins.int(text)
    except ValueError:
        value = float(text)  # ValueError -> argparse's "invalid int value"
        if not value.is_integer():
            raise
        return builtins.int(value)


count.__name__ = "int"  # argparse names the type in its message: "invalid int value: 'abc'"


def size(text: str) -> int:
    """argparse type of memory sizes (``512M``, ``8G``)."""
    from ..runs.budget import parse_size

    return parse_size(text)


def positive(text: str) -> float:
    """argparse type of a finite number > 0."""
    value = float(text)
    if not (0 < value < float("inf")):
        raise ValueError(text)
    return value


positive.__name__ = "positive number"


def experiment_options(p: argparse.ArgumentParser, model_flags: bool = True) -> Any:
    """The layers every command builds its run from, the same options in each: ``--config`` (an
    experiment file), ``--fmu``, ``--set``, ``--solver`` and (``model_flags``) the oscillator's
    flags; returns their group."""
    g = p.add_argument_group("experiment")
    g.add_argument("--config", "-c", metavar="FILE.toml", help="experiment file (TOML); flags override it")
    g.add_argument("--fmu", dest="fmu__path", metavar="PATH",
                   help="FMU to drive (default: build/fmu/ImpactOscillator.fmu or $IMPACT_HARNESS_FMU)")
    g.add_argument("--set", dest="model_set", metavar="NAME=VALUE", action="append", default=[],
                   help="set an FMU parameter, e.g. --set sigma=0.3 --set wall=rigid (repeatable)")
    solver_option(g, default=None)  # None: the settings' layers supply it (DEFAULT_SOLVER)
    if model_flags:
        model_shortcuts(p, "model__")
    return g


def common_parent() -> argparse.ArgumentParser:
    """Options shared by every subcommand that runs the FMU."""
    p = OneLineParser(add_help=False)
    g = experiment_options(p)
    g.add_argument("--u0", dest="initial__u0", type=float, metavar="U",
                   help="initial displacement u at the start time t = theta (the section phase, --theta; "
                   "simulate: t = --t0); default: the FMU's start value")
    g.add_argument("--v0", dest="initial__v0", type=float, metavar="V",
                   help="initial velocity v at the start time t = theta (simulate: t = --t0); default: the FMU's start value")
    o = p.add_argument_group("output")
    o.add_argument("--out", "-o", dest="run__out", metavar="FILE.nc", help="NetCDF result file")
    o.add_argument("--plot", dest="run__plot", metavar="FILE.png", help="PNG plot (default: next to --out)")
    o.add_argument("--no-plot", action="store_true", help="do not draw a plot")
    o.add_argument("--no-progress", action="store_true", help="no progress bar")
    b = p.add_argument_group("limits (checked before anything is allocated or run)")
    b.add_argument("--max-memory", type=size, metavar="SIZE",
                   help="largest memory a run may plan for, e.g. 2G (default: half the RAM)")
    b.add_argument("--max-work", type=positive, metavar="N",
                   help="largest number of FMU periods a run may integrate (default 1e8, ~8 CPU hours)")
    b.add_argument("--force", action="store_true", help="run even beyond --max-work")
    return p


def sampling_parent() -> argparse.ArgumentParser:
    """Options of stroboscopic sampling (strobe, sweep)."""
    p = OneLineParser(add_help=False)
    g = p.add_argument_group("stroboscopic sampling")
    theta_option(g, "sampling__theta", default=None)
    g.add_argument("--transient", dest="sampling__transient", type=count, metavar="N",
                   help="periods discarded before sampling (default 300)")
    g.add_argument("--samples", dest="sampling__samples", type=count, metavar="N",
                   help="periods sampled (default 40)")
    g.add_argument("--tol", dest="sampling__tol", type=float, metavar="TOL", help="periodicity tolerance, relative (default 1e-5)")
    g.add_argument("--max-period", dest="sampling__max_period", type=count, metavar="M",
                   help="largest period tried (default samples/2)")
    g.add_argument("--extend", dest="sampling__extend", type=count, metavar="N",
                   help="sweeps: up to N more periods for points not yet periodic (slow convergence "
                   "near window edges; default 0)")
    g.add_argument("--lyapunov", dest="sampling__lyapunov", type=count, metavar="N",
                   help="Lyapunov exponents of the stroboscopic map over N periods after the samples, with "
                   "their uncertainty, and the classification periodic / quasi-periodic / chaotic / not "
                   "converged (exact with an FMU that reports its derivatives, else by differences at ~5x "
                   "the cost; default 0: none)")
    return p


def overrides_from_args(args: argparse.Namespace) -> dict[str, dict[str, Any]]:
    """CLI flags as a ``{section: {key: value}}`` layer (flags not given are absent)."""
    layer: dict[str, dict[str, Any]] = {}
    for dest, value in vars(args).items():
        if "__" in dest and value is not None:
            section, key = dest.split("__", 1)
            layer.setdefault(section, {})[key] = value
    for item in getattr(args, "model_set", []) or []:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise HarnessInputError("--set", f"expected NAME=VALUE, got {item!r}")
        layer.setdefault("model", {})[name.strip()] = value.strip()
    if getattr(args, "solver", None):
        layer.setdefault("model", {})["solver"] = args.solver
    if getattr(args, "no_progress", False):
        layer.setdefault("run", {})["progress"] = False
    return layer


def execution_options(p: argparse.ArgumentParser, what: str) -> None:
    """Where a grid of runs executes, and its checkpoint (sweep, basins)."""
    b = p.add_argument_group("execution")
    b.add_argument("--backend", dest="run__backend", choices=["serial", "processes", "dask"],
                   help="where to run (default processes, or dask with --scheduler)")
    b.add_argument("--workers", "-j", dest="run__workers", type=count, metavar="N",
                   help="local worker processes (default: all cores)")
    b.add_argument("--scheduler", dest="run__scheduler", metavar="tcp://HOST:PORT", help="run on this Dask scheduler")
    b.add_argument("--checkpoint", dest="run__checkpoint", metavar="DIR",
                   help=f"directory of finished points, to resume an interrupted {what} (default: OUT.partial)")
    b.add_argument("--no-resume", action="store_true", help="discard an existing checkpoint and start over")


def xtol_option(g: Any, default_text: str) -> None:
    """``--xtol``: the march-and-bisection fallback's absolute tolerance (``windows``, ``chart``); the
    edges the continuation locates do not depend on it (one wording for both commands)."""
    g.add_argument("--xtol", type=positive, metavar="DS",
                   help="absolute tolerance, in sigma, of the march-and-bisection fallback, used only for an edge "
                   "the continuation could not locate ('located' in the JSON says which); edges located by the "
                   "continuation are located to 1e-9 (flips, folds) or within an interval of ~1e-8 (grazes) "
                   f"whatever this is, with --quick too (default: {default_text})")


def solver_option(g: Any, default: str | None = None) -> None:
    """``--solver``: the same choices, default and help in every command (``default`` None: the
    settings' layers supply it, :data:`~harness.config.DEFAULT_SOLVER`)."""
    g.add_argument("--solver", choices=tuple(SOLVERS), default=default, help=SOLVER_HELP)


def theta_option(g: Any, dest: str = "theta", default: float | None = SECTION_PHASE) -> None:
    """``--theta``: the section phase, the same default and help in every command (``default``
    None: the settings' layers supply it, from the same constant)."""
    g.add_argument("--theta", dest=dest, type=float, default=default, metavar="PHASE", help=THETA_HELP)


def model_shortcuts(p: argparse.ArgumentParser, prefix: str = "", defaults: dict[str, Any] | None = None,
                    walls: tuple[str, ...] = tuple(WALLS)) -> None:
    """The oscillator's flags (``--nu --Omega --r --Gamma --wall``), the same in every command:
    shortcuts for ``--set NAME=VALUE``; ``prefix`` is put before each dest (``model__``: a
    settings layer), ``defaults`` are the command's own (stated in the help)."""
    defaults = defaults or {}
    g = p.add_argument_group("oscillator (shortcuts for --set NAME=VALUE)")
    for name, what in MODEL_SHORTCUTS.items():
        d = defaults.get(name)
        g.add_argument(f"--{name}", dest=f"{prefix}{name}", type=float, default=d, metavar="X",
                       help=what + (f" (default {d:g})" if d is not None else ""))
    d = defaults.get("wall")
    g.add_argument("--wall", dest=f"{prefix}wall", choices=walls, default=d,
                   help="wall model" + (f" (default {d})" if d is not None else ""))
