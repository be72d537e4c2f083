"""Fixtures of the twin's tests: the twin FMU (rebuilt when older than its sources), the C FMU,
and one fmpy instance of the twin per module."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Iterator

import pytest

from tests.support.twin import C_FMU, ROOT, TWIN_FMU, TWIN_SRC, Slave


@pytest.fixture(scope="module")
def twin_fmu() -> Path:
    """The twin as the set-up script builds it; rebuilt here if missing or older than its
    sources, so that the tests never run a stale twin."""
    sources = [*TWIN_SRC.glob("*.py"), *TWIN_SRC.glob("*.c")]
    if not TWIN_FMU.exists() or max(p.stat().st_mtime for p in sources) > TWIN_FMU.stat().st_mtime:
        subprocess.run(
            [sys.executable, str(TWIN_SRC / "build.py"), "--out", str(TWIN_FMU)],
            check=True, cwd=ROOT, capture_output=True,
        )
    return TWIN_FMU


@pytest.fixture(scope="module")
def c_fmu() -> Path:
    assert C_FMU.exists(), f"{C_FMU} missing: build it with scripts/setup.sh"
    return C_FMU


@pytest.fixture(scope="module")
def twin(twin_fmu: Path) -> Iterator[Slave]:
    s = Slave(twin_fmu)
    yield s
    s.close()
