"""Child processes of the harness that go with their parent: pool initialisers ask Linux to
end them when the parent dies (SIGKILL included), and SIGTERM removes their temporary folder.

In the io layer beside :mod:`harness.io.tempdirs` (whose folders they clean up) so that both the
dynamics layer (parallel shooting) and the runs layer (sweep pools) can use them.
"""
from __future__ import annotations

import os
from typing import Any


def init_child_process(parent_pid: int | None = None) -> None:
    """Initializer of any other process pool of the harness (e.g. parallel shooting): the
    process dies with its parent, SIGKILL included, and SIGTERM removes its temporary folder.
    Ctrl-C is left as it is."""
    import signal

    signal.signal(signal.SIGTERM, _exit_on_signal)
    die_with_parent(parent_pid)


def _exit_on_signal(signum: int, frame: Any) -> None:
    # os._exit, not SystemExit: the pool's worker loop catches BaseException from a task and
    # would send it back as a result instead of exiting
    from . import tempdirs

    tempdirs.remove_now()
    os._exit(128 + signum)


def die_with_parent(parent_pid: int | None) -> bool:
    """Ask Linux to send this process SIGTERM when its parent dies, SIGKILL included
    (``prctl(PR_SET_PDEATHSIG)``); without it, workers of a killed sweep wait on their task
    queue as orphans for good.  Returns False where prctl is unavailable (not Linux).

    If the parent died before the request took effect, exit now; a watchdog thread covers
    a death signal that arrives too late to be handled.
    """
    import ctypes
    import signal

    _watch_parent(os.getppid() if parent_pid is None else parent_pid)
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(1, int(signal.SIGTERM), 0, 0, 0) != 0:  # 1 = PR_SET_PDEATHSIG
            return False
    except (OSError, AttributeError):
        return False
    if parent_pid is not None and os.getppid() != parent_pid:
        _exit_on_signal(int(signal.SIGTERM), None)
    return True


def _watch_parent(parent_pid: int, every: float = 1.0) -> None:
    """A daemon thread that ends this process once its parent is gone.

    The kernel closes a dead parent's pipes before it sends the death signal, so a worker
    waiting on its task queue may already be on its way out (EOF) when SIGTERM arrives; a
    Python handler does not run once the interpreter is finalizing, and the signal is then
    lost while the exit can still wait on a thread or a lock.  The watchdog does not depend
    on the signal: it polls the parent (a cheap getppid) and exits as the handler would.
    """
    import signal
    import threading
    import time

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(every)
        _exit_on_signal(int(signal.SIGTERM), None)

    threading.Thread(target=watch, name="die-with-parent", daemon=True).start()
