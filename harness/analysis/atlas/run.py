"""``atlas``: the plane of sigma and a second parameter by brute force, and what it writes:
atlas.nc, atlas.json (the classes and where each is stable; with ``curves``, the chart's edges
checked against the pixels), atlas.png and report.md in the output folder."""
from __future__ import annotations

import json
import shutil
import time
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ...runs.atlas.plane import CHAOS_LYAPUNOV, AtlasPlane
from ...runs.atlas.scan import run_atlas_plane
from ..context import to_jsonable
from .classes import class_summary, classify
from .curves import compare_curves, read_curves
from .dataset import atlas_dataset
from .figure import atlas_figure


def atlas(plane: AtlasPlane, out: str | Path, *, route: str = "kernel", model: Any = None, log_p2: bool = False,
          log_sigma: bool = False, curves: str | Path | None = None, backend: Any = None, workers: int | None = None,
          scheduler: str | None = None, progress: bool = True, plot: bool = True, checkpoint: str | Path | None = None,
          settings: Mapping[str, Any] | None = None, command: str | None = None) -> dict[str, Any]:
    """Run the atlas (resuming from ``checkpoint``, default ``out``/atlas.partial), write its files, return
    atlas.json's dict."""
    from ...io.results import write_netcdf

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    chart = read_curves(curves, plane.param2) if curves is not None else None  # bad input before any work
    ckpt = Path(checkpoint) if checkpoint is not None else out / "atlas.partial"
    t0, c0 = time.perf_counter(), time.process_time()
    arrays = run_atlas_plane(plane, route, model, backend=backend, workers=workers, scheduler=scheduler,
                             checkpoint=str(ckpt), progress=progress)
    cpu = time.process_time() - c0
    maps = classify(arrays.data)
    res = summary(plane, arrays, maps, route, time.perf_counter() - t0, cpu, log_p2, log_sigma)
    if chart is not None:
        res["curves"] = {"file": str(curves), "count": len(chart),
                         **compare_curves(maps, chart, plane.p2, plane.sigma, log_p2, log_sigma)}
    ds = atlas_dataset(arrays, maps, {**(settings or {}), "atlas.summary": json.dumps(to_jsonable(res["counts"]))},
                       model, command)
    write_netcdf(ds, out / "atlas.nc")
    (out / "atlas.json").write_text(json.dumps(to_jsonable(res), indent=1) + "\n")
    if plot:
        atlas_figure(maps, plane.p2, plane.sigma, plane.param2, log_p2, log_sigma, title(plane, res), out / "atlas.png",
                     chart)
    from .report import atlas_report

    (out / "report.md").write_text(atlas_report(res, command))
    shutil.rmtree(ckpt, ignore_errors=True)  # atlas.nc now holds everything
    return res


def title(plane: AtlasPlane, res: Mapping[str, Any]) -> str:
    """The plot's title: the oscillator, the grid, the starts."""
    p = plane.params
    wall = {0: "no wall", 1: "compliant", 2: "rigid"}.get(int(p.get("wall", 1)), "?")
    shown = [f"{k} = {p[k]:.6g}" for k in ("nu", "Omega", "r", "Gamma") if k in p and k != plane.param2
             and not (k == "Gamma" and wall != "compliant")]
    return (f"atlas: {wall} wall, {', '.join(shown)}, theta = {plane.theta:g}\n{plane.p2.size} x {plane.sigma.size} "
            f"pixels ({plane.param2} x sigma), {plane.starts} starts each; {res['route']}")


def summary(plane: AtlasPlane, arrays: Any, maps: Any, route: str, wall: float, cpu: float, log_p2: bool,
            log_sigma: bool) -> dict[str, Any]:
    """atlas.json's dict (without the curves)."""
    d = arrays.data
    n_pix = int(np.prod(plane.shape))
    classes = class_summary(maps, plane.p2, plane.sigma)
    kinds = {name: int((d["kind"] == code).sum()) for code, name in enumerate(
        ("periodic", "sticking", "chaotic", "aperiodic", "escaped", "invalid", "failed"))}
    return {
        "param2": plane.param2, "params": plane.params, "theta": plane.theta,
        "grid": {"p2": [float(plane.p2[0]), float(plane.p2[-1]), int(plane.p2.size)], "p2_log": log_p2,
                 "sigma": [float(plane.sigma[0]), float(plane.sigma[-1]), int(plane.sigma.size)],
                 "sigma_log": log_sigma, "starts": plane.starts, "seed": plane.seed},
        "run": {**vars(plane.run), "chaos_lyapunov": CHAOS_LYAPUNOV},
        "route": arrays.describe if route == "kernel" else f"FMU, {arrays.describe}",
        "classes": classes,
        "counts": {"pixels": n_pix, "starts": n_pix * plane.starts, "starts_by_kind": kinds,
                   "multistable_pixels": int((maps.n_attractors >= 2).sum()),
                   "max_attractors": int(maps.n_attractors.max()) if n_pix else 0,
                   "chaotic_pixels": int(sum(s["pixels"] for s in classes if s["kind"] == "chaotic"))},
        "timing": {"wall_s": wall, "cpu_s_this_process": cpu, "tiles": arrays.tiles, "tiles_resumed": arrays.resumed,
                   "periods_per_start": float(np.mean(d["periods_run"])),
                   "starts_per_s": float(n_pix * plane.starts / wall) if wall > 0 else None},
        "errors": arrays.errors[:5],
    }
