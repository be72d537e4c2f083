"""Command line: ``impact-harness`` / ``python -m harness``.

Subcommands are registered by modules: :mod:`harness.cli.commands` provides simulate, strobe,
sweep and jacobian; further modules listed in :data:`OPTIONAL_COMMAND_MODULES` (e.g. a
later ``harness/reproduce/``) are picked up when they exist.  A command module exposes
``register(subparsers, parents)``, which adds its parser(s) with ``set_defaults(func=...)``;
``func(args)`` returns the exit status.

Exit status: 0 success, 1 the FMU failed during a run, 2 bad input (a one-line message
naming the argument, or quoting the FMU when it refuses the settings at initialization;
also broken FMU binaries, unreadable files, unwritable outputs, runs over the memory or work
limits of :mod:`harness.runs.budget`; never a traceback), 130 interrupted, 143 terminated.
"""
from __future__ import annotations

import argparse
import builtins
import importlib
import os
import shlex
import sys
from typing import Any, Sequence

from ..errors import FmuError, FmuRejectedInput, HarnessInputError, SweepTaskError

PROG = "impact-harness"

#: Command modules always present.
COMMAND_MODULES = ("harness.cli.commands", "harness.cli.basin_command", "harness.cli.continue_command")
#: Command modules added by later issues; skipped while they do not exist.
OPTIONAL_COMMAND_MODULES = ("harness.reproduce",)


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


def common_parent() -> argparse.ArgumentParser:
    """Options shared by every subcommand that runs the FMU."""
    p = OneLineParser(add_help=False)
    g = p.add_argument_group("experiment")
    g.add_argument("--config", "-c", metavar="FILE.toml", help="experiment file (TOML); flags override it")
    g.add_argument("--fmu", dest="fmu__path", metavar="PATH",
                   help="FMU to drive (default: build/fmu/ImpactOscillator.fmu or $IMPACT_HARNESS_FMU)")
    g.add_argument("--set", dest="model_set", metavar="NAME=VALUE", action="append", default=[],
                   help="set an FMU parameter, e.g. --set sigma=0.3 --set wall=rigid (repeatable)")
    g.add_argument("--u0", dest="initial__u0", type=float, metavar="U",
                   help="initial displacement u at the start time t = theta (the section phase, --theta; "
                   "simulate: t = --t0); default: the FMU's start value")
    g.add_argument("--v0", dest="initial__v0", type=float, metavar="V",
                   help="initial velocity v at the start time t = theta (simulate: t = --t0); default: the FMU's start value")
    g.add_argument("--solver", choices=("cvode", "closed-form"),
                   help="the FMU's integrator: cvode (default) or closed-form (exact propagation of the linear "
                   "contact law; an FMU without the parameter 'solver' has CVODE only)")
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
    g.add_argument("--theta", dest="sampling__theta", type=float, metavar="PHASE",
                   help="section phase in [0, 1): samples at t = n + theta (default 0)")
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


def build_parser() -> argparse.ArgumentParser:
    """The full parser, with every registered command module."""
    from ..io.results import project_version

    parser = OneLineParser(
        prog=PROG,
        description="Stroboscopic Poincare maps, bifurcation sweeps and map Jacobians of the "
        "grazing impact oscillator FMU (fmpy; local processes or Dask).",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {project_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=OneLineParser)
    sub.required = True
    parents = {"common": common_parent(), "sampling": sampling_parent()}
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub, parents)
    for name in OPTIONAL_COMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:
                continue  # not written yet
            _warn_plugin(name, exc)
            continue
        except Exception as exc:  # a broken add-on must not take the other commands down
            _warn_plugin(name, exc)
            continue
        module.register(sub, parents)
    return parser


#: Options whose value is a list that may start with a minus sign ("-0.5,0.1").
_LIST_OPTIONS = ("--values", "--state", "--scan", "--range")


def _join_list_values(argv: list[str]) -> list[str]:
    """``--values -0.5,0.1`` -> ``--values=-0.5,0.1``: argparse would take a value starting
    with '-' for an option unless it is a plain negative number."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        a = argv[i]
        nxt = argv[i + 1] if i + 1 < len(argv) else ""
        if a in _LIST_OPTIONS and len(nxt) > 1 and nxt[0] == "-" and (nxt[1].isdigit() or nxt[1] == "."):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


def _warn_plugin(name: str, exc: BaseException) -> None:
    print(f"{PROG}: warning: commands of {name} unavailable ({type(exc).__name__}: {exc})", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``impact-harness``; returns the exit status."""
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    args = parser.parse_args(_join_list_values(argv))
    # recorded in the results' attributes
    args.command_line = " ".join([PROG, *(shlex.quote(a) for a in argv)])
    prog = f"{PROG} {args.command}"
    restore = _terminate_like_interrupt()
    try:
        return int(args.func(args) or 0)
    except Terminated:
        print(f"{prog}: terminated", file=sys.stderr)
        return 143
    except HarnessInputError as exc:
        from .flags import with_flags  # the library names Python arguments; the user typed flags

        print(f"{prog}: error: {with_flags(exc, parser, args.command)}", file=sys.stderr)
        return 2
    except FmuRejectedInput as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    except FmuError as exc:
        print(f"{prog}: FMU failure: {exc}", file=sys.stderr)
        return 1
    except SweepTaskError as exc:
        print(f"{prog}: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130
    except MemoryError:
        print(f"{prog}: error: out of memory (lower the grid, samples or --dt, or --max-memory)", file=sys.stderr)
        return 2
    except OSError as exc:
        if isinstance(exc, BrokenPipeError):
            # stdout closed early (e.g. piped into `head`): the results are written; stay quiet
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 0
        # files the user named (unreadable, unwritable, vanished): one line, not a traceback
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    finally:
        restore()  # the extraction folder goes at exit (harness.io.tempdirs), SIGTERM included


class Terminated(KeyboardInterrupt):
    """SIGTERM, handled like Ctrl-C (workers stopped, checkpoint kept, temp folder removed)."""


def _terminate_like_interrupt() -> Any:
    """Raise :class:`Terminated` on SIGTERM in the main thread; returns the undo function."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return lambda: None

    def handler(signum: int, frame: Any) -> None:
        raise Terminated()

    previous = signal.signal(signal.SIGTERM, handler)
    return lambda: signal.signal(signal.SIGTERM, previous)
