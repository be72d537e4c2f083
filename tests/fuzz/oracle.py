"""The oracle's verdict: a :class:`Violation` names the rule a sequence broke (the rules are
listed in tests/fuzz/executor.py); a status in PASSED is a call that succeeded."""
from __future__ import annotations

import math

from tests.fuzz.bindings import OK, WARNING

PASSED = (OK, WARNING)


class Violation(Exception):
    """An oracle violation: `kind` names the rule, the message says what was seen."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(f"{kind}: {message}")
        self.kind = kind


def same_values(a: list, b: list) -> bool:
    return len(a) == len(b) and all(
        x == y or (isinstance(x, float) and isinstance(y, float) and math.isnan(x) and math.isnan(y))
        for x, y in zip(a, b))
