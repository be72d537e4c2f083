"""``impact-harness reproduce FIG --out DIR [--quick]``: one of the paper's figures
(:mod:`harness.reproduce`), map vs FMU, with a report."""
from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from ..errors import HarnessInputError
from ..reproduce import TARGETS, run_target

__all__ = ["register", "cmd_reproduce"]


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add the ``reproduce`` subcommand."""
    p = sub.add_parser(
        "reproduce", help="reproduce a figure of the paper: FMU vs maps, with a report",
        description="Run the FMU sweeps / shooting / Jacobians and the maps for one of the paper's figures, "
        "compare them, and write PNG figures, FIG.json and report.md into --out.")
    p.add_argument("figure", metavar="FIG", choices=sorted(TARGETS),
                   help="one of: " + ", ".join(TARGETS))
    p.add_argument("--out", "-o", metavar="DIR", help="output directory (default results/FIG)")
    p.add_argument("--quick", action="store_true", help="coarse version (under a minute on 2 cores)")
    p.add_argument("--workers", "-j", type=int, metavar="N", help="local worker processes for sweeps (default: all cores)")
    p.add_argument("--fmu", metavar="PATH", help="FMU (default build/fmu/ImpactOscillator.fmu)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--solver", choices=("cvode", "closed-form"), default="cvode",
                   help="the FMU's integrator (default cvode: the paper's question is about the ODE as a general "
                   "integrator solves it; closed-form: exact propagation, linear contact law)")
    p.set_defaults(func=cmd_reproduce)


def cmd_reproduce(args: argparse.Namespace) -> int:
    if args.workers is not None and args.workers < 1:
        raise HarnessInputError("--workers", f"must be >= 1, got {args.workers}")
    out = args.out or f"results/{args.figure}"
    t0 = time.perf_counter()
    result = run_target(args.figure, out, args.quick, args.workers, not args.no_progress, args.fmu,
                        getattr(args, "solver", "cvode"))
    verdict = result.get("verdict", "")
    print(f"{args.figure}: {verdict}")
    print(f"wrote {Path(out) / 'report.md'} and {Path(out) / (args.figure + '.json')} "
          f"({time.perf_counter() - t0:.1f} s)")
    return 0
