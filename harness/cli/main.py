"""Command line: ``impact-harness`` / ``python -m harness``.

One module per subcommand (:data:`COMMANDS`, in the order ``--help`` lists them); each exposes
``register(subparsers, parents)``, which adds its parser with ``set_defaults(func=...)``;
``func(args)`` returns the exit status.  The option groups they share are in :mod:`.options`.

Exit status: 0 success, 1 the FMU failed during a run, 2 bad input (a one-line message
naming the argument, or quoting the FMU when it refuses the settings at initialization;
also broken FMU binaries, unreadable files, unwritable outputs, runs over the memory or work
limits of :mod:`harness.runs.budget`; never a traceback), 3 results written but short of what was
asked (``continue``: a branch stopped on its point budget inside ``--range``), 130 interrupted,
143 terminated.
"""
from __future__ import annotations

import argparse
import os
import sys
from typing import Any, Sequence

from ..errors import FmuError, FmuRejectedInput, HarnessInputError, SweepTaskError
from . import atlas, basins, chart, continue_, jacobian, reproduce, simulate, strobe, sweep, windows
from .experiment_args import PROG, recorded_command
from .flags import command_parser, with_flags
from .options import OneLineParser, common_parent, sampling_parent

#: The subcommands' modules, in the order ``--help`` lists them.
COMMANDS = (simulate, strobe, sweep, jacobian, basins, continue_, reproduce, windows, chart, atlas)


def build_parser() -> argparse.ArgumentParser:
    """The full parser, with every subcommand."""
    from ..io.versions import project_version

    parser = OneLineParser(
        prog=PROG,
        description="Stroboscopic Poincare maps, bifurcation sweeps and map Jacobians of the "
        "grazing impact oscillator FMU (fmpy; local processes or Dask).",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {project_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=OneLineParser)
    sub.required = True
    parents = {"common": common_parent(), "sampling": sampling_parent()}
    for command in COMMANDS:
        command.register(sub, parents)
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


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``impact-harness``; returns the exit status."""
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    args = parser.parse_args(_join_list_values(argv))
    prog = f"{PROG} {args.command}"
    restore = _terminate_like_interrupt()
    try:
        # recorded in the results (attributes, reports), the same way for every command
        args.command_line = recorded_command(command_parser(parser, args.command), args, argv)
        return int(args.func(args) or 0)
    except BaseException as exc:  # every exit of a command passes through one mapping to a status
        return exit_status(exc, prog, parser, args.command)
    finally:
        restore()  # the extraction folder goes at exit (harness.io.tempdirs), SIGTERM included


def exit_status(exc: BaseException, prog: str, parser: argparse.ArgumentParser | None = None,
                command: str | None = None) -> int:
    """Report what stopped the command ``prog`` on stderr (one line, no traceback) and return
    its exit status; re-raise what is not the command's to report (a bug: its traceback).
    With the ``parser`` and the ``command``, a library error's Python argument is shown as the
    command's flag."""
    if isinstance(exc, Terminated):
        print(f"{prog}: terminated", file=sys.stderr)
        return 143
    if isinstance(exc, HarnessInputError) and parser is not None and command is not None:
        exc = with_flags(exc, parser, command)  # the library names Python arguments; the user typed flags
    if isinstance(exc, (HarnessInputError, FmuRejectedInput)):
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    if isinstance(exc, FmuError):
        print(f"{prog}: FMU failure: {exc}", file=sys.stderr)
        return 1
    if isinstance(exc, SweepTaskError):
        print(f"{prog}: {exc}", file=sys.stderr)
        return 1
    if isinstance(exc, KeyboardInterrupt):
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130
    if isinstance(exc, MemoryError):
        print(f"{prog}: error: out of memory (lower the grid, samples or --dt, or --max-memory)", file=sys.stderr)
        return 2
    if isinstance(exc, BrokenPipeError):
        # stdout closed early (e.g. piped into `head`): the results are written; stay quiet
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    if isinstance(exc, OSError):
        # files the user named (unreadable, unwritable, vanished): one line, not a traceback
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    raise exc


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
