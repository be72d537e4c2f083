"""From parsed arguments to a run: the :class:`~harness.runs.experiment.Experiment` (defaults <
TOML < flags), its output files checked writable before any work, and the command line recorded
in the results."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from ..io.outputs import check_output, check_plot
from ..runs.experiment import Experiment
from .options import overrides_from_args

__all__ = ["experiment_of", "output_paths", "command_line", "finite"]


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


def command_line(args: argparse.Namespace | None = None) -> str:
    """The ``impact-harness`` command line of this run (recorded in the results' attributes)."""
    line = getattr(args, "command_line", None)
    return line if line else " ".join(["impact-harness", *sys.argv[1:]])


def finite(layers: Any, section: str, key: str) -> float:
    """A finite number from the settings, or a one-line error naming the flag or file key."""
    from ..config import _number

    return _number(layers, section, key)
