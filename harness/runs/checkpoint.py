"""Checkpoints: finished sweep tasks on disk, so an interrupted sweep resumes.

A checkpoint is a directory with a ``manifest.json`` (the fingerprint of the run: FMU
sha256, parameters, grids, sampling) and one ``.npz`` file per finished task, written
atomically (temporary file + rename), so an interruption at any moment leaves only whole
results.  Resuming with different settings is refused rather than mixing two runs.
"""
from __future__ import annotations

import hashlib
import json
import os
import shutil
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import HarnessInputError


def _json_default(o: Any) -> Any:
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    return repr(o)


def fingerprint(obj: Any) -> str:
    """sha256 of a JSON rendering of ``obj`` (numpy arrays and scalars included)."""
    text = json.dumps(obj, sort_keys=True, default=_json_default)
    return hashlib.sha256(text.encode()).hexdigest()


def _short(value: Any) -> str:
    if isinstance(value, list) and len(value) > 4 and all(isinstance(v, (int, float)) for v in value):
        return f"{len(value)} values {value[0]:g}..{value[-1]:g}"
    text = json.dumps(value, sort_keys=True)
    return text if len(text) <= 40 else text[:37] + "..."


def differences(stored: Any, current: Any, prefix: str = "") -> list[str]:
    """What differs between two run identities (JSON renderings), e.g.
    ``["params.sigma: 0.5 -> 0.3", "values: 31 values 0.1..1 -> 41 values 0.1..1"]``."""
    if isinstance(stored, dict) and isinstance(current, dict):
        out = []
        for key in sorted(set(stored) | set(current)):
            name = f"{prefix}{key}"
            if key not in stored:
                out.append(f"{name}: (none) -> {_short(current[key])}")
            elif key not in current:
                out.append(f"{name}: {_short(stored[key])} -> (none)")
            else:
                out += differences(stored[key], current[key], name + ".")
        return out
    if stored != current:
        name = prefix.rstrip(".")
        if name == "fmu":
            return ["fmu: another FMU binary (sha256 differs)"]
        return [f"{name}: {_short(stored)} -> {_short(current)}"]
    return []


class CheckpointMismatch(HarnessInputError):
    """The checkpoint directory holds another run's results; :attr:`changes` says what differs."""

    def __init__(self, argument: str, reason: str, changes: list[str] | None = None) -> None:
        super().__init__(argument, reason)
        self.changes = list(changes or [])

    def __reduce__(self) -> tuple:
        return (type(self), (self.argument, self.reason, self.changes))


class Checkpoint:
    """Finished tasks of one run, stored in ``directory``.

    Parameters
    ----------
    directory : path
        Created if missing.
    run_fingerprint : str
        Identifies the run; an existing checkpoint with another fingerprint is an error.
    argument : str
        Name used in error messages (``"checkpoint"``, the argument of :func:`harness.run_sweep`).
    """

    def __init__(self, directory: str | os.PathLike, run_fingerprint: str, argument: str = "checkpoint",
                 identity: Any = None) -> None:
        self.directory = Path(directory)
        self.fingerprint = run_fingerprint
        manifest = self.directory / "manifest.json"
        # the identity (parameters, grids, sampling, FMU hash) is kept beside its hash so that a
        # mismatch can say what changed
        current = None if identity is None else json.loads(json.dumps(identity, sort_keys=True,
                                                                      default=_json_default))
        if manifest.exists():
            try:
                record = json.loads(manifest.read_text())
                stored = record["fingerprint"]
            except (ValueError, KeyError, TypeError):
                raise HarnessInputError(argument, f"{self.directory} is not a harness checkpoint") from None
            if stored != run_fingerprint:
                changes = (differences(record["identity"], current)
                           if current is not None and "identity" in record else [])
                what = "; ".join(changes) if changes else "other parameters or FMU"
                raise CheckpointMismatch(
                    argument,
                    f"{self.directory} holds a checkpoint of a different run ({what}); "
                    "delete it or choose another directory", changes)
        else:
            try:
                self.directory.mkdir(parents=True, exist_ok=True)
                manifest.write_text(json.dumps({"fingerprint": run_fingerprint, "identity": current}))
            except OSError as exc:
                raise HarnessInputError(argument, f"cannot create the checkpoint {str(self.directory)!r}: "
                                        f"{exc.strerror or exc}") from None

    def _file(self, key: str) -> Path:
        safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in key)
        return self.directory / f"{safe}.npz"

    def has(self, key: str) -> bool:
        """True when task ``key`` is finished and stored."""
        return self._file(key).exists()

    @staticmethod
    def _write(target: Path, arrays: dict[str, np.ndarray]) -> None:
        """Write ``arrays`` to ``target`` atomically (a killed run leaves the old file or none)."""
        tmp = target.with_suffix(".tmp.npz")
        np.savez(tmp, **arrays)
        os.replace(tmp, target)

    def save(self, key: str, arrays: dict[str, np.ndarray]) -> None:
        """Store one finished task atomically."""
        self._write(self._file(key), arrays)

    # -- unfinished chains ------------------------------------------------------------------
    def _partial_file(self, key: str) -> Path:
        return self._file(key).with_suffix(".partial.npz")

    def save_partial(self, key: str, arrays: dict[str, np.ndarray]) -> None:
        """Store the finished leading points of an unfinished chain (rows of each array),
        atomically, replacing the previous ones."""
        self._write(self._partial_file(key), arrays)

    def load_partial(self, key: str) -> dict[str, np.ndarray] | None:
        """The stored leading points of chain ``key`` (None if there are none)."""
        f = self._partial_file(key)
        if not f.exists():
            return None
        with np.load(f) as data:
            return {k: data[k] for k in data.files}

    def remove_partial(self, key: str) -> None:
        """Forget the leading points of ``key`` (its whole result is stored now)."""
        self._partial_file(key).unlink(missing_ok=True)

    def load(self, key: str) -> dict[str, np.ndarray]:
        """The stored arrays of task ``key``."""
        with np.load(self._file(key)) as data:
            return {k: data[k] for k in data.files}

    def remove(self) -> None:
        """Delete the checkpoint (after the final results are written)."""
        shutil.rmtree(self.directory, ignore_errors=True)
