"""harness: the grazing impact oscillator FMU as a dynamicist's object.

Stroboscopic Poincare maps, orbit classification, bifurcation sweeps (fresh starts and
quasi-static continuation up/down, 1D and 2D), Newton shooting of periodic orbits and window
edges, map Jacobians near grazing, on a local process pool or a Dask cluster, with results as
NetCDF (xarray) and PNG plots.  The theory (model, maps, corrections, how window edges are
found) is in ``docs/theory.md``; the command line (``impact-harness --help``) covers the same
ground as this API.

The public entry points, grouped as you look for them:

# FMU driving

* `FmuModel` -- an FMU file: defaults, parameter checks, a picklable `FmuSource` for workers;
* `FmuSimulator` -- one reusable FMU instance: ``start``, ``advance``, ``read``;
  `MappingSimulator` -- any one-period map given as a Python function; `Simulator` -- the protocol;
* `simulate` -- a time series u(t), v(t), impacts.

# Sampling

* `strobe` -> `StrobeResult` -- samples at t = n + theta after a transient;
* `SamplingSpec` -- transient, samples, tolerance, section phase;
* `classify_orbit` -> `OrbitClass`, `classify_samples` -- period and impacts per period (codes in
  `harness.dynamics.maps.classify`: period > 0 periodic, <= 0 not periodic or not converged);
* `windows` -- runs of equal period along a scan.

# Sweeps

* `SweepSpec`, `run_sweep` -> xarray Dataset (`SweepStats`) -- fresh starts or continuation
  up/down, 1D or 2D, serial / processes / Dask; `Experiment` -- a TOML run description;
* `write_netcdf`, `read_netcdf`.

# Errors

* `HarnessInputError` -- bad input, naming the argument (the CLI's one-line message, exit 2);
  `FmuError` -- the FMU failed during a run (exit 1).

# Basins of attraction

* `run_basins` (``impact-harness basins``) -- a grid of initial states (u0, v0) at t = theta, each
  labelled by the periodic attractor it reaches (`Attractor`: period, impacts, stroboscopic
  points); coexisting attractors of equal period told apart by their points
  (`identify_attractors`); starts inside a rigid wall marked invalid; parallel and resumable.
* `run_basins_kernel` -- the same on the batch kernel (the FMU's closed form in C for many starts
  at once, early-stopped on the attractors found, in tiles, locally or on Dask); its quantifiers:
  `basin_fractions`, `basin_entropy`, `uncertainty_exponent` (from the grid),
  `uncertainty_from_pairs` (from random pairs of starts), and `fmu_agreement` (random starts
  through the FMU, labels compared).
* `global_search` -- the attractors of one parameter set from fresh starts (a grid plus random
  ones over a `Region`), with their basin shares; `global_search_over` at every value of one
  parameter (``windows`` runs it over sigma).

# Shooting

* `StroboscopicMap` -- the FMU's one-period map in coordinates relative to the
  wall-free orbit;
* `map_guided_windows` -- ODE window edges of maximal period-M orbits, started in a map's
  windows; each edge the midpoint of a bracket the shooting bisected, or unresolved (``windows``
  locates its edges by continuation instead: :mod:`harness.analysis.windows.located_edges`);
* `harness.dynamics.maps.shooting.window_edges`, `harness.dynamics.maps.shooting.Edge`.

# Lyapunov exponents

* `lyapunov_exponents` -> `LyapunovResult` -- both exponents of the stroboscopic map with their
  standard errors (QR method, the FMU's own derivatives or differences);
  `lyapunov_from_jacobians` -- the same from given one-period Jacobians;
* `classify_dynamics` -- periodic, quasi-periodic, chaotic or not converged, from the period
  test and the largest exponent (the sweeps' ``dynamics`` variable).

# Jacobians

* `map_jacobian` -> `JacobianResult`, `jacobian_vs_x` -> `JacobianScan` -- the one-period map's
  Jacobian, and along the grazing family.

# Comparison with the maps

* `compare_windows` (``impact-harness windows``) -- for any (alpha, gamma) or (nu, Omega), r and
  wall: window edges of (64), the 2D map, the A~ map and the ODE, with report.md, JSON and plots;
* `harness.analysis` -- the window comparison and the chart for any parameter set;
* `harness.reproduce` -- the paper's figures (``impact-harness reproduce FIG``);
* `mapcheck.compare` -- the generic comparison logic (coordinates, window tables, fits).

# Maps

* `mapcheck` -- the paper's maps and coefficients (`mapcheck.coefficients`, `mapcheck.natural_map`,
  `mapcheck.physical_map`), windows (`mapcheck.window_1d`, `mapcheck.windows`), the closed-form
  solution of the ODE (`mapcheck.ExactOscillator`).

# Example

Run from the repository root after ``bash scripts/setup.sh`` (these lines are run by the tests):

>>> from harness import FmuModel, FmuSimulator, strobe, classify_orbit
>>> model = FmuModel("build/fmu/ImpactOscillator.fmu")
>>> sim = FmuSimulator(model.source())
>>> params = {**model.defaults(), "sigma": 0.5}
>>> r = strobe(sim, params, (-1.0, 0.0), theta=0.0, n_transient=300, n_samples=40)
>>> classify_orbit(r.u, r.v, r.impacts).label
'P2, 1 impact'

Sweeps and `compare_windows` use worker processes, which re-import the main module: in a
script, call them under ``if __name__ == "__main__":`` (``examples/sweep.py``,
``examples/windows.py``).
"""
from importlib import metadata as _metadata

try:
    __version__ = _metadata.version("impact-grazing")
except _metadata.PackageNotFoundError:  # pragma: no cover - running from a bare checkout
    __version__ = "0+unknown"

# Public names -> defining module.  Loaded lazily (PEP 562) so that a worker process that
# only needs harness.runs.tasks does not import xarray, matplotlib or Dask.
_EXPORTS = {
    "OrbitClass": "dynamics.maps.classify", "classify_orbit": "dynamics.maps.classify", "classify_samples": "dynamics.maps.classify", "windows": "dynamics.maps.classify",
    "Experiment": "runs.experiment", "SamplingSpec": "config", "SweepSpec": "config",
    "FmuError": "errors", "HarnessInputError": "errors",
    "FmuModel": "fmu.fmi", "FmuSource": "fmu.fmi",
    "JacobianResult": "dynamics.maps.jacobian", "JacobianScan": "dynamics.maps.jacobian", "jacobian_vs_x": "dynamics.maps.jacobian", "map_jacobian": "dynamics.maps.jacobian",
    "LyapunovResult": "dynamics.maps.lyapunov", "lyapunov_exponents": "dynamics.maps.lyapunov", "lyapunov_from_jacobians": "dynamics.maps.lyapunov",
    "classify_dynamics": "dynamics.maps.classify",
    "read_netcdf": "io.results", "write_netcdf": "io.results",
    "StrobeResult": "dynamics.maps.sampling", "simulate": "dynamics.maps.sampling", "strobe": "dynamics.maps.sampling",
    "FmuSimulator": "fmu.simulator", "MappingSimulator": "fmu.simulator", "Simulator": "fmu.simulator",
    "SweepStats": "runs.sweeps", "run_sweep": "runs.sweeps",
    "StroboscopicMap": "dynamics.maps.shooting", "map_guided_windows": "dynamics.maps.shooting",
    "compare_windows": "analysis.windows.compare_windows",
    "run_basins": "runs.basins.scan", "Attractor": "dynamics.attractors.identity", "identify_attractors": "dynamics.attractors.identity",
    "run_basins_kernel": "runs.basins.kernel_scan", "basin_fractions": "analysis.basins.measures",
    "basin_entropy": "analysis.basins.measures", "uncertainty_exponent": "analysis.basins.measures",
    "global_search": "runs.basins.global_search", "global_search_over": "runs.basins.global_search",
    "Region": "runs.basins.global_search",
    "fmu_agreement": "analysis.basins.agreement", "uncertainty_from_pairs": "analysis.basins.uncertainty",
}

__all__ = sorted(_EXPORTS) + ["__version__"]


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'harness' has no attribute {name!r}")
    from importlib import import_module

    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return __all__
