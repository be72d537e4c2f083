"""FMU states in a fuzzed sequence: taken, restored, serialised, corrupted, deserialised, and
taken from the other interface type (ME <-> CS) of the same binary.

:class:`StateActions` is the part of :class:`tests.fuzz.executor.Executor` that checks the rules
on states: ``not-atomic`` (a refused restore leaves every variable as it was) and ``roundtrip``
(a state serialised and deserialised restores the very same variables).
"""
from __future__ import annotations

import math
import struct
from typing import Any

from tests.fuzz.bindings import OK
from tests.fuzz.oracle import PASSED, Violation, same_values


def corrupt(data: bytes, how: str, pos: float, bit: int, offset: int | None = None) -> bytes:
    """A serialised FMU state damaged in one way, deterministically.

    Parameters
    ----------
    data : bytes
        The serialised state.
    how : str
        One of sequences.CORRUPTIONS, or "none".
    pos : float
        Where, as a fraction of the length (ignored where `offset` is given).
    bit : int
        Which bit to flip (bitflip), or a small variation for the other kinds.
    offset : int, optional
        Where, as a byte offset.

    Returns
    -------
    bytes
        The damaged copy.
    """
    if not data or how == "none":
        return data
    b = bytearray(data)
    i = min(len(b) - 1, int(pos * len(b)) if offset is None else offset)
    i8 = min(max(0, len(b) - 8), i - i % 8)
    if how == "bitflip":
        b[i] ^= 1 << bit
    elif how in ("nan", "inf"):
        b[i8:i8 + 8] = struct.pack("<d", math.nan if how == "nan" else -math.inf)[: len(b) - i8]
    elif how == "zero_word":
        i4 = i - i % 4
        b[i4:i4 + 4] = bytes(min(4, len(b) - i4))
    elif how == "truncate":
        del b[max(1, i):]
    elif how == "extend":
        b += bytes(8 * (bit + 1))
    elif how == "zeros":
        b = bytearray(len(b))
    elif how == "random_body":
        for k in range(8, len(b)):
            b[k] = (b[k] * 131 + k * 7 + bit) & 0xFF
    elif how == "swap_halves":
        h = len(b) // 2
        b = b[h:] + b[:h]
    return bytes(b)



class StateActions:
    """The state actions of :class:`tests.fuzz.executor.Executor` (which provides ``lib``,
    ``slots``, ``slot_values``, ``blobs``, ``me``, ``calls``, ``_check``, ``snapshot`` ...)."""

    def _set_state(self, state: int | None, fn: str) -> int:
        before = self.snapshot_quiet()
        st = self._check(fn, self.lib.set_state(state))
        if st in PASSED:
            self.snapshot()
        elif before is not None:
            after = self.snapshot_quiet()
            if after is not None and not same_values(before, after):
                raise Violation("not-atomic", f"refused {fn} changed the variables")
        return st

    def _roundtrip(self, slot: int) -> None:
        state = self.slots[slot]
        if state is None:
            return
        st, data = self.lib.serialize(state)
        if self._check("serialize", st) not in PASSED:
            return
        st, p = self.lib.deserialize(data, None)
        if self._check("deserialize", st) not in PASSED:
            raise Violation("roundtrip", f"own serialised state refused: {self.last_message()}")
        try:
            st = self._set_state(p, "set_state(roundtrip)")
            expected = self.slot_values[slot]
            if st in PASSED and expected is not None:
                got = self.snapshot()
                if got is not None and not same_values(expected, got):
                    diff = [(i, e, g) for i, (e, g) in enumerate(zip(expected, got)) if e != g]
                    raise Violation("roundtrip", f"restored values differ: {diff[:4]}")
        finally:
            self._check("free_state", self.lib.free_state(p)[0])

    def _deser(self, a: dict[str, Any]) -> None:
        src = a["src"]
        if src == "foreign":
            data = self.blobs.get("foreign")
        else:
            state = self.slots[int(src[4:])]
            if state is None:
                return
            st, data = self.lib.serialize(state)
            if self._check("serialize", st) not in PASSED:
                return
        if not data:
            return
        data = corrupt(data, a["corrupt"], a.get("pos", 0.0), a.get("bit", 0), a.get("offset"))
        st, p = self.lib.deserialize(data, self.slots[a["slot"]])
        if self._check("deserialize", st) in PASSED:
            self.slots[a["slot"]] = p
            self.slot_values[a["slot"]] = None
            if a["set"]:
                self._set_state(p, f"set_state(deserialized {src}, {a['corrupt']})")

    def _foreign_state(self, h: float) -> bytes:
        """A serialised state of the other interface type (ME <-> CS) of the same binary."""
        other = type(self.lib)(self.lib.desc)
        self.calls += 1
        if not other.instantiate(not self.me):
            return b""
        try:
            for fn, st in (("setup", other.setup(0.0, None)), ("enter_init", other.enter_init(0.0, None)),
                           ("exit_init", other.exit_init())):
                self._check(f"foreign {fn}", st)
            if not self.me and h:  # the other one is ME: move its state a little
                other.set_time(h)
            elif h:
                other.do_step(0.0, h)
            st, p = other.get_state(None)
            data = other.serialize(p)[1] if st == OK else b""
            other.free_state(p)
            self.calls += 4
            return data
        finally:
            other.free()
