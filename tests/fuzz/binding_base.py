"""What the FMI 2.0 and FMI 3.0 bindings (tests/fuzz/bindings.py) share: the status codes, the C
library's calloc/free (so that AddressSanitizer sees every allocation the FMU makes through the
callbacks), the ctypes shorthands and :class:`_Base` (the library, its log, the instance)."""
from __future__ import annotations

import ctypes as C
from typing import Any

from tests.fuzz.model import Description

__all__ = ["OK", "WARNING", "DISCARD", "ERROR", "FATAL"]

OK, WARNING, DISCARD, ERROR, FATAL = 0, 1, 2, 3, 4

_libc = C.CDLL(None)
_libc.calloc.restype = C.c_void_p
_libc.calloc.argtypes = [C.c_size_t, C.c_size_t]
_libc.free.argtypes = [C.c_void_p]

_P = C.c_void_p
_D = C.c_double
_SZ = C.c_size_t
_DP = C.POINTER(C.c_double)
_UP = C.POINTER(C.c_uint)


def _arr(ctype: Any, values: list) -> Any:
    return (ctype * max(1, len(values)))(*values)


class _Base:
    """What both bindings share: the library, the logger's last message, the instance pointer."""

    version = 0

    def __init__(self, desc: Description) -> None:
        self.desc = desc
        self.lib = C.CDLL(str(desc.library))
        self.inst: int | None = None
        self.messages: list[str] = []
        self._declare()

    def _fn(self, name: str, restype: Any, *argtypes: Any) -> None:
        f = getattr(self.lib, name)
        f.restype = restype
        f.argtypes = list(argtypes)

    def _declare(self) -> None:  # pragma: no cover - overridden
        raise NotImplementedError

    def log(self, status: int, category: bytes | None, message: bytes | None) -> None:
        if len(self.messages) > 50:
            del self.messages[:25]
        self.messages.append(f"[{status}] {(category or b'').decode(errors='replace')}: "
                             f"{(message or b'').decode(errors='replace')}")
