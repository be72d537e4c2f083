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


def pytest_configure(config) -> None:
    """Keep the file order below: pytest-xdist (3.6+) otherwise hands out whole files
    (each file one group of --dist=loadgroup) by their number of tests, most first, which left the long files with few
    tests (the charts, the benchmark smoke tests) for last, one core busy with them and the other
    idle."""
    if hasattr(config.option, "loadscopereorder"):
        config.option.loadscopereorder = False


@pytest.hookimpl(tryfirst=True)  # before xdist reads the groups into the node ids
def pytest_collection_modifyitems(config, items) -> None:
    """Files with slow tests first (those marked ``spread`` first of all, in their collection
    order), then the others, most tests first.  A file goes to one worker whole (its module
    fixtures run once; some build into fixed folders under build/), unless it is marked ``spread``:
    then each of its tests goes to whichever worker is free (``--dist=loadgroup``), so that a file
    of many long independent tests (random oscillators, the two solvers' reports) keeps both cores
    busy instead of one.  The files start early in this order, and the many short ones fill the
    end evenly on both cores."""
    files: dict = {}
    for item in items:
        files.setdefault(item.path, []).append(item)
    slow = {path: any(i.get_closest_marker("slow") for i in its) for path, its in files.items()}
    spread = {path: any(i.get_closest_marker("spread") for i in its) for path, its in files.items()}
    order = sorted(files, key=lambda path: (not slow[path], not spread[path],
                                            0 if slow[path] else -len(files[path])))
    items[:] = [item for path in order for item in files[path]]
    root = config.rootpath
    for item in items:
        if not spread[item.path]:
            item.add_marker(pytest.mark.xdist_group(str(item.path.relative_to(root))))
