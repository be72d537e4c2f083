"""The attractors a batch-kernel basin scan has found so far, and its checkpoint of tiles.

The registry only grows (an attractor keeps its index for the rest of the scan), so a tile's
labels stay valid after later tiles add attractors, and a checkpoint written after each tile
(``attractors.json`` first, then ``tile-NNNNN.npz``) resumes with nothing recomputed that was
finished.  Every new attractor is confirmed by Newton shooting on the FMU
(:func:`harness.dynamics.attractors.check.shoot_attractor`) when a simulator is given.
"""
from __future__ import annotations

import hashlib
import json
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ...fmu.batch_kernel import KnownAttractors
from .tiles import CANDIDATE, Candidate, match_known
from ..checkpoint import CheckpointMismatch

#: Consecutive periods on an attractor that recognise a start, per period of the attractor
#: (at least MIN_CONFIRM): the orbit must come round twice, each point within the tolerance.
#: The strict rule; one period is enough once every attractor's tolerance balls were run and
#: all reached it (:mod:`.basin_ball`).
CONFIRM_ROUNDS = 2
MIN_CONFIRM = 4


@dataclass
class Found:
    """One attractor of the registry: a candidate, with Newton's verdict."""

    period: int
    impacts: int
    points: list[list[float]]
    entries: list[int]
    stuck: bool
    shot: dict[str, Any] = field(default_factory=dict)
    ball: dict[str, Any] = field(default_factory=dict)  # .basin_ball.check_balls (empty: not run)

    @property
    def array(self) -> np.ndarray:
        """The points as an array (period, 2), consecutive in time."""
        return np.asarray(self.points, dtype=float).reshape(-1, 2)


class Registry:
    """The attractors found so far, matched within ``tol`` (max norm); ``shoot`` confirms a new
    one by Newton on the FMU, ``ball`` runs its tolerance balls (:func:`.basin_ball.ball_checker`)."""

    def __init__(self, tol: float, shoot: Callable[[np.ndarray], dict[str, Any]] | None = None,
                 found: list[Found] | None = None, ball: Callable[..., dict[str, Any]] | None = None) -> None:
        self.tol = float(tol)
        self.shoot = shoot
        self.ball = ball
        self.found: list[Found] = list(found or [])

    def known(self, strict: bool = False) -> KnownAttractors:
        """The registry as the kernel's early-stop input: one period on an attractor whose
        tolerance balls all reached it recognises a start, else (or ``strict``) two rounds."""
        n = len(self.found)
        width = max([f.period for f in self.found], default=1)
        pts = np.full((n, width, 2), np.nan)
        ent = np.full((n, width), -1, dtype=np.int32)
        for a, f in enumerate(self.found):
            pts[a, : f.period] = f.array
            ent[a, : f.period] = f.entries
        rounds = max(MIN_CONFIRM, CONFIRM_ROUNDS * width)
        confirm = np.array([1 if f.ball.get("inside", False) and not strict else rounds for f in self.found],
                           dtype=np.int32)
        return KnownAttractors(pts, ent, np.array([f.period for f in self.found], dtype=np.int32), self.tol, confirm)

    def add(self, c: Candidate) -> int:
        """The index of ``c``'s attractor, registered (and shot) if new."""
        a = match_known(c, self.known())
        if a >= 0:
            return a
        f = Found(c.period, c.impacts, c.points.tolist(), [int(x) for x in c.entries], c.stuck)
        if self.shoot is not None:
            f.shot = self.shoot(c.points)
        self.found.append(f)
        if self.ball is not None:  # with the strict rule, against every attractor known
            f.ball = self.ball(self.known(strict=True), len(self.found) - 1)
        return len(self.found) - 1

    def merge(self, result: Mapping[str, Any]) -> np.ndarray:
        """A tile's labels with its candidates replaced by registry indices."""
        label = np.asarray(result["label"]).copy()
        for k, c in enumerate(result["candidates"]):
            label[label == CANDIDATE - k] = self.add(c)
        return label


def fingerprint(settings: Mapping[str, Any]) -> str:
    """A short hash of everything that decides a scan's labels."""
    text = json.dumps(settings, sort_keys=True, default=lambda x: np.asarray(x).tolist())
    return hashlib.sha256(text.encode()).hexdigest()[:16]


class TileCheckpoint:
    """Finished tiles and the registry on disk (``None`` directory: nothing kept)."""

    def __init__(self, directory: str | os.PathLike | None, key: str) -> None:
        self.dir = Path(directory) if directory is not None else None
        self.key = key
        if self.dir is None:
            return
        meta = self.dir / "run.json"
        if meta.exists():
            stored = json.loads(meta.read_text()).get("key")
            if stored != key:
                raise CheckpointMismatch("checkpoint", f"{self.dir} holds another basin scan's tiles",
                                         ["grid, parameters or sampling"])
        else:
            self.dir.mkdir(parents=True, exist_ok=True)
            self._atomic(meta, json.dumps({"key": key}).encode())

    def _atomic(self, path: Path, data: bytes) -> None:
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_bytes(data)
        os.replace(tmp, path)

    def registry(self, shoot: Callable[[np.ndarray], dict[str, Any]] | None,
                 ball: Callable[..., dict[str, Any]] | None = None) -> Registry | None:
        """The stored registry (None: none yet)."""
        path = self.dir / "attractors.json" if self.dir else None
        if path is None or not path.exists():
            return None
        data = json.loads(path.read_text())
        return Registry(data["tol"], shoot, [Found(**f) for f in data["found"]], ball)

    def save_registry(self, reg: Registry) -> None:
        if self.dir is not None:
            data = {"tol": reg.tol, "found": [asdict(f) for f in reg.found]}
            self._atomic(self.dir / "attractors.json", json.dumps(data).encode())

    def done(self) -> dict[int, dict[str, np.ndarray]]:
        """Finished tiles: index -> labels and periods run."""
        out: dict[int, dict[str, np.ndarray]] = {}
        if self.dir is None:
            return out
        for p in sorted(self.dir.glob("tile-*.npz")):
            with np.load(p) as z:
                out[int(p.stem.split("-")[1])] = {"label": z["label"], "periods": z["periods"]}
        return out

    def save_tile(self, index: int, label: np.ndarray, periods: np.ndarray) -> None:
        if self.dir is not None:
            path = self.dir / f"tile-{index:05d}.npz"
            tmp = path.with_name(path.stem + ".tmp.npz")
            np.savez(tmp, label=label, periods=periods)
            os.replace(tmp, path)
