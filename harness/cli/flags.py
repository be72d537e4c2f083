"""The command line's names for the library's arguments.

The library (dynamics/, runs/) raises :class:`~harness.errors.HarnessInputError` naming the
Python argument (``p_range``, ``z0``, ``M_max``), so that a Python caller reads its own names.
The CLI prints the flag that set it (``--range``, ``--start``, ``--M-max``): it looks the name up
among the command's own options, by their ``dest``.  A dest is the argument's name, or, for the
options that mirror a section of the experiment file, ``<section>__<name>`` (``run__scheduler``).
Where the two names differ otherwise, :data:`ALIASES` says which option sets the argument.
"""
from __future__ import annotations

import argparse

from ..errors import HarnessInputError, SettingsErrors

__all__ = ["ALIASES", "flag_for", "with_flags", "command_parser"]

#: Python argument -> the dest (or the name after ``<section>__``) of the option that sets it,
#: where the names differ.
ALIASES = {
    "p0": "start",          # continue_orbit's start value: --start
    "z0": "start",          # its orbit guess, found at --start (or given by --state)
    "spec.param": "param",  # run_sweep's SweepSpec fields
    "spec.scan_param": "scan",
    "spec.modes": "mode",
    "x": "x_num",           # the Jacobian scan's values of x: --x-start/--x-stop/--x-num
    "fmu_path": "path",     # compare_windows, chart, run_target: --fmu (fmu__path)
}


def command_parser(parser: argparse.ArgumentParser, command: str) -> argparse.ArgumentParser | None:
    """The parser of the subcommand ``command``."""
    for action in parser._actions:  # argparse keeps its subparsers only here
        if isinstance(action, argparse._SubParsersAction):
            return action.choices.get(command)
    return None


def flag_for(parser: argparse.ArgumentParser, command: str, name: str) -> str | None:
    """The option of ``command`` that sets the Python argument ``name`` (its first spelling,
    e.g. ``-M`` for ``-M/--period``), or None when the command has none (then the name stays)."""
    sub = command_parser(parser, command)
    if sub is None or name.startswith("-"):
        return None
    dest = ALIASES.get(name, name)
    options = [a for a in sub._actions if a.option_strings]
    for match in (lambda d: d == dest, lambda d: d.endswith("__" + dest)):
        found = [a for a in options if match(a.dest)]
        if len(found) == 1:
            return found[0].option_strings[0]
    return None


def with_flags(exc: HarnessInputError, parser: argparse.ArgumentParser, command: str) -> HarnessInputError:
    """``exc`` with each argument it names replaced by the flag of ``command`` that sets it."""
    if isinstance(exc, SettingsErrors):
        return SettingsErrors([with_flags(e, parser, command) for e in exc.errors])
    flag = flag_for(parser, command, exc.argument)
    if flag is None:
        return exc
    cls, args = exc.__reduce__()[:2]  # every HarnessInputError pickles as (argument, reason, ...)
    return cls(flag, *args[1:])
