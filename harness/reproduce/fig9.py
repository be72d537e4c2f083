"""Figure 9: truncated period adding at (alpha, gamma) = (0.99, 0.01), r = 0.9.

This is ``impact-harness windows`` (:mod:`harness.analysis.windows.compare_windows`) with the paper's
parameters and grids:

* ``theory_64``   -- (64), rho in [1/(4M), 1/M^2], with rho(sigma) linear from (48);
* ``map``         -- the 2D map (37)/(38) with (48) (closed-form orbits, bisection);
* ``map_A_tilde`` -- the same with |A~(sigma)| = (1+sigma) 4 pi^2 - sigma Omega^2 in rho;
* ``ode``         -- the FMU (compliant wall, Gamma = 10): Newton shooting on its
  stroboscopic M-period map, lower edges where the orbit loses stability, upper edges
  where an extra contact appears, each bracketed and bisected to ``xtol`` by the shooting;
  confirmed by quasi-static up and down scans of the FMU (the scans also give the ODE
  bifurcation diagram).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from . import Context
from .fig9_maps import ALPHA, GAMMA, R
from ..analysis.windows.compare_windows import WindowProblem, WindowSettings, run_windows

GAMMA_WALL = 10.0
M_MAX = 4
THETA = 0.5  # section phase of the FMU samples: half a period from the impacts

SETTINGS = {
    # quick: 0.01 grid (windows M <= 3 resolved; M = 4 is 0.0016 wide, found by shooting
    # only), 200 transient periods per continuation point (the state is carried on).
    True: {"grid": (0.10, 1.0, 91), "transient": 200, "samples": 24, "xtol": 1e-4, "map_grid": 451},
    # full: 0.001 grid, 300 transient periods (the free mode decays like 0.98^n).
    False: {"grid": (0.10, 1.0, 901), "transient": 300, "samples": 40, "xtol": 1e-5, "map_grid": 1801},
}


def problem() -> WindowProblem:
    """Figure 9's parameter set."""
    return WindowProblem.from_alpha_gamma(ALPHA, GAMMA, r=R, wall="compliant", Gamma=GAMMA_WALL, M_max=M_MAX,
                                          theta=THETA)


def settings(quick: bool) -> WindowSettings:
    """The paper's sigma range on a uniform grid; the table on fig9_maps' grid."""
    cfg = SETTINGS[quick]
    return WindowSettings(scan_grid=np.linspace(*cfg["grid"]), transient=cfg["transient"], samples=cfg["samples"],
                          xtol=cfg["xtol"], sigma_range=(0.05, 1.5), table_grid=np.linspace(-0.5, 3.0, 12001),
                          log_sigma=False, extra={"map_points": cfg["map_grid"]})


def run(ctx: Context) -> tuple[dict[str, Any], str]:
    result, _ = run_windows(ctx, problem(), settings(ctx.quick))
    from ..analysis.windows.report import report

    return result, report(ctx, problem(), result, title="Figure 9: truncated period adding, map vs ODE")
