"""Progress bars (tqdm) for long runs, on stderr so that stdout stays parseable."""
from __future__ import annotations

import sys
from typing import Any


class NullBar:
    """What a disabled bar does (nothing), without importing tqdm: its import, with the package
    metadata it reads, costs about 50 ms, a sixth of a small basin scan on the batch kernel."""

    def __init__(self, total: int, initial: int = 0) -> None:
        self.total, self.n = total, initial

    def update(self, k: int = 1) -> None:
        """Count ``k`` more done."""
        self.n += k

    def refresh(self) -> None:
        """Nothing to draw."""

    def close(self) -> None:
        """Nothing to close."""

    def __enter__(self) -> "NullBar":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def progress_bar(total: int, desc: str, unit: str = "it", initial: int = 0, disable: bool = False) -> Any:
    """A tqdm bar; ``disable`` gives a :class:`NullBar`, whose ``update``/``close`` do nothing.

    ``mininterval`` keeps the overhead negligible even when updated once per period.
    """
    if disable:
        return NullBar(total, initial)
    from tqdm.auto import tqdm

    return tqdm(total=total, initial=initial, desc=desc, unit=unit, disable=disable,
                file=sys.stderr, mininterval=0.5, dynamic_ncols=True, leave=True)
