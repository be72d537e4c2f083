"""An atlas run in tiles of whole rows: each finished tile checkpointed (``run.json`` with the
plane's fingerprint, then ``tile-NNNNN.npz``), so that a rerun resumes with nothing recomputed
and an interruption (Ctrl-C) keeps what was finished; locally on the batch kernel's threads (one
tile at a time, all threads on it), on local processes (the FMU route) or on Dask (``scheduler``:
tiles spread over the workers, one thread each); a progress bar in pixels.
"""
from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import HarnessInputError
from ...fmu.batch_kernel import default_threads
from ..basins.registry import fingerprint
from ..checkpoint import CheckpointMismatch
from ..tasks import run_test_hook
from .plane import AtlasPlane, check_plane
from .tiles import AtlasTile, run_tile

#: The per-start arrays of a tile and of the whole plane, with their dtypes.
FIELDS = {"kind": np.int8, "period": np.int16, "impacts": np.int16, "lyapunov": np.float64, "label": np.int16,
          "periods_run": np.int32, "u": np.float64, "v": np.float64}
#: Pixels per tile (whole rows).
TILE_PIXELS = 4096


class AtlasCheckpoint:
    """Finished tiles on disk (``None`` directory: nothing kept)."""

    def __init__(self, directory: str | os.PathLike | None, key: str) -> None:
        self.dir = Path(directory) if directory is not None else None
        if self.dir is None:
            return
        meta = self.dir / "run.json"
        if meta.exists():
            if json.loads(meta.read_text()).get("key") != key:
                raise CheckpointMismatch("checkpoint", f"{self.dir} holds another atlas's tiles",
                                         ["plane, parameters, starts or run lengths"])
        else:
            self.dir.mkdir(parents=True, exist_ok=True)
            meta.write_text(json.dumps({"key": key}))

    def done(self) -> dict[int, dict[str, np.ndarray]]:
        out: dict[int, dict[str, np.ndarray]] = {}
        for p in sorted(self.dir.glob("tile-*.npz")) if self.dir else ():
            with np.load(p) as z:
                out[int(p.stem.split("-")[1])] = {k: z[k] for k in FIELDS}
        return out

    def save(self, result: dict[str, Any]) -> None:
        if self.dir is not None:
            path = self.dir / f"tile-{result['index']:05d}.npz"
            tmp = path.with_name(path.stem + ".tmp.npz")
            np.savez(tmp, **{k: result[k] for k in FIELDS})
            os.replace(tmp, path)  # a tile is there whole or not at all


@dataclass
class AtlasArrays:
    """The plane's per-start arrays (p2, sigma, start) as tiles finish, and how the run went."""

    plane: AtlasPlane
    data: dict[str, np.ndarray] = field(default_factory=dict)
    tiles: int = 0
    resumed: int = 0
    errors: list[str] = field(default_factory=list)
    wall_time: float = 0.0
    describe: str = ""

    def __post_init__(self) -> None:
        shape = (*self.plane.shape, self.plane.starts)
        fill = {np.float64: np.nan}
        self.data = {k: np.full(shape, fill.get(t, -1), dtype=t) for k, t in FIELDS.items()}

    def put(self, rows: slice, result: dict[str, Any]) -> None:
        for k in FIELDS:
            self.data[k][rows] = result[k]
        if result.get("error"):
            self.errors.append(str(result["error"]))


def _backend(route: str, backend: Any, workers: int | None, scheduler: str | None) -> tuple[Any, int]:
    """(backend or None for this process's kernel threads, threads per kernel call)."""
    if backend == "serial":
        return None, 1
    if route == "kernel" and backend in (None, "processes") and not scheduler:
        return None, int(workers or default_threads())
    from ..backends import make_backend

    return make_backend(backend, workers, scheduler), 1


def run_atlas_plane(plane: AtlasPlane, route: str = "kernel", model: Any = None, *, backend: Any = None,
                    workers: int | None = None, scheduler: str | None = None, checkpoint: str | None = None,
                    progress: bool = True, tile_pixels: int = TILE_PIXELS) -> AtlasArrays:
    """Run every tile of ``plane`` not in the checkpoint yet.

    Parameters
    ----------
    plane : AtlasPlane
    route : str
        ``"kernel"`` (the closed form in C) or ``"fmu"`` (through ``model``'s FMU).
    backend, workers, scheduler
        As for :func:`harness.runs.basins.kernel_scan.run_basins_kernel` (the FMU route: local
        processes by default).
    checkpoint : str, optional
        Directory of finished tiles; a rerun resumes there.
    """
    from ...io.progress import progress_bar

    t0 = time.perf_counter()
    plane = check_plane(plane)
    if route not in ("kernel", "fmu"):
        raise HarnessInputError("route", f"must be kernel or fmu, got {route!r}")
    if route == "fmu" and model is None:
        raise HarnessInputError("model", "the FMU route needs the FMU")
    arrays = AtlasArrays(plane)
    ckpt = AtlasCheckpoint(checkpoint, fingerprint({**plane.fingerprint(), "route": route}))
    tiles = plane.tiles(tile_pixels)
    slices = dict(tiles)
    done = ckpt.done()
    for k, got in done.items():
        arrays.put(slices[k], got)
    arrays.tiles, arrays.resumed = len(tiles), len(done)
    n_sigma = plane.sigma.size
    kept = sum((slices[k].stop - slices[k].start) * n_sigma for k in done)
    bar = progress_bar(plane.p2.size * n_sigma, "atlas", unit="pixel", initial=kept, disable=not progress)
    be, threads = _backend(route, backend, workers, scheduler)

    def finish(k: int, result: dict[str, Any]) -> None:
        ckpt.save(result)
        arrays.put(slices[k], result)
        bar.update((slices[k].stop - slices[k].start) * n_sigma)

    todo = {k: AtlasTile(k, plane, sl, route, threads) for k, sl in tiles if k not in done}
    source = model.source() if route == "fmu" and hasattr(model, "source") else None
    try:
        if be is None:
            for k, tile in todo.items():
                run_test_hook(f"atlas-tile-{k:05d}", 0)  # tests interrupt a run at a known tile
                finish(k, run_tile(tile, source))
        else:
            be.run(run_tile, todo, source, finish)
    finally:
        bar.close()
        if be is not None:
            arrays.describe = be.describe()
            be.close()
    arrays.describe = arrays.describe or f"batch kernel (closed form in C), {threads} thread(s)"
    if route == "kernel" and be is not None:
        arrays.describe = f"batch kernel (closed form in C) on {arrays.describe}"
    arrays.wall_time = time.perf_counter() - t0
    return arrays
