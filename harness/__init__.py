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

from .classify import OrbitClass, classify_orbit, classify_samples, windows
from .config import Experiment, SamplingSpec, SweepSpec
from .errors import FmuError, HarnessInputError
from .fmi import FmuModel, FmuSource
from .jacobian import JacobianResult, JacobianScan, jacobian_vs_x, map_jacobian
from .results import read_netcdf, write_netcdf
from .sampling import StrobeResult, simulate, strobe
from .simulator import FmuSimulator, MappingSimulator, Simulator
from .sweeps import SweepStats, run_sweep

__all__ = [
    "Experiment", "FmuError", "FmuModel", "FmuSimulator", "FmuSource", "HarnessInputError",
    "JacobianResult", "JacobianScan", "MappingSimulator", "OrbitClass", "SamplingSpec",
    "Simulator", "StrobeResult", "SweepSpec", "SweepStats", "classify_orbit", "classify_samples",
    "jacobian_vs_x", "map_jacobian", "read_netcdf", "run_sweep", "simulate", "strobe", "windows",
    "write_netcdf", "__version__",
]
