"""Output files: checked before a run starts, written atomically next to their target.

A run that takes minutes must not fail at its end because ``--out`` names a directory or a
place the user cannot write; :func:`check_output` finds that before any work is done.
:func:`atomic_write` writes through a uniquely named temporary file in the target's own
directory (never ``OUT.tmp`` beside a directory like ``/tmp``), renames it over the target,
and removes it on every failure.
"""
from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path
from typing import Iterator

from ..errors import HarnessInputError


def check_output(path: str | os.PathLike, argument: str) -> Path:
    """Return ``path`` if a file can be written there; create its parent directories.

    Raises
    ------
    HarnessInputError
        If ``path`` is an existing directory, its parent cannot be created, or the
        parent is not writable.
    """
    p = Path(path).expanduser()
    if p.is_dir():
        raise HarnessInputError(argument, f"{str(path)!r} is a directory; give a file name")
    if p.exists() and not os.access(p, os.W_OK):
        raise HarnessInputError(argument, f"cannot write {str(path)!r}: permission denied")
    parent = p.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise HarnessInputError(argument, f"cannot create the directory of {str(path)!r}: {exc.strerror or exc}") from None
    # Try it: os.access says yes to root everywhere, also on read-only mounts and /proc.
    try:
        fd, probe = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".probe", dir=parent)
    except OSError as exc:
        raise HarnessInputError(argument, f"cannot write to the directory {str(parent)!r}: {exc.strerror or exc}") from None
    os.close(fd)
    os.unlink(probe)
    return p


#: Image formats matplotlib writes (checked before a run, so a typo costs nothing).
PLOT_FORMATS = ("png", "pdf", "svg", "svgz", "eps", "ps", "jpg", "jpeg", "tif", "tiff", "webp", "pgf", "gif",
                "avif", "raw", "rgba")


def check_plot(path: str | os.PathLike, argument: str = "--plot") -> Path:
    """:func:`check_output` for a plot, whose suffix must be an image format."""
    suffix = Path(path).suffix.lstrip(".").lower()
    if suffix and suffix not in PLOT_FORMATS:
        raise HarnessInputError(argument, f"unknown image format {suffix!r}; use one of {', '.join(PLOT_FORMATS)}")
    return check_output(path, argument)


def _umask() -> int:
    """This process's umask, read without changing it (os.umask would, for every thread)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except OSError:  # pragma: no cover - not Linux
        pass
    return 0o022


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike, argument: str = "--out") -> Iterator[Path]:
    """Yield a temporary path next to ``path``; on success it replaces ``path``.

    The temporary name is unique (several runs may write to one directory) and hidden;
    it is removed if the body or the rename fails.  Failures to write are reported as
    :class:`HarnessInputError` naming ``argument`` (a one-line message in the CLI).
    """
    target = check_output(path, argument)
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    except OSError as exc:
        raise HarnessInputError(argument, f"cannot write {str(path)!r}: {exc.strerror or exc}") from None
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        # mkstemp creates the file 0600; a result file gets the mode any new file would
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, target)
    except OSError as exc:
        raise HarnessInputError(argument, f"cannot write {str(path)!r}: {exc.strerror or exc}") from None
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
