"""Fixtures shared by the harness tests: the real FMU, as the harness sees it."""
from __future__ import annotations

import os

import pytest

from harness import FmuModel, FmuSimulator
from tests.support.fmu import FMU_PATH


@pytest.fixture(scope="session")
def model() -> FmuModel:
    assert FMU_PATH.is_file(), f"build the FMU first ({FMU_PATH} missing): bash scripts/setup.sh"
    return FmuModel(FMU_PATH)


@pytest.fixture(scope="module")
def sim(model: FmuModel) -> FmuSimulator:
    return FmuSimulator(model.source())


@pytest.fixture(autouse=True)
def _same_working_directory():
    """Every test starts where the last one did: fmpy changes into a binary's folder to load it
    and stays there when the load fails (tests load broken binaries on purpose), and a worker
    runs many files, so one such test made relative paths fail in unrelated later ones."""
    cwd = os.getcwd()
    yield
    if os.getcwd() != cwd:
        os.chdir(cwd)
