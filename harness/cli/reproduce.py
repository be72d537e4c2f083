"""``impact-harness reproduce FIG --out DIR [--quick]``: one of the paper's figures
(:mod:`harness.reproduce`), map vs FMU, with a report.

The run comes from the same layers as every command (the FMU's start values < ``--config``
file < flags and ``--set``: the FMU, the solver, any FMU parameter the figure does not set
itself); the figure's own parameters win over them."""
from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from ..reproduce import TARGETS, run_target
from .experiment_args import command_line, experiment_of
from .options import count, experiment_options

__all__ = ["register", "cmd_reproduce"]


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add the ``reproduce`` subcommand."""
    p = sub.add_parser(
        "reproduce", help="reproduce a figure of the paper: FMU vs maps, with a report",
        description="Run the FMU sweeps / shooting / Jacobians and the maps for one of the paper's figures, "
        "compare them, and write PNG figures, FIG.json and report.md into --out. The figure sets its own "
        "oscillator; --config, --set and --solver set the rest of the run (e.g. --solver closed-form).")
    p.add_argument("figure", metavar="FIG", choices=sorted(TARGETS),
                   help="one of: " + ", ".join(TARGETS))
    experiment_options(p, model_flags=False)
    p.add_argument("--out", "-o", metavar="DIR", help="output directory (default results/FIG)")
    p.add_argument("--quick", action="store_true", help="coarse version (under a minute on 2 cores)")
    p.add_argument("--workers", "-j", dest="run__workers", type=count, metavar="N",
                   help="local worker processes for sweeps (default: all cores)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func=cmd_reproduce)


def cmd_reproduce(args: argparse.Namespace) -> int:
    run = experiment_of(args)
    out = args.out or f"results/{args.figure}"
    t0 = time.perf_counter()
    result = run_target(args.figure, out, args.quick, run=run, command=command_line(args))
    verdict = result.get("verdict", "")
    print(f"{args.figure}: {verdict}")
    print(f"wrote {Path(out) / 'report.md'} and {Path(out) / (args.figure + '.json')} "
          f"({time.perf_counter() - t0:.1f} s)")
    return 0
