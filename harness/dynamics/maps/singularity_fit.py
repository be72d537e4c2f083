"""The singularity exponent of the map's Jacobian near grazing, with its standard error.

The impact contribution J11 - P11 along the grazing family grows like x^q (docs/theory.md
section 8): q = -1/2 for the square-root map (hard contacts, and r < 1 at a soft wall),
q = +1/2 for soft elastic contacts (r = 1).  At a compliant wall the regime is set by
beta = r kappa sqrt(8 pi^2 x) / |A~|, kappa = sqrt(Gamma) Omega, A~ = (1 + sigma) A + sigma Omega^2
with A = -4 pi^2 (section 5): soft for beta <= :data:`SOFT_BETA`, hard for beta >=
:data:`HARD_BETA`, each fitted on its own (a fit across the crossover gives neither exponent).
Used by the ``jacobian`` command and by ``reproduce fig6/fig7``.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

#: beta bounds of the soft and hard regimes.
SOFT_BETA, HARD_BETA = 0.1, 5.0
#: A fit needs at least this many points over at least this many decades of x.
MIN_POINTS, MIN_DECADES = 3, 1.0
#: A point enters a fit only when J's own error estimate is below this fraction of J11 - P11.
RELIABLE = 0.05


def contact_beta(x: np.ndarray, r: float, Gamma: float, Omega: float, sigma: float = 0.0) -> np.ndarray:
    """beta = r kappa sqrt(8 pi^2 x) / |A~| of the grazing family's impact at distance x."""
    a_tilde = -(1.0 + sigma) * 4.0 * math.pi ** 2 + sigma * Omega ** 2
    return r * math.sqrt(Gamma) * Omega * np.sqrt(8.0 * math.pi ** 2 * np.asarray(x, dtype=float)) / abs(a_tilde)


def loglog_fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Least-squares slope of log|y| against log x and its standard error (NaN with < 3 points:
    two points leave no residual to estimate it from)."""
    lx, ly = np.log(np.asarray(x, dtype=float)), np.log(np.abs(np.asarray(y, dtype=float)))
    if lx.size < 2:
        return math.nan, math.nan
    slope, intercept = np.polyfit(lx, ly, 1)
    if lx.size < 3:
        return float(slope), math.nan
    residual = ly - (slope * lx + intercept)
    sxx = float(np.sum((lx - lx.mean()) ** 2))
    return float(slope), float(math.sqrt(float(np.sum(residual ** 2)) / (lx.size - 2) / sxx))


@dataclass(frozen=True)
class SingularityFit:
    """The exponent q of |J11 - P11| ~ x^q in one regime.

    Attributes
    ----------
    regime : str
        "soft", "hard" (compliant wall) or "all" (rigid wall: one regime).
    exponent, stderr : float
        Least-squares log-log slope and its standard error.
    x_min, x_max : float
        The fitted range of x.
    points : int
        Points in the fit.
    beta_min, beta_max : float
        The fitted range of beta (NaN for "all").
    """

    regime: str
    exponent: float
    stderr: float
    x_min: float
    x_max: float
    points: int
    beta_min: float = math.nan
    beta_max: float = math.nan

    def as_dict(self) -> dict[str, Any]:
        """The fields as a dict (for JSON reports)."""
        return asdict(self)


def regime_masks(x: np.ndarray, beta: np.ndarray | None) -> dict[str, np.ndarray]:
    """Which x belong to which regime: soft and hard for a compliant wall, "all" otherwise."""
    x = np.asarray(x, dtype=float)
    if beta is None:
        return {"all": np.ones(x.shape, dtype=bool)}
    return {"soft": beta <= SOFT_BETA, "hard": beta >= HARD_BETA}


def fit_singularity(x: np.ndarray, d: np.ndarray, error: np.ndarray, beta: np.ndarray | None = None
                    ) -> dict[str, SingularityFit | None]:
    """Fit |d| ~ x^q per regime, on the points J's error estimate calls reliable.

    Parameters
    ----------
    x : array_like
        Distances from grazing (> 0).
    d : array_like
        J11 - P11 at each x.
    error : array_like
        J's estimated absolute error at each x (0 for exact derivatives).
    beta : array_like, optional
        :func:`contact_beta` at each x for a compliant wall; None: one regime, "all".

    Returns
    -------
    dict
        regime -> :class:`SingularityFit`, or None where the regime has fewer than
        :data:`MIN_POINTS` reliable points over :data:`MIN_DECADES` decades.
    """
    x, d, error = (np.asarray(a, dtype=float) for a in (x, d, error))
    reliable = (x > 0) & (d != 0) & np.isfinite(d) & (error < RELIABLE * np.abs(d))
    out: dict[str, SingularityFit | None] = {}
    for name, sel in regime_masks(x, beta).items():
        sel = sel & reliable
        xs = x[sel]
        if xs.size < MIN_POINTS or math.log10(xs.max() / xs.min()) < MIN_DECADES - 1e-9:
            out[name] = None
            continue
        q, se = loglog_fit(xs, d[sel])
        b = (math.nan, math.nan) if beta is None else (float(beta[sel].min()), float(beta[sel].max()))
        out[name] = SingularityFit(name, q, se, float(xs.min()), float(xs.max()), int(xs.size), *b)
    return out


def describe(name: str, fit: SingularityFit | None) -> str:
    """One line per regime, e.g. "hard regime (beta >= 5): exponent -0.497 +- 0.003 over
    x in [1e-06, 0.01] (9 points)"."""
    bounds = {"soft": f" (beta <= {SOFT_BETA:g})", "hard": f" (beta >= {HARD_BETA:g})"}.get(name, "")
    head = f"{'whole range' if name == 'all' else name + ' regime'}{bounds}"
    if fit is None:
        return (f"{head}: no fit, fewer than {MIN_POINTS} reliable points over {MIN_DECADES:g} decade of x "
                "in the scanned range")
    return (f"{head}: exponent {fit.exponent:+.4f} +- {fit.stderr:.2g} over x in [{fit.x_min:.3g}, {fit.x_max:.3g}] "
            f"({fit.points} points)")


def grazing_fits(scan: Any, params: dict[str, Any]) -> tuple[dict[str, SingularityFit | None], np.ndarray | None]:
    """:func:`fit_singularity` of a :func:`harness.dynamics.maps.jacobian.jacobian_vs_x` scan with the
    FMU parameters it ran with: soft and hard regimes at a compliant wall (returned with beta at
    each x), the whole range otherwise (beta None)."""
    from ...config.defaults import WALLS

    wall = params.get("wall")
    compliant = wall in (WALLS["compliant"], "compliant") or (
        isinstance(wall, float) and int(wall) == WALLS["compliant"])
    beta = None
    if compliant:
        beta = contact_beta(scan.x, float(params["r"]), float(params["Gamma"]), float(params["Omega"]),
                            float(params.get("sigma", 0.0)))
    d = scan.J[:, 0, 0] - scan.P1[0, 0]
    return fit_singularity(scan.x, d, scan.error, beta), beta


def fits_dataset(fits: dict[str, SingularityFit | None]) -> Any:
    """The fits as NetCDF variables over a ``regime`` dimension (NaN / 0 points: no fit)."""
    import xarray as xr

    names = list(fits)
    def column(field: str) -> np.ndarray:
        return np.array([getattr(fits[n], field) if fits[n] is not None else math.nan for n in names], dtype=float)

    return xr.Dataset(
        {
            "exponent": ("regime", column("exponent"), {
                "long_name": "exponent q of |J11 - P11| ~ x^q (least-squares log-log slope)",
                "comment": f"points with J's estimated error < {RELIABLE:g} |J11 - P11|; soft: beta <= {SOFT_BETA:g}, "
                           f"hard: beta >= {HARD_BETA:g}; NaN: fewer than {MIN_POINTS} points over "
                           f"{MIN_DECADES:g} decade"}),
            "exponent_stderr": ("regime", column("stderr"), {"long_name": "standard error of the exponent"}),
            "fit_x_min": ("regime", column("x_min"), {"long_name": "smallest x in the fit"}),
            "fit_x_max": ("regime", column("x_max"), {"long_name": "largest x in the fit"}),
            "fit_points": ("regime", np.array([fits[n].points if fits[n] else 0 for n in names], dtype=np.int64),
                           {"long_name": "points in the fit"}),
        },
        coords={"regime": names},
    )
