"""Fixtures of the FMU's own tests: the real C FMU through fmpy, its log collected."""
from __future__ import annotations

from typing import Iterator

import pytest

from tests.support.fmu import LoggedSlave


def _open(request: pytest.FixtureRequest) -> Iterator[LoggedSlave]:
    """One FMI 2.0 Co-Simulation instance named after the test module; freed afterwards.

    A module that needs the FMU's debug log from the start sets ``FMU_LOGGING = True``.
    """
    name = request.module.__name__.rsplit(".", 1)[-1].removeprefix("test_")
    s = LoggedSlave(name=name, logging=getattr(request.module, "FMU_LOGGING", False))
    yield s
    s.close()


@pytest.fixture
def fmu(request: pytest.FixtureRequest) -> Iterator[LoggedSlave]:
    """A fresh instance per test: for tests that leave it in an error state or mid-run."""
    yield from _open(request)


@pytest.fixture(scope="module")
def module_fmu(request: pytest.FixtureRequest) -> Iterator[LoggedSlave]:
    """One instance per module, for modules whose every test restarts it (``LoggedSlave.start``):
    extracting and instantiating the archive once per test would dominate their run time."""
    yield from _open(request)
