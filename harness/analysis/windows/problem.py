"""The question :func:`harness.analysis.windows.compare_windows.compare_windows` answers: one parameter set
(:class:`WindowProblem`: the oscillator, the wall, the periods looked at), how hard to look
(:class:`WindowSettings`, :func:`default_settings`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mapcheck.coeffs import Coefficients, coefficients
from mapcheck.compare import predicted_windows
from mapcheck.linear import alpha_gamma, invert_alpha_gamma

from ...config.defaults import SECTION_PHASE, WALLS
from ...errors import HarnessInputError

__all__ = ["WindowProblem", "WindowSettings", "default_settings", "map_guide", "WINDOW_WALLS"]

#: The walls a window comparison takes (the maps need impacts: no ``"none"``).
WINDOW_WALLS = ("compliant", "rigid")
#: Coefficients of the maps: "auto" (from the wall), or a ``wall`` of :func:`mapcheck.coeffs.coefficients`.
MAP_WALLS = ("auto", "compliant", "compliant-high", "rigid")
#: Highest period classified by the scans (and searched with --M-max auto).
M_AUTO_LIMIT = 12


@dataclass(frozen=True)
class WindowProblem:
    """One parameter set: the oscillator, the wall, and the periods looked at.

    Attributes
    ----------
    nu, Omega : float
        Forcing-to-natural frequency ratio and its damped counterpart (the FMU's parameters).
    r : float
        Coefficient of restitution (rigid wall) / of the compliant wall's damping.
    wall : {"compliant", "rigid"}
    Gamma : float
        Stiffness of the compliant wall (ignored for a rigid wall).
    M_max : int or None
        Highest period looked at; None ("auto"): until period adding truncates (no stable
        maximal window at M and M + 1), up to :data:`M_AUTO_LIMIT`.
    theta : float
        Phase of the FMU's stroboscopic section (the default of every command,
        :data:`harness.config.SECTION_PHASE`: half a period from the impacts).
    """

    nu: float
    Omega: float
    r: float = 0.9
    wall: str = "compliant"
    Gamma: float = 10.0
    M_max: int | None = 4
    theta: float = SECTION_PHASE
    map_wall: str = "auto"

    def __post_init__(self) -> None:
        if self.wall not in WINDOW_WALLS:
            raise HarnessInputError("wall", f"must be compliant or rigid, got {self.wall!r}")
        if self.map_wall not in MAP_WALLS:
            raise HarnessInputError("map_wall", f"must be one of {', '.join(MAP_WALLS)}, got {self.map_wall!r}")
        if not (0.0 < self.r <= 1.0):
            raise HarnessInputError("r", f"must be in (0, 1], got {self.r}")
        if self.wall == "compliant" and not self.Gamma > 0:
            raise HarnessInputError("Gamma", f"must be > 0, got {self.Gamma}")
        for name in ("nu", "Omega"):
            if not getattr(self, name) > 0:
                raise HarnessInputError(name, f"must be > 0, got nu = {self.nu}, Omega = {self.Omega}")
        if not 0.0 <= self.theta < 1.0:
            raise HarnessInputError("theta", f"must lie in [0, 1), got {self.theta}")
        if self.M_max is not None and not 1 <= self.M_max <= M_AUTO_LIMIT:
            raise HarnessInputError("M_max", f"must be 'auto' or in 1..{M_AUTO_LIMIT}, got {self.M_max}")

    @classmethod
    def from_alpha_gamma(cls, alpha: float, gamma: float, branch: int | None = None, **kw: Any) -> "WindowProblem":
        """From the map's (alpha, gamma) of (9): unique when P(1) has real eigenvalues; underdamped
        (alpha^2 < 4 gamma) the psi branch must be chosen (it sets sign(P12) = c1).  Whether the
        maps apply to the oscillator is reported by the run, as for --nu/--Omega."""
        if not 0.0 < gamma < 1.0:
            raise HarnessInputError("gamma", f"gamma = det P(1) = exp(-nu) must lie in (0, 1) (nu > 0), got {gamma}")
        try:
            inv = invert_alpha_gamma(alpha, gamma, branch)
        except (ValueError, ArithmeticError) as exc:
            raise HarnessInputError("alpha", f"no (nu, Omega) for (alpha, gamma) = ({alpha}, {gamma}): {exc}"
                                    + ("; give a branch 0, 1, ... or nu and Omega" if "branch" in str(exc) else "")
                                    ) from exc
        return cls(float(inv.nu), float(inv.Omega), **kw)

    @property
    def alpha_gamma(self) -> tuple[float, float]:
        a, g = alpha_gamma(self.nu, self.Omega)
        return float(a), float(g)

    @property
    def map_coefficients_wall(self) -> str:
        """The ``wall`` of :func:`mapcheck.coeffs.coefficients` for the maps: by default the FMU's
        wall ((48) low-velocity map for compliant, (39) for rigid); ``map_wall`` overrides it,
        e.g. "compliant-high" ((39): high-velocity impacts on a stiff compliant wall)."""
        return self.wall if self.map_wall == "auto" else self.map_wall

    def coefficients(self) -> Coefficients:
        return coefficients(self.nu, self.Omega, self.r, self.map_coefficients_wall)

    def fmu_params(self) -> dict[str, Any]:
        p: dict[str, Any] = {"nu": self.nu, "Omega": self.Omega, "r": self.r, "wall": WALLS[self.wall]}
        if self.wall == "compliant":
            p["Gamma"] = self.Gamma
        return p

    def describe(self) -> str:
        a, g = self.alpha_gamma
        wall = f"compliant wall, Gamma = {self.Gamma:g}" if self.wall == "compliant" else "rigid wall"
        return f"(alpha, gamma) = ({a:.4g}, {g:.4g}), r = {self.r:g}, {wall}"

    def coefficient_eq(self) -> str:
        return "(48)" if self.map_coefficients_wall == "compliant" else "(39)"


@dataclass
class WindowSettings:
    """How hard to look.

    Attributes
    ----------
    far_start : bool
        Scan also from a large-amplitude start (``--sigma-range``'s runs).
    scan_grid : ndarray
        Sorted sigma values of the up/down scans (and of the map's bifurcation diagrams).
    transient, samples : int
        Periods per scan point before classifying, and periods sampled.
    xtol : float or None
        Bisection tolerance of the shooting in sigma (absolute); None: ``xtol_rel`` times the
        sigma where the window was seen.
    sigma_range : (float, float)
        Search range of the shooting.
    table_grid : ndarray
        sigma grid of the 2D maps' window search.
    log_sigma : bool
        Geometric scan grid (windows spread over decades of sigma): log axes in the plots.
    """

    scan_grid: np.ndarray
    transient: int
    samples: int
    xtol: Any
    sigma_range: tuple[float, float]
    table_grid: np.ndarray
    log_sigma: bool = False
    extra: dict[str, Any] = field(default_factory=dict)
    xtol_rel: float = 1e-3
    #: also scan up and down from a start far from the wall-free orbit (large amplitude, hitting
    #: the wall): below grazing the wall-free orbit is an attractor, and scans started on it never
    #: leave it, so an impacting attractor beside it is reached only from elsewhere
    far_start: bool = False
    #: fresh starts of the global search at every sigma of the scan grid (0: no global search)
    global_starts: int = 1000
    #: its path: "auto" (the batch kernel for the linear contact law), "batch" or "fmu"
    global_path: str = "auto"


#: The sigma range every default scan covers, whatever the maps say (geometric grid): the
#: windows of the oscillators tried so far lie inside it (Figure 9: 0.12 to 0.8; underdamped
#: nu = 0.8, Omega = 2.5, r = 0.8: period 1 from 1.6 (rigid), period 2 to 0.125 (Gamma = 100)).
BASE_RANGE = (1e-3, 3.0)


def map_guide(problem: WindowProblem, M_max: int) -> tuple[Coefficients | None, str | None]:
    """The maps' coefficients, or None with the reason they do not exist."""
    try:
        return problem.coefficients(), None
    except (ValueError, ArithmeticError) as exc:
        return None, str(exc)


#: Most scan points one run may ask for (each is two runs of the FMU and a global search).
MAX_SCAN_POINTS = 20001


def default_settings(problem: WindowProblem, quick: bool, sigma_range: tuple[float, float] | None = None,
                     xtol: float | None = None, scan_points: int | None = None) -> WindowSettings:
    """Grids and tolerances: the ODE is scanned over :data:`BASE_RANGE`, widened to hold the
    maps' windows where the maps give finite ones, on a geometric grid (24 points per decade
    quick, 80 full); the shooting may follow an orbit beyond the grid, a decade below and a factor
    4 above.  The bisection tolerance is relative to the window's sigma (1e-3 quick, 1e-4 full).

    ``sigma_range`` (lo, hi) replaces all that: the scans and the shooting cover exactly
    [lo, hi], on a geometric grid when lo > 0, else on an even grid (120 points quick, 400 full)
    with even marching steps: sigma <= 0 included (the wall-free orbit, which grazes at sigma =
    0).  ``xtol``: an absolute bisection tolerance in sigma instead of the relative one (on an
    even grid the default is 1e-6 (quick) or 1e-8 (full) of hi - lo).  ``scan_points``: the scan
    grid's points over the range instead (even or geometric as above; at least 3).
    """
    if scan_points is not None and (isinstance(scan_points, bool) or not isinstance(scan_points, (int, np.integer))
                                    or not 3 <= scan_points <= MAX_SCAN_POINTS):
        raise HarnessInputError("scan_points", f"must be an integer from 3 to {MAX_SCAN_POINTS}, got {scan_points!r}")
    table_grid, (lo, hi) = _map_range(problem)
    if sigma_range is not None:
        lo, hi = sigma_range
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi and lo > -1.0):
            raise HarnessInputError("sigma_range", f"needs -1 < LO < HI, both finite, got {lo:g}:{hi:g}")
    else:
        lo, hi = max(lo, 1e-6), min(hi, 1e3)
    if xtol is not None and not (math.isfinite(xtol) and xtol > 0):
        raise HarnessInputError("xtol", f"must be a finite number > 0, got {xtol!r}")
    rel = 1e-3 if quick else 1e-4
    search = (lo, hi) if sigma_range is not None else (0.1 * lo, 4.0 * hi)
    st = dict(transient=200 if quick else 300, samples=24 if quick else 40, sigma_range=search, xtol_rel=rel,
              far_start=sigma_range is not None)
    if lo <= 0:  # an even grid: a geometric one cannot reach sigma <= 0
        grid = np.linspace(lo, hi, scan_points or (121 if quick else 401))
        return WindowSettings(scan_grid=grid, xtol=xtol if xtol is not None else (1e-6 if quick else 1e-8) * (hi - lo),
                              table_grid=table_grid, log_sigma=False, **st)
    # the maps are cheap: search them over the ODE's whole range too
    table_grid = np.geomspace(min(table_grid[0], 0.01 * lo), max(table_grid[-1], 4.0 * hi), 16001)
    per_decade = 24 if quick else 80
    grid = np.geomspace(lo, hi, scan_points or int(math.ceil(per_decade * math.log10(hi / lo))) + 1)
    return WindowSettings(scan_grid=grid, xtol=xtol, table_grid=table_grid, log_sigma=True, **st)


def _map_range(problem: WindowProblem) -> tuple[np.ndarray, tuple[float, float]]:
    """The maps' sigma grid, and :data:`BASE_RANGE` widened to hold the maps' windows."""
    lo, hi = BASE_RANGE
    c, _ = map_guide(problem, problem.M_max or M_AUTO_LIMIT)
    table_grid = np.geomspace(1e-6, 1e3, 12001)
    if c is not None:
        with np.errstate(all="ignore"):
            s_1 = float(max(c.sigma_of_rho(0.25, "paper"), c.sigma_of_rho(0.25, "tilde")))
            if not math.isfinite(s_1):
                s_1 = float(c.sigma_of_rho(0.25, "paper"))
        if math.isfinite(s_1) and s_1 > 0:
            table_grid = np.geomspace(1e-5 * s_1, 4.0 * s_1, 12001)
            guide = predicted_windows(c, problem.M_max or 8, table_grid)["map_A_tilde"]
            los = [w[0] for w in guide.values() if w is not None and w[0] is not None]
            if los:
                lo, hi = min(lo, 0.7 * min(los)), max(hi, 2.5 * s_1)
    return table_grid, (lo, hi)
