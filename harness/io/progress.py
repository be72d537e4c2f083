"""Progress bars (tqdm) for long runs, on stderr so that stdout stays parseable."""
from __future__ import annotations

import sys
from typing import Any


def progress_bar(total: int, desc: str, unit: str = "it", initial: int = 0, disable: bool = False) -> Any:
    """A tqdm bar; ``disable`` gives a bar whose ``update``/``close`` do nothing.

    ``mininterval`` keeps the overhead negligible even when updated once per period.
    """
    from tqdm.auto import tqdm

    return tqdm(total=total, initial=initial, desc=desc, unit=unit, disable=disable,
                file=sys.stderr, mininterval=0.5, dynamic_ncols=True, leave=True)
