"""Results as xarray Datasets with full provenance, written as NetCDF.

Every Dataset the harness writes carries, as attributes, every parameter of the run, the
FMU's sha256 and FMI version, the versions of this project and of the libraries, the
backend and the wall time, so a file on its own says how it was made.
"""
from __future__ import annotations

import datetime as _dt
import json
import os
import platform
import sys
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import xarray as xr

from .versions import library_versions, project_version  # noqa: F401  (part of this module's API)


def _attr_value(value: Any) -> Any:
    """NetCDF attributes hold strings, numbers and 1-D numeric arrays only."""
    if value is None:
        return "none"
    if isinstance(value, (bool, np.bool_)):
        return int(value)
    if isinstance(value, (int, float, str, np.integer, np.floating)):
        return value
    if isinstance(value, (list, tuple, np.ndarray)):
        arr = np.asarray(value)
        if arr.dtype.kind in "if" and arr.ndim == 1 and arr.size:
            return arr
        return json.dumps(np.asarray(value).tolist())
    return str(value)


def provenance(
    settings: Mapping[str, Any],
    model: Any = None,
    backend: str | None = None,
    wall_time: float | None = None,
    command: str | None = None,
) -> dict[str, Any]:
    """Attributes for a result.

    Parameters
    ----------
    settings : mapping
        Every parameter of the run (flat ``{"model.sigma": 0.2, "sampling.theta": 0, ...}``).
    model : FmuModel, optional
        The FMU (its path, sha256, FMI version and model identifier are recorded).
    backend : str, optional
        Backend description.
    wall_time : float, optional
        Seconds.
    command : str, optional
        The command line, when run from the CLI.
    """
    attrs: dict[str, Any] = {}
    for key, value in settings.items():
        attrs[key] = _attr_value(value)
    if model is not None:
        attrs["fmu_path"] = str(model.path)
        attrs["fmu_sha256"] = model.sha256
        attrs["fmi_version"] = model.fmi_version
        attrs["fmu_model_identifier"] = model.model_identifier
    for name, version in library_versions().items():
        attrs[f"version.{name}"] = version
    attrs["platform"] = f"{platform.system()} {platform.machine()}"
    if backend is not None:
        attrs["backend"] = backend
    if wall_time is not None:
        attrs["wall_time_s"] = float(wall_time)
    attrs["created_utc"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    if command is not None:
        attrs["command"] = command
    elif "command" not in attrs:
        attrs["command"] = " ".join(sys.argv)
    # The whole record once more as JSON, for programs that want a dict back.
    attrs["settings_json"] = json.dumps({k: _jsonable(v) for k, v in settings.items()}, sort_keys=True)
    return attrs


def _jsonable(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    return str(value)


def write_netcdf(ds: xr.Dataset, path: str | os.PathLike, argument: str = "--out") -> Path:
    """Write ``ds`` to ``path`` (directories created), atomically.

    Written to a temporary name first, so that an interruption never leaves a truncated
    file under the final name.
    """
    from .outputs import atomic_write

    # a unique temporary name in the target's directory, removed on failure (a fixed OUT + ".tmp"
    # would land beside a directory given as --out, e.g. /tmp.tmp for --out /tmp)
    with atomic_write(path, argument) as tmp:
        ds.to_netcdf(tmp, engine="netcdf4")
    return Path(path)


def read_netcdf(path: str | os.PathLike) -> xr.Dataset:
    """Load a result written by :func:`write_netcdf` fully into memory."""
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return ds.load()


#: Attributes of the ``period`` variable (sweeps and strobe runs).
PERIOD_ATTRS = {
    "long_name": "orbit period in forcing periods",
    "units": "forcing periods",
    "comment": "M > 0: the samples repeat after M forcing periods (within sampling.tol) with the same wall "
               "entries; 0: no period found up to sampling.max_period -- why (not converged, quasi-periodic, "
               "chaotic, unclassified) is in the variable dynamics where present; -1: not run (a start of a "
               "basin scan that the FMU refused: inside a rigid wall)",
}
#: Attributes of the ``orbit_impacts`` variable.
ORBIT_IMPACTS_ATTRS = {
    "long_name": "wall entries per orbit period (M forcing periods)",
    "comment": "-1 when period = 0 (no orbit period, so no count); a maximal period-M orbit of the paper's "
               "period adding has period = M, orbit_impacts = 1",
}


def strobe_dataset(result: Any, orbit: Any, attrs: Mapping[str, Any]) -> xr.Dataset:
    """Dataset of one stroboscopic run (samples + its classification)."""
    n = len(result.u)
    ds = xr.Dataset(
        {
            "u": ("sample", result.u, {"long_name": "displacement at t = n + theta"}),
            "v": ("sample", result.v, {"long_name": "velocity at t = n + theta"}),
            "impacts": ("sample", result.impacts, {"long_name": "wall entries in the period ending at the sample"}),
            "t": ("sample", result.t, {"long_name": "sample time"}),
            "period": ((), orbit.period, PERIOD_ATTRS),
            "orbit_impacts": ((), orbit.impacts, ORBIT_IMPACTS_ATTRS),
        },
        coords={"sample": np.arange(n)},
        attrs=dict(attrs),
    )
    ds.attrs["classification"] = orbit.label
    return ds


def timeseries_dataset(series: Mapping[str, np.ndarray], attrs: Mapping[str, Any]) -> xr.Dataset:
    """Dataset of a plain simulation (u, v, cumulative impacts against time)."""
    return xr.Dataset(
        {
            "u": ("t", series["u"], {"long_name": "displacement"}),
            "v": ("t", series["v"], {"long_name": "velocity"}),
            "impacts": ("t", series["impacts"], {"long_name": "wall entries since the start"}),
        },
        coords={"t": series["t"]},
        attrs=dict(attrs),
    )


def jacobian_dataset(scan: Any, attrs: Mapping[str, Any]) -> xr.Dataset:
    """Dataset of :func:`harness.dynamics.maps.jacobian.jacobian_vs_x`: J(x) and the free-flight P(1)."""
    rows = ["d_u_next", "d_v_next"]
    cols = ["d_u", "d_v"]
    ds = xr.Dataset(
        {
            "J": (("x", "row", "col"), scan.J, {"long_name": f"map Jacobian in the coordinates at theta = {scan.theta}"}),
            "J_measured": (("x", "row", "col"), scan.J_measured,
                           {"long_name": f"map Jacobian measured at theta = {scan.measure_theta}"}),
            "P1": (("row", "col"), scan.P1, {"long_name": "free-flight Jacobian P(1)"}),
            "step": ("x", scan.step, {"long_name": "central-difference step chosen"}),
            "error": ("x", scan.error, {"long_name": "estimated absolute error of J"}),
        },
        coords={"x": scan.x, "row": rows, "col": cols},
        attrs=dict(attrs),
    )
    ds["x"].attrs["long_name"] = "wall-free penetration u at t = n of the family (x, 0)"
    return ds


def state_jacobian_dataset(res: Any, state: tuple[float, float], theta: float, attrs: Mapping[str, Any]) -> xr.Dataset:
    """J of the one-period map at one state and its eigenvalues (the multipliers)."""
    mu = np.linalg.eigvals(res.J)
    ds = xr.Dataset(
        {
            "J": (("row", "col"), res.J, {"long_name": f"map Jacobian at (u, v) = {tuple(state)}, t = {theta}",
                                          "method": res.method}),
            "multiplier_real": ("eigenvalue", mu.real, {"long_name": "eigenvalues of J, real part"}),
            "multiplier_imag": ("eigenvalue", mu.imag, {"long_name": "eigenvalues of J, imaginary part"}),
            "multiplier_abs": ("eigenvalue", np.abs(mu), {"long_name": "modulus of the eigenvalues of J"}),
            "image": ("component", np.asarray(res.image, dtype=float)[:2], {"long_name": "(u, v) one period later"}),
        },
        coords={"row": ["d_u_next", "d_v_next"], "col": ["d_u", "d_v"], "eigenvalue": [1, 2],
                "component": ["u", "v"]},
        attrs={**dict(attrs), "jacobian.u": float(state[0]), "jacobian.v": float(state[1]),
               "jacobian.error": float(res.error), "jacobian.step": float(res.step)},
    )
    return ds
