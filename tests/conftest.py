"""Fixtures shared by the harness tests: the real FMU, as the harness sees it."""
from __future__ import annotations

import os
import signal

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
    """Keep the file order below: pytest-xdist (3.6+) otherwise hands out whole files by their
    number of tests, most first, which left the long files with few tests (the charts, the
    benchmark smoke tests) for last, one core busy with them and the other idle."""
    if hasattr(config.option, "loadscopereorder"):
        config.option.loadscopereorder = False
    # A run started in the background by a non-interactive shell ignores SIGINT, and the CLI
    # processes the tests interrupt would inherit that (exit 0 where an interrupt means 130): give
    # this process a handler, which its children start from as the default.
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


#: Files of many long tests that share no fixture wider than a test (the session's FMU aside): their
#: tests go one by one to whichever worker is free; as whole files they kept one core busy for
#: minutes after the other had finished.  Every other file goes to one worker whole.
SPREAD = frozenset({
    "tests/analysis/test_random_oscillators.py",
    "tests/analysis/test_solvers_agree.py",
    "tests/analysis/test_chart_random.py",
    "tests/analysis/test_chart_below_grazing.py",
    "tests/analysis/test_chart_flip_closings.py",
    "tests/analysis/test_fig9_graze_edges.py",
    "tests/project/test_docs_examples.py",
})


def pytest_collection_modifyitems(config, items) -> None:
    """Files with slow tests first (the :data:`SPREAD` ones first of all, in their collection
    order), then the others, most tests first: the files that take long start early and the many
    short ones fill the end evenly on both cores."""
    files: dict = {}
    for item in items:
        files.setdefault(item.path, []).append(item)
    root = config.rootpath
    slow = {path: any(i.get_closest_marker("slow") for i in its) for path, its in files.items()}
    spread = {path: path.relative_to(root).as_posix() in SPREAD for path in files}
    order = sorted(files, key=lambda path: (not slow[path], not spread[path],
                                            0 if slow[path] else -len(files[path])))
    items[:] = [item for path in order for item in files[path]]


def pytest_xdist_make_scheduler(config, log):
    """A whole file per worker (its module fixtures run once; some build into fixed folders under
    build/), except the :data:`SPREAD` files, whose tests are handed out one by one.  (xdist's own
    ``loadgroup`` would do this with marks, but under pytest 9.2 its group suffix no longer
    reaches the node ids, and every test was handed out alone.)"""
    from xdist.scheduler import LoadScopeScheduling

    class FileOrTestScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            path = nodeid.split("::", 1)[0]
            return nodeid if path in SPREAD else path

    return FileOrTestScheduling(config, log)
