"""mapcheck: the analytic near-grazing maps of Molenaar, de Weger & van de Water,
"Mappings of grazing-impact oscillators", Nonlinearity 14 (2001) 301.

Modules, by concern:

* :mod:`mapcheck.linear`   -- eigenvalues, propagator (7), (alpha, gamma) (9) and its inverse
* :mod:`mapcheck.coeffs`   -- ``coefficients(nu, Omega, r, wall)``: (36), (39), (48); A and A~(sigma)
* :mod:`mapcheck.maps`     -- the maps: L (26)-(30), (31)/(32), (33)-(35), (37)/(38), (1)/(2), (54)-(56)
* :mod:`mapcheck.exact`    -- closed-form solution of the ODE and the exact pre-impact map
* :mod:`mapcheck.segments` -- one linear regime in closed form and its first wall crossing
* :mod:`mapcheck.resonant_grazing` -- the single-impact fold of a rigid wall at grazing in closed form (resonant grazing)
* :mod:`mapcheck.exact_flow` -- the exact flow strobed: periodic orbits, multipliers, largest u
* :mod:`mapcheck.windows`  -- ``window_1d(M)`` (64); maximal period-M orbits and their windows
* :mod:`mapcheck.bifurcation` -- vectorized iteration over sigma/rho grids (fresh, up, down)
* :mod:`mapcheck.duration` -- impact duration: exact (41) and (42), (45), (50)
* :mod:`mapcheck.orbits`   -- Newton periodic orbits and window edges of any map (e.g. the exact map)
* :mod:`mapcheck.impact_orbit` -- the rigid wall's one-impact period-1 orbit in closed form: fold, flip, graze
"""
from .coeffs import A_GRAZING, Coefficients, coefficients, grazing_acceleration
from .exact import ExactOscillator
from .bifurcation import PiecewiseMap, classify, orbit_diagram
from .duration import duration_42, duration_45, duration_50, duration_exact
from .linear import alpha_gamma, invert_alpha_gamma, propagator
from .maps import (
    damped_1d_map,
    from_natural,
    local_impact_map,
    local_impact_map_delay,
    natural_map,
    nordmark_map,
    physical_map,
    piecewise_map,
    rho_1d,
    to_natural,
)
from .orbits import PeriodicOrbit, solve_periodic_orbit, window_edge
from .windows import MapParams, Window, maximal_orbits, window_1d, windows

__all__ = [
    "A_GRAZING",
    "MapParams",
    "PeriodicOrbit",
    "duration_42",
    "duration_45",
    "duration_50",
    "duration_exact",
    "solve_periodic_orbit",
    "window_edge",
    "PiecewiseMap",
    "Window",
    "classify",
    "maximal_orbits",
    "orbit_diagram",
    "window_1d",
    "windows",
    "Coefficients",
    "ExactOscillator",
    "alpha_gamma",
    "coefficients",
    "damped_1d_map",
    "from_natural",
    "grazing_acceleration",
    "invert_alpha_gamma",
    "local_impact_map",
    "local_impact_map_delay",
    "natural_map",
    "nordmark_map",
    "physical_map",
    "piecewise_map",
    "propagator",
    "rho_1d",
    "to_natural",
]
