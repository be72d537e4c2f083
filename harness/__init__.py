"""harness: the grazing impact oscillator FMU as a dynamicist's object.

Stroboscopic Poincare maps, orbit classification, bifurcation sweeps (fresh starts and
quasi-static continuation up/down, 1D and 2D), map Jacobians near grazing, on a local
process pool or a Dask cluster, with results as NetCDF (xarray) and PNG plots.

Typical use::

    from harness import FmuModel, FmuSimulator, strobe, classify_orbit
    model = FmuModel("build/fmu/ImpactOscillator.fmu")
    sim = FmuSimulator(model.source())
    params = {**model.defaults(), "sigma": 0.5}
    r = strobe(sim, params, (-1.0, 0.0), theta=0.0, n_transient=200, n_samples=40)
    print(classify_orbit(r.u, r.v, r.impacts).label)

    from harness import SweepSpec, SamplingSpec, run_sweep
    spec = SweepSpec("sigma", np.linspace(0.15, 1.0, 35), ("up", "down"))
    ds = run_sweep(model, spec, sampling=SamplingSpec(n_transient=300, n_samples=40))

The command line (``impact-harness --help``) covers the same ground.
"""
from importlib import metadata as _metadata

try:
    __version__ = _metadata.version("impact-grazing")
except _metadata.PackageNotFoundError:  # pragma: no cover - running from a bare checkout
    __version__ = "0+unknown"

# Public names -> defining module.  Loaded lazily (PEP 562) so that a worker process that
# only needs harness.tasks does not import xarray, matplotlib or Dask.
_EXPORTS = {
    "OrbitClass": "classify", "classify_orbit": "classify", "classify_samples": "classify", "windows": "classify",
    "Experiment": "config", "SamplingSpec": "config", "SweepSpec": "config",
    "FmuError": "errors", "HarnessInputError": "errors",
    "FmuModel": "fmi", "FmuSource": "fmi",
    "JacobianResult": "jacobian", "JacobianScan": "jacobian", "jacobian_vs_x": "jacobian", "map_jacobian": "jacobian",
    "LyapunovResult": "lyapunov", "lyapunov_exponents": "lyapunov", "lyapunov_from_jacobians": "lyapunov",
    "classify_dynamics": "classify",
    "read_netcdf": "results", "write_netcdf": "results",
    "StrobeResult": "sampling", "simulate": "sampling", "strobe": "sampling",
    "FmuSimulator": "simulator", "MappingSimulator": "simulator", "Simulator": "simulator",
    "SweepStats": "sweeps", "run_sweep": "sweeps",
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
