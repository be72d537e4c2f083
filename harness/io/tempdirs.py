"""This process's temporary folder (FMU extraction), removed on every way out.

Each process that extracts an FMU gets one folder ``$TMPDIR/impact-harness-<pid>-XXXX``.
It is removed

* at a normal exit (``atexit``; ``multiprocessing`` children skip ``atexit`` and run
  ``multiprocessing.util`` finalizers instead, so both are registered);
* on SIGTERM, by :func:`remove_now` called from the signal handlers the CLI and the pool
  workers install;
* after a SIGKILL, which no process can catch, by the next run: :func:`remove_stale` deletes
  folders whose owner process (the pid in the name) no longer exists.  Folders of live
  processes, and folders without a pid in their name, are never touched.
"""
from __future__ import annotations

import atexit
import os
import re
import shutil
import tempfile
import threading
from pathlib import Path

PREFIX = "impact-harness-"
_NAME = re.compile(re.escape(PREFIX) + r"(\d+)-[A-Za-z0-9_]+$")

_LOCK = threading.Lock()
_ROOT: str | None = None
_OWNER: int | None = None  # pid that created _ROOT (a forked child must not remove it)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    return True


def remove_stale(base: str | os.PathLike | None = None) -> list[Path]:
    """Delete the folders of processes that died without cleaning up (SIGKILL); return them."""
    base = Path(base or tempfile.gettempdir())
    removed: list[Path] = []
    try:
        # names first, a Path only for ours: a shared /tmp can hold tens of thousands of
        # entries, and a Path each cost 30 ms at every FMU extraction
        names = [n for n in os.listdir(base) if n.startswith(PREFIX)]
    except OSError:
        return removed
    for name in names:
        m = _NAME.match(name)
        if not m or int(m.group(1)) == os.getpid() or _alive(int(m.group(1))):
            continue
        entry = base / name
        try:
            if entry.is_dir() and not entry.is_symlink() and entry.stat().st_uid == os.getuid():
                shutil.rmtree(entry, ignore_errors=True)
                removed.append(entry)
        except OSError:
            continue
    return removed


def root() -> str:
    """This process's temporary folder, created (and stale ones swept) on first use."""
    global _ROOT, _OWNER
    with _LOCK:
        if _ROOT is None or _OWNER != os.getpid():
            remove_stale()
            _ROOT = tempfile.mkdtemp(prefix=f"{PREFIX}{os.getpid()}-")
            _OWNER = os.getpid()
            atexit.register(remove_now)
            try:
                from multiprocessing import util

                util.Finalize(None, remove_now, exitpriority=0)  # at exit of a pool worker
            except Exception:  # pragma: no cover - multiprocessing unavailable
                pass
        return _ROOT


def current() -> str | None:
    """The folder if this process made one (else None)."""
    return _ROOT if _OWNER == os.getpid() else None


def remove_now() -> None:
    """Remove this process's folder (idempotent; safe in a signal handler's last act)."""
    global _ROOT
    path = current()
    if path is not None:
        shutil.rmtree(path, ignore_errors=True)
        _ROOT = None
