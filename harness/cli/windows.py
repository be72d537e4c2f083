"""``impact-harness windows``: the window edges of the maps vs the ODE for any parameter set
(:func:`harness.analysis.windows.compare_windows.compare_windows`)."""
from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from mapcheck.compare import markdown_window_table

from ..analysis.windows.compare_windows import compare_windows
from ..analysis.windows.problem import MAP_WALLS
from ..config import wall_name
from .experiment_args import command_line, experiment_of
from .options import count, experiment_options, theta_option, xtol_option

__all__ = ["register", "cmd_windows"]


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add the ``windows`` subcommand."""
    p = sub.add_parser(
        "windows", help="window edges of the maps vs the ODE (FMU) for any parameter set, with a report",
        description="For (alpha, gamma) or (nu, Omega), r and a wall: the sigma-edges of the stable maximal "
        "period-M windows from (64), the 2D map (37)/(38), the 2D map with A~(sigma), and the ODE (FMU; every "
        "orbit the up/down scans see continued in sigma to its edges, each edge located on its defining equation: "
        "flips and folds on their test functions, grazes on the gap or impact velocity). Writes report.md, windows.json "
        "(fig9.json's format), PNG plots and the scans' NetCDF into --out. The oscillator comes from the same "
        "layers as every command: the FMU's start values < --config FILE.toml ([fmu], [model]) < flags and --set.")
    experiment_options(p)
    g = p.add_argument_group("parameter set: --alpha/--gamma, or --nu/--Omega (above, or the experiment file)")
    g.add_argument("--alpha", type=float, help="map parameter alpha of (9), in (0, 1)")
    g.add_argument("--gamma", type=float, help="map parameter gamma of (9), in (0, 1)")
    g.add_argument("--branch", type=int, default=None,
                   help="with an underdamped --alpha/--gamma: the psi branch (0, 1, ...; sets sign(P12) = c1)")
    p.add_argument("--map", choices=MAP_WALLS, default="auto", dest="map_wall",
                   help="the maps' coefficients: auto (from --wall: (48) compliant, (39) rigid), or "
                   "compliant ((48), low-velocity impacts), compliant-high ((39), high-velocity impacts on a stiff "
                   "compliant wall), rigid ((39))")
    s = p.add_argument_group("where and how closely")
    s.add_argument("--sigma-range", type=sigma_range, metavar="LO:HI",
                   help="sigma interval of the scans and the shooting, negative values allowed (--sigma-range=-0.2:1; "
                   "default: 1e-3 to 3, widened to the maps' windows, edges followed down to 1e-4 and up to 12)")
    xtol_option(s, "1e-4 x the window's sigma, 1e-3 with --quick; with a --sigma-range reaching sigma <= 0: "
                   "1e-8 x its width, 1e-6 quick")
    theta_option(s)
    s.add_argument("--scan-points", type=count, default=None, metavar="N",
                   help="points of the scan grid over the range (default: 121 with --quick, 401 without on an even "
                   "grid, i.e. a --sigma-range reaching sigma <= 0; 24 or 80 per decade on a geometric one)")
    s.add_argument("--global-starts", type=int, default=None, metavar="N",
                   help="fresh starts of the global search at every sigma of the scan grid (a grid plus random "
                   "starts over the region the attractors occupy, iterated to their attractors with early stopping; "
                   "default 1000; 0: no global search)")
    s.add_argument("--global-path", choices=("auto", "batch", "fmu"), default="auto",
                   help="the global search's path: auto (default: the batch kernel, the exact closed form, for the "
                   "linear contact law; the FMU otherwise), batch, or fmu (every start through the FMU with --solver, "
                   "in parallel processes)")
    s.add_argument("--M-max", type=_m_max, default=None, dest="M_max", metavar="{auto,1..12}",
                   help="highest period; auto (default): until period adding truncates (no stable window at M "
                   "and M + 1)")
    o = p.add_argument_group("run")
    o.add_argument("--out", "-o", metavar="DIR", default="results/windows", help="output directory")
    o.add_argument("--quick", action="store_true", help="coarse scans (fewer points, shorter transients) and a "
                   "coarser fallback bisection (seconds to a minute); the edges located by the continuation are as "
                   "exact as without it")
    o.add_argument("--workers", "-j", dest="run__workers", type=count, metavar="N",
                   help="worker processes (default: up to 2)")
    o.add_argument("--no-progress", action="store_true", help="no progress bars")
    o.add_argument("--no-figures", action="store_true", help="no PNG figures: the report, the JSON and the scans' "
                   "NetCDF only")
    p.set_defaults(func=cmd_windows)


def sigma_range(text: str) -> tuple[float, float]:
    """argparse type of ``LO:HI`` (any signs; checked by the analysis: -1 < LO < HI)."""
    try:
        lo, hi = (float(x) for x in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected LO:HI (two numbers), got {text!r}") from None
    return lo, hi


def _m_max(text: str) -> int | None:
    if text == "auto":
        return None
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be 'auto' or an integer, got {text!r}") from None


def _nu_Omega(run: Any, args: argparse.Namespace) -> dict[str, float | None]:
    """nu and Omega where a file or a flag gave them (else None: --alpha/--gamma give them);
    --alpha/--gamma typed win over a file's nu and Omega, flags over the file as everywhere."""
    typed_map = args.alpha is not None or args.gamma is not None
    out: dict[str, float | None] = {}
    for k in ("nu", "Omega"):
        origin = run.layers.origin.get(("model", k))
        out[k] = run.params[k] if origin == "cli" or (origin is not None and not typed_map) else None
    return out


def cmd_windows(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    run = experiment_of(args)
    res = compare_windows(args.alpha, args.gamma, **_nu_Omega(run, args), r=run.params["r"],
                          wall=wall_name(run.params["wall"]), Gamma=run.params["Gamma"], M_max=args.M_max, quick=args.quick, out=args.out,
                          map_wall=args.map_wall, branch=args.branch, sigma_range=args.sigma_range, xtol=args.xtol,
                          theta=args.theta, global_starts=args.global_starts,
                          global_path=args.global_path, run=run, command=command_line(args),
                          figures=not args.no_figures, scan_points=args.scan_points)
    for line in res["summary"]:
        print(line)
    print(markdown_window_table(res["windows"], na=res["map_applicability"]))
    print(f"wrote {Path(args.out) / 'report.md'} and {Path(args.out) / 'windows.json'} "
          f"({time.perf_counter() - t0:.1f} s)")
    return 0
