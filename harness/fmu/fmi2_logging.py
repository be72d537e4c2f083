"""FMI 2.0 logger callbacks that stay valid for the whole process (fmpy's logger proxy).

An FMI 2.0 logger is variadic (printf-style), which ctypes cannot receive, so fmpy's
``addLoggerProxy(callbacks)`` replaces ``callbacks.logger`` by a C function that formats the
message and forwards it to the Python logger. That C function keeps the Python logger in ONE
process-global pointer (``s_logger`` in fmpy's ``logging`` library), overwritten by every call:
every FMI 2.0 instance in the process whose callbacks go through the proxy (fmpy's own default
callbacks included, proxied when ``fmpy.fmi2`` is imported) logs to the logger given last.

Giving it a per-instance ctypes callback therefore made the pointer dangle as soon as that
instance and its callback were garbage collected: the next message of any other proxied
instance (the first error it reports, e.g. a refused ``fmi2ExitInitializationMode``) jumped into
freed memory. That was the intermittent segfault that depended on which tests had run before in
the same process; before the crash, such messages went to the wrong instance's log.

Here the proxy is only ever handed :data:`_DISPATCH`, one module-level callback that is never
freed, and each instance gets a distinct ``componentEnvironment`` token that the FMU passes back
with every message (FMI 2.0, 2.1.5): the dispatcher hands the message to that instance's
handler, and prints messages of instances it does not know (fmpy's default callbacks pass
NULL), as fmpy's default logger does.
"""
from __future__ import annotations

import ctypes
import itertools
import threading
from typing import Callable, Optional

from fmpy import calloc, free
from fmpy.fmi2 import (
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.logging import addLoggerProxy

#: handler(instance_name, status, category, message), the strings decoded ('' for NULL)
Handler = Callable[[str, int, str, str], None]

_LABELS = ("OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING")
_handlers: dict[int, Handler] = {}
_lock = threading.Lock()
_tokens = itertools.count(1)


def _text(b: Optional[bytes]) -> str:
    return b.decode("utf-8", "replace") if b else ""


def _dispatch(env: Optional[int], instance: Optional[bytes], status: int,
              category: Optional[bytes], message: Optional[bytes]) -> None:
    handler = _handlers.get(env or 0)
    if handler is not None:
        handler(_text(instance), status, _text(category), _text(message))
    else:  # fmpy's default callbacks, or an instance whose handler was released
        label = _LABELS[status] if 0 <= status < len(_LABELS) else str(status)
        print(f"[{label}] {_text(message)}")


# Module-level, so never collected: the only logger ever given to fmpy's proxy by this project.
_DISPATCH = fmi2CallbackLoggerTYPE(_dispatch)


def repoint_proxy() -> None:
    """Points fmpy's proxy at the immortal dispatcher (undoing a per-instance logger that
    other code, e.g. ``fmpy.simulate_fmu(logger=...)``, may have given it)."""
    cb = fmi2CallbackFunctions()
    cb.logger = _DISPATCH
    addLoggerProxy(ctypes.byref(cb))


class Fmi2Callbacks:
    """The callback functions of one FMI 2.0 instance, its messages going to `handler`.

    Pass :attr:`functions` to ``FMU2Slave.instantiate(callbacks=...)``; keep this object until
    the instance is freed, then call :meth:`release`. Messages that arrive after the release
    (there should be none) are printed instead of reaching freed memory.
    """

    def __init__(self, handler: Handler) -> None:
        with _lock:
            self.token = next(_tokens)
            _handlers[self.token] = handler
        self.functions = fmi2CallbackFunctions()
        self.functions.logger = _DISPATCH
        self.functions.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.functions.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self.functions.componentEnvironment = ctypes.c_void_p(self.token)
        # the proxy now calls _DISPATCH for every proxied instance, this one included
        addLoggerProxy(ctypes.byref(self.functions))

    def release(self) -> None:
        with _lock:
            _handlers.pop(self.token, None)


repoint_proxy()  # fmpy's default callbacks stay safe whatever was proxied before this import
