"""Fixtures shared by the harness tests: the real FMU, as the harness sees it."""
from __future__ import annotations

import pytest

from harness import FmuModel, FmuSimulator
from tests.fmu_support import FMU_PATH


@pytest.fixture(scope="session")
def model() -> FmuModel:
    assert FMU_PATH.is_file(), f"build the FMU first ({FMU_PATH} missing): bash scripts/setup.sh"
    return FmuModel(FMU_PATH)


@pytest.fixture(scope="module")
def sim(model: FmuModel) -> FmuSimulator:
    return FmuSimulator(model.source())
