"""From parsed arguments to a run: the :class:`~harness.runs.experiment.Experiment` (defaults <
TOML < flags), its output files checked writable before any work, and the command line recorded
in the results (:func:`recorded_command`: one way for every command)."""
from __future__ import annotations

import argparse
import shlex
from pathlib import Path
from typing import Any, Iterator

from ..config import load_toml, solver_name, wall_name
from ..io.outputs import check_output, check_plot
from ..runs.experiment import Experiment
from .options import overrides_from_args

__all__ = ["experiment_of", "output_paths", "command_line", "recorded_command", "finite"]

PROG = "impact-harness"

#: Settings of an experiment file that a flag of another shape carries (its dest): ``--scan
#: NAME=V1,V2`` holds both keys of a second sweep axis.
SHAPED_FLAGS = {("sweep", "scan_param"): "scan", ("sweep", "scan_values"): "scan"}


def experiment_of(args: argparse.Namespace, extra: dict[str, dict[str, Any]] | None = None) -> Experiment:
    """The experiment of a command: defaults < ``--config`` file < flags (and ``extra`` flags of its own)."""
    layer = overrides_from_args(args)
    for section, entries in (extra or {}).items():
        layer.setdefault(section, {}).update(entries)
    return Experiment.from_sources(getattr(args, "config", None), layer)


def output_paths(args: argparse.Namespace, exp: Experiment, default_stem: str) -> tuple[Path, Path | None]:
    """The result and plot files, checked writable before any work is done."""
    out = check_output(exp.run.out or f"results/{default_stem}.nc", exp.layers.arg("run", "out"))
    if args.no_plot:
        return out, None
    origin = exp.layers.origin
    # a file's plot path goes with that file's result path: with --out on the command line and
    # the plot only in the file (another command's, say), the plot goes next to --out
    if exp.run.plot and not (origin.get(("run", "out")) == "cli" and origin.get(("run", "plot")) != "cli"):
        return out, check_plot(exp.run.plot, exp.layers.arg("run", "plot"))
    return out, check_plot(out.with_suffix(".png"), "--out")  # OUT.png may be a directory


def command_line(args: argparse.Namespace) -> str:
    """The command line of this run, as :func:`recorded_command` wrote it (``main`` records it)."""
    return args.command_line


def recorded_command(sub: argparse.ArgumentParser, args: argparse.Namespace, argv: list[str]) -> str:
    """The command line recorded with every command's results, written one way: what was typed,
    with ``--config FILE`` written out as the flags of the command that its settings stand for (a
    file read again later may have changed); ``--config`` stays only where one of the file's
    settings the command takes has no flag of its own (``[sweep] scan_values``).  Settings the
    command does not take (another command's sections) are left out."""
    config = getattr(args, "config", None)
    if not config:
        return " ".join([PROG, *(shlex.quote(a) for a in argv)])
    written, needs_file = _file_flags(sub, args, load_toml(config))
    out: list[str] = []
    skip = False
    for i, a in enumerate(argv):
        if skip:
            skip = False
            continue
        if a in ("--config", "-c") or a.startswith("--config="):
            skip = "=" not in a
            if needs_file:
                out += [a] if "=" in a else [a, argv[i + 1]]
            out += written
            continue
        out.append(a)
    return " ".join([PROG, *(shlex.quote(a) for a in out)])


def _file_flags(sub: argparse.ArgumentParser, args: argparse.Namespace,
                data: dict[str, Any]) -> tuple[list[str], bool]:
    """The file's settings as the command's flags (those not typed as well), and whether a
    setting the command takes has no flag to be written as."""
    by_dest = {a.dest: a for a in sub._actions if a.option_strings}
    typed_set = {item.partition("=")[0].strip() for item in getattr(args, "model_set", []) or []}

    written: list[str] = []
    needs_file = False
    for section, key, value in _entries(data):
        action = by_dest.get(f"{section}__{key}")
        if section == "model" and key == "solver" and "solver" in by_dest:
            action = by_dest["solver"]
        if section == "model" and key in typed_set:
            continue  # --set NAME=VALUE typed: it wins over the file
        if action is not None:
            if getattr(args, action.dest, None) is None:
                written += _option(max(action.option_strings, key=len), _text(key, value))
        elif section == "model" and "model_set" in by_dest:
            written += _option("--set", f"{key}={_text(key, value)}")
        elif SHAPED_FLAGS.get((section, key)) in by_dest:
            needs_file = True  # the command takes it, through a flag of another shape (--scan)
    return written, needs_file


def _entries(data: dict[str, Any]) -> Iterator[tuple[str, str, Any]]:
    for section, entries in data.items():
        if isinstance(entries, dict):
            for key, value in entries.items():
                yield section, key, value


def _text(key: str, value: Any) -> str:
    """A file's value as its flag takes it: enums by name, numbers in full, lists comma-joined."""
    if key == "wall":
        return wall_name(value) if not isinstance(value, str) else value
    if key == "solver":
        return solver_name(value) if not isinstance(value, str) else value
    if isinstance(value, (list, tuple)):
        return ",".join(_text("", v) for v in value)
    if isinstance(value, bool):
        return str(value).lower()
    return repr(value) if isinstance(value, float) else str(value)


def _option(flag: str, text: str) -> list[str]:
    """``[flag, text]``, or ``[flag=text]`` where the value starts with a minus sign."""
    return [f"{flag}={text}"] if text.startswith("-") else [flag, text]


def finite(layers: Any, section: str, key: str) -> float:
    """A finite number from the settings, or a one-line error naming the flag or file key."""
    from ..config import _number

    return _number(layers, section, key)
