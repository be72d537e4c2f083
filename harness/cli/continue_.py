"""``impact-harness continue``: one-parameter continuation of a periodic orbit of the FMU.

The orbit to start from is either given (``--state U,V`` at t = theta) or found by
:func:`harness.dynamics.attractors.scans.find_attractors` at ``--start`` (up/down/fresh scans).  The
branch is continued both ways (or one, ``--direction``), with flips, folds, Neimark-Sacker points,
grazings and sticking onsets located; ``--switch`` adds the period-2M branch at each flip.
Writes NetCDF (every branch point with its state, multipliers, stability, contacts and event
label; provenance as attributes), a PNG and report.md, and prints the report.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..config import DEFAULT_SOLVER, SOLVERS, solver_name
from ..errors import HarnessInputError
from ..io.progress import progress_bar
from .experiment_args import command_line, experiment_of, output_paths
from .options import count, theta_option

__all__ = ["register", "cmd_continue", "branch_report"]


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add ``continue`` to the CLI."""
    p = sub.add_parser(
        "continue", parents=[parents["common"]], help="continue a periodic orbit in a parameter (branches, bifurcations)",
        description="Pseudo-arclength continuation of a period-M orbit of the stroboscopic map in any FMU parameter, "
        "stable and unstable parts alike, with flip, fold, Neimark-Sacker, grazing and sticking points located.")
    c = p.add_argument_group("continuation")
    c.add_argument("--param", default="sigma", metavar="NAME", help="continued FMU parameter (default sigma)")
    c.add_argument("--range", dest="p_range", required=True, metavar="LO:HI", help="parameter interval of the branch")
    c.add_argument("--start", type=float, required=True, metavar="X", help="parameter value to start from")
    c.add_argument("-M", "--period", dest="M", type=count, metavar="M",
                   help="period of the orbit (default: the shortest attractor found at --start)")
    c.add_argument("--state", metavar="U,V", help="a point of the orbit at t = theta (default: found by scans)")
    theta_option(c)
    c.add_argument("--direction", choices=("both", "up", "down"), default="both", help="which way (default both)")
    c.add_argument("--max-points", type=count, default=200, metavar="N", help="steps per direction (default 200)")
    c.add_argument("--ds-max", type=float, default=0.05, metavar="DS", help="largest arclength step (default 0.05)")
    c.add_argument("--locate-tol", type=float, default=1e-8, metavar="TOL", help="event location width (default 1e-8)")
    c.add_argument("--switch", action="store_true", help="also continue the period-2M branch from every flip")
    c.add_argument("--report", metavar="FILE.md", help="report file (default: next to --out)")
    p.set_defaults(func=cmd_continue)


def _range(text: str) -> tuple[float, float]:
    try:
        lo, hi = (float(x) for x in text.split(":"))
    except ValueError:
        raise HarnessInputError("--range", f"expected LO:HI (two numbers), got {text!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
        raise HarnessInputError("--range", f"needs finite LO < HI, got {text!r}")
    return lo, hi


def _state(text: str) -> np.ndarray:
    try:
        z = np.array([float(x) for x in text.split(",")])
    except ValueError:
        z = np.array([])
    if z.shape != (2,) or not np.all(np.isfinite(z)):
        raise HarnessInputError("--state", f"expected two finite numbers U,V, got {text!r}")
    return z


def _check_args(args: argparse.Namespace, exp: Any) -> tuple[float, float]:
    """The flags the library does not check itself; returns the parameter range."""
    lo, hi = _range(args.p_range)
    if not lo <= args.start <= hi:
        raise HarnessInputError("--start", f"{args.start:g} lies outside --range {args.p_range}")
    if args.param not in exp.model.variables:
        raise HarnessInputError("--param", f"{exp.model.path.name} has no parameter {args.param!r}")
    if args.M is not None and not 1 <= args.M <= 64:
        raise HarnessInputError("-M", f"must be in 1..64, got {args.M}")
    if not 0.0 <= args.theta < 1.0:
        raise HarnessInputError("--theta", f"must lie in [0, 1), got {args.theta}")
    return lo, hi


def _start_orbit(args: argparse.Namespace, sim: Any, params: dict[str, Any]) -> tuple[int, np.ndarray, str]:
    """The period, a point of the orbit to start from and how it was found (for the report):
    ``--state``, or the shortest attractor the scans find at ``--start``."""
    from ..dynamics.attractors.scans import find_attractors

    if args.state is not None:
        if args.M is None:
            raise HarnessInputError("-M", "give the period of the orbit through --state")
        M, z0 = args.M, _state(args.state)
        return M, z0, f"started from the given state ({z0[0]:.6g}, {z0[1]:.6g}) at {args.param} = {args.start:g}"
    scan = find_attractors(sim, params, [args.start], args.param, M_max=args.M or 8, theta=args.theta)
    cands = [a for a in scan.attractors if args.M is None or a.period == args.M]
    scans = ", ".join(scan.scans)
    if not cands:
        raise HarnessInputError("--start", f"no stable period-{args.M or '1..8'} orbit found at {args.param} = "
                                f"{args.start:g} by the scans ({scans}; {scan.transient} periods of transient "
                                "from rest, near the wall and on the wall-free orbit); give --state U,V")
    a = cands[0]
    others = [b.label for b in scan.attractors if b is not a]
    search = (f"started from the attractor {a.label} found at {args.param} = {args.start:g} by {', '.join(a.found_by)}"
              + (f" (also found there: {', '.join(others)})" if others else ""))
    return a.period, a.points[0], search


def _branches(args: argparse.Namespace, sim: Any, params: dict[str, Any], M: int, z0: np.ndarray,
              p_range: tuple[float, float]) -> tuple[list[Any], list[str]]:
    """The branch continued each way asked, and with ``--switch`` the period-2M branch at every
    flip; returns the branches and what each is (for the dataset and the report)."""
    from ..dynamics.continuation.continue_orbit import continue_orbit, switch_at_flip

    dirs = {"both": (-1.0, 1.0), "up": (1.0,), "down": (-1.0,)}[args.direction]
    branches, kinds = [], []
    with progress_bar(total=args.max_points * len(dirs), desc="continue", unit="step",
                      disable=args.no_progress) as bar:
        for d in dirs:
            br = continue_orbit(sim, params, M, args.start, z0, args.param, p_range, d, ds_max=args.ds_max,
                                max_points=args.max_points, theta=args.theta, locate_tol=args.locate_tol, progress=bar)
            branches.append(br)
            kinds.append("up" if d > 0 else "down")
        if args.switch:
            for br in list(branches):
                for e in [e for e in br.events if e.kind == "flip"]:
                    sw = switch_at_flip(sim, params, br, e, p_range=p_range, max_points=args.max_points,
                                        locate_tol=args.locate_tol, ds_max=args.ds_max)
                    if sw is not None:
                        branches.append(sw)
                        kinds.append(f"period {2 * M} from the flip at {e.value:.10g}")
                    else:
                        e.note = f"no period-{2 * M} orbit found next to it (branch switching tried on both sides)"
    return branches, kinds


def cmd_continue(args: argparse.Namespace) -> int:
    """``continue``: branches, NetCDF, plot, report."""
    from ..dynamics.continuation.branch import branches_dataset
    from ..fmu.simulator import FmuSimulator
    from ..io.results import provenance, write_netcdf

    exp = experiment_of(args)
    lo, hi = _check_args(args, exp)
    out, plot = output_paths(args, exp, "continue")
    report_path = Path(args.report) if args.report else out.with_suffix(".md")
    t0 = time.perf_counter()
    sim = FmuSimulator(exp.model.source())
    params = dict(exp.params)
    M, z0, search = _start_orbit(args, sim, params)
    branches, kinds = _branches(args, sim, params, M, z0, (lo, hi))
    settings = {**exp.as_attrs(), "continue.param": args.param, "continue.range": [lo, hi],
                "continue.start": args.start, "continue.M": M, "continue.theta": args.theta, "continue.search": search}
    attrs = provenance(settings, exp.model, "serial", time.perf_counter() - t0, command_line(args))
    ds = branches_dataset(branches, kinds, attrs)
    write_netcdf(ds, out)
    from ..io.plots import parameter_title

    title = f"{parameter_title(ds.attrs, (args.param,))}: continuation in {args.param}"
    text = branch_report(branches, kinds, title, search, command_line(args), params, (lo, hi))
    try:
        report_path.write_text(text)
    except OSError as exc:
        raise HarnessInputError("--report", f"cannot write {report_path}: {exc.strerror}") from None
    print(text)
    print(f"wrote {out}, {report_path}")
    if plot:
        from ..io.branch_plot import branch_figure

        print(f"plot: {branch_figure(branches, plot, title)}")
    short = [br for br in branches if _budget_spent(br, (lo, hi))]
    if short:  # a result, but not of the whole range asked for: say so in the exit status too
        print(f"{len(short)} branch(es) stopped on the point budget short of --range: raise --max-points "
              f"(now {args.max_points}); exit status {INCOMPLETE}")
        return INCOMPLETE
    return 0


#: Exit status of a run that wrote its results but did not cover what was asked (main's table).
INCOMPLETE = 3


def _budget_spent(br: Any, p_range: tuple[float, float]) -> bool:
    """The branch ended because its point budget was spent, inside the range (not at its end)."""
    end = br.events[-1] if br.events else None
    return bool(end is not None and end.kind == "end" and end.note.endswith("steps done")
                and p_range[0] < br.values[-1] < p_range[1])


def _mu(m: Sequence[complex]) -> str:
    return ", ".join(f"{z.real:.4g}{z.imag:+.3g}i" if abs(z.imag) > 1e-9 else f"{z.real:.4g}" for z in m)


def branch_report(branches: Sequence[Any], kinds: Sequence[str], title: str, search: str, command: str,
                  params: dict, p_range: tuple[float, float] | None = None) -> str:
    """The branches as Markdown: search, stable intervals, located events."""
    solver = solver_name(params.get("solver", SOLVERS[DEFAULT_SOLVER]))
    lines = [f"# Continuation: {title}", "", f"Command: `{command}`", "",
             f"FMU solver: {solver}; derivatives: {branches[0].derivatives if branches else '?'}; {search}.", ""]
    for br, kind in zip(branches, kinds):
        end = br.events[-1].note if br.events and br.events[-1].kind == "end" else "?"
        short = p_range is not None and _budget_spent(br, p_range)
        lines += [f"## Branch of period {br.M} ({kind}): {len(br)} points, {br.param} from "
                  f"{br.values[0]:.8g} to {br.values[-1]:.8g}, {br.periods_run} FMU periods; ended: {end}"
                  + (f" -- **short of the range [{p_range[0]:g}, {p_range[1]:g}]: the point budget ran out "
                     "(raise --max-points)**" if short and p_range else ""), ""]
        iv = br.stable_intervals()
        if iv:
            lines.append("Stable parts (" + br.param + " from the first to the last stable point computed):")
            lines += [f"- {a:.8g} .. {b:.8g}, {n} impact(s) per period {br.M}" for a, b, n in iv]
        else:
            lines.append("No stable point on this branch.")
        lines += ["", "| event | " + br.param + " | bracket | multipliers | note |", "|---|---|---|---|---|"]
        lines += [f"| {e.kind} | {e.value:.10g} | {e.bracket:.2g} | {_mu(e.multipliers)} | {e.note} |" for e in br.events]
        lines.append("")
    return "\n".join(lines)
