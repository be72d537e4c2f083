"""atlas.nc: the atlas's per-start and per-pixel arrays with the classes and the run's provenance."""
from __future__ import annotations

import json
from typing import Any, Mapping

import numpy as np
import xarray as xr

from ...runs.atlas.scan import AtlasArrays
from ...runs.atlas.tiles import KINDS
from .classes import ClassMaps


def atlas_dataset(arrays: AtlasArrays, maps: ClassMaps, settings: Mapping[str, Any], model: Any = None,
                  command: str | None = None) -> xr.Dataset:
    """Coordinates (p2 named after the parameter, sigma, start); per start: the pixel's attractor
    label, kind, period, wall entries per orbit period, exponent, class, periods run, the orbit's
    last stroboscopic point; per pixel: the dominant class and the number of attractors."""
    from ...io.results import provenance

    plane = arrays.plane
    d = arrays.data
    dims = (plane.param2, "sigma", "start")
    ds = xr.Dataset(coords={plane.param2: plane.p2, "sigma": plane.sigma, "start": np.arange(plane.starts)})
    flags = {"flag_values": np.arange(len(KINDS), dtype=np.int8), "flag_meanings": " ".join(KINDS)}
    per_start = {
        "attractor": (d["label"], {"long_name": "the pixel's attractor reached from the start (0, 1, ... per pixel; "
                                                "-1: invalid or failed)"}),
        "kind": (d["kind"], {"long_name": "what the start reached", **flags}),
        "period": (d["period"], {"long_name": "period M of the orbit reached, in forcing periods (0: none)"}),
        "impacts": (d["impacts"], {"long_name": "wall entries per orbit period"}),
        "lyapunov": (d["lyapunov"], {"long_name": "largest Lyapunov exponent per forcing period (periodic: "
                                                  "ln|mu|/M of the M-period map's exact Jacobian)"}),
        "class_index": (maps.of_start, {"long_name": "index into the attribute atlas.classes (-1: none)"}),
        "periods_run": (d["periods_run"], {"long_name": "forcing periods the start ran"}),
        "orbit_u": (d["u"], {"long_name": "u at the orbit's last stroboscopic point (aperiodic: the last state)"}),
        "orbit_v": (d["v"], {"long_name": "v at the orbit's last stroboscopic point"}),
    }
    for name, (x, attrs) in per_start.items():
        ds[name] = (dims, x, attrs)
    ds["dominant_class"] = (dims[:2], maps.dominant, {"long_name": "the class most of the pixel's starts reached "
                                                                   "(index into atlas.classes; -1: none)"})
    ds["n_attractors"] = (dims[:2], maps.n_attractors, {"long_name": "attractors the pixel's starts reached"})
    attrs = provenance(settings, model if hasattr(model, "sha256") else None, arrays.describe, arrays.wall_time,
                       command)
    attrs.update({"atlas.param2": plane.param2, "atlas.starts": plane.starts,
                  "atlas.classes": json.dumps([c.name for c in maps.classes]),
                  "atlas.tiles": arrays.tiles, "atlas.tiles_resumed": arrays.resumed,
                  "atlas.periods_run_mean": float(np.mean(d["periods_run"][d["periods_run"] >= 0])),
                  "atlas.first_error": arrays.errors[0] if arrays.errors else ""})
    ds.attrs = attrs
    return ds
