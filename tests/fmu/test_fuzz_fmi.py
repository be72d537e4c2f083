"""The FMI fuzzer on the ASan + UBSan build of the FMU.

* ``test_fuzz``: a fixed seed and IMPACT_FUZZ_SEQUENCES (default 2000) random FMI 2.0/3.0 call
  sequences; any sanitizer report, crash, hang (20 s per sequence) or oracle violation
  (tests/fuzz/executor.py) fails it, with each failing sequence's seed and a minimised version.
  More on demand: ``IMPACT_FUZZ_SEQUENCES=100000 IMPACT_FUZZ_SEED=7 pytest tests/fmu/test_fuzz_fmi.py``.
* ``test_corpus``: every sequence in tests/fuzz_corpus/ (minimised fuzzer finds and the inputs
  of the reported failures) replays cleanly.
* The rest checks the fuzzer itself: the sanitizer is live in its child process, sequences are
  reproducible from their seed, corruption and minimisation do what they say.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.fuzz import runner
from tests.fuzz.fmu_states import corrupt
from tests.fuzz.model import ROOT, describe
from tests.fuzz.sequences import Generator

pytestmark = pytest.mark.slow  # builds the ASan + UBSan FMU and fuzzes it

CORPUS = sorted((ROOT / "tests" / "fuzz_corpus").glob("*.json"))

# Findings still open in fmu_src (see the "finding" field of each corpus file); an entry here marks its corpus files xfail (not strict) until
# the fix lands, then it is deleted.
OPEN_FINDINGS: dict[str, str] = {}

def _require_toolchain(fn):
    """Fail (not skip) without cmake/gcc: the sanitizer checks must be able to fail CI."""
    import functools

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        missing = [t for t in ("cmake", "gcc") if shutil.which(t) is None]
        if missing:
            pytest.fail(f"{', '.join(missing)} missing: run scripts/setup.sh (it installs them)")
        return fn(*args, **kwargs)
    return wrapper


needs_toolchain = _require_toolchain


@pytest.fixture(scope="session")
def asan_build() -> Path:
    return runner.build_sanitized()


def _open(finding: str) -> pytest.MarkDecorator | None:
    reason = OPEN_FINDINGS.get(finding)
    return pytest.mark.xfail(reason=f"{finding} open: {reason}", strict=False) if reason else None


def _corpus_params() -> list:
    out = []
    for f in CORPUS:
        finding = json.loads(f.read_text()).get("finding", "")
        mark = _open(finding)
        out.append(pytest.param(f, id=f.stem, marks=[mark] if mark else []))
    return out


@needs_toolchain
@pytest.mark.parametrize("path", _corpus_params())
def test_corpus(asan_build: Path, path: Path) -> None:
    doc = json.loads(path.read_text())
    res = runner.replay(asan_build, doc["sequence"], timeout=float(doc.get("timeout", 20)))
    assert res["kind"] is None, f"{doc['id']} ({doc.get('why', '')}): {res['kind']}: {res['message']}"


@needs_toolchain
def test_fuzz(asan_build: Path) -> None:
    n = int(os.environ.get("IMPACT_FUZZ_SEQUENCES", "2000"))
    seed = int(os.environ.get("IMPACT_FUZZ_SEED", "13"))
    rep = runner.fuzz(asan_build, n, seed=seed, timeout=20.0)
    print(rep.summary())
    assert rep.sequences == n
    assert rep.calls > 100 * n  # the sequences reach the running states, not just instantiate
    assert not rep.failures, rep.summary() + "\nminimal: " + json.dumps(
        [f.get("minimal") for f in rep.failures[:3]])


@needs_toolchain
def test_sanitizer_is_live_in_the_child(asan_build: Path) -> None:
    """A heap overflow in the fuzzer's child process is reported and classified as ASan."""
    code = ("import ctypes; libc = ctypes.CDLL(None); libc.malloc.restype = ctypes.c_void_p;"
            "p = libc.malloc(8); ctypes.memset(p, 0, 16)")
    res = subprocess.run([sys.executable, "-c", code], env=runner.child_env(asan_build),
                         capture_output=True, text=True, timeout=60)
    assert res.returncode != 0
    assert runner.crash_kind(res.returncode, res.stderr) == "asan", res.stderr[-2000:]


def test_sequences_are_reproducible_from_the_seed() -> None:
    for version in (2, 3):
        gen = Generator(describe(ROOT / "build" / "fmu", version))
        for seed in range(version, 200, 2):
            a, b = gen.sequence(seed), gen.sequence(seed)
            assert json.dumps(a) == json.dumps(b)
    interfaces = {Generator(describe(ROOT / "build" / "fmu", 3)).sequence(s)["interface"]
                  for s in range(1, 400, 2)}
    assert interfaces == {"fmi3cs", "fmi3cs_event", "fmi3cs_intermediate", "fmi3me"}


def test_corruptions_change_the_bytes_deterministically() -> None:
    data = bytes((i * 37) % 251 for i in range(500))
    for how in ("bitflip", "nan", "inf", "zero_word", "truncate", "extend", "zeros",
                "random_body", "swap_halves"):
        a = corrupt(data, how, 0.37, 3)
        assert a != data, how
        assert a == corrupt(data, how, 0.37, 3), how
    assert corrupt(data, "zero_word", 0.0, 0, offset=8)[8:12] == bytes(4)
    assert corrupt(data, "none", 0.5, 0) == data


def test_minimise_keeps_what_the_failure_needs() -> None:
    seq = {"interface": "fmi2cs", "actions": [{"op": "x", "i": i} for i in range(40)]}

    def fails(s: dict) -> bool:
        ids = {a["i"] for a in s["actions"]}
        return {3, 17, 31} <= ids

    small = runner.minimise(seq, fails)
    assert [a["i"] for a in small["actions"]] == [3, 17, 31]


def test_the_standard_model_flags_an_illegal_call_answered_ok() -> None:
    """The fuzzer's state-machine oracle: fed the calls of an FMU that accepts a call
    the standard forbids, it reports; the standard's transitions move it (Error -> error state,
    FMI 3.0 -> Terminated; Reset -> Instantiated; SetFMUState -> unknown, not judged)."""
    from tests.fuzz.standard_model import StateModel

    found: list[str] = []
    m = StateModel("fmi2cs")
    m.feed("fmi2DoStep", 0, found.append)  # doStep in Instantiated answered OK
    assert found and "fmi2DoStep" in found[0]
    m.feed("fmi2SetupExperiment", 3, found.append)  # allowed, failed: Error state
    assert m.state == "Error"
    m.feed("fmi2Terminate", 0, found.append)  # not allowed in Error
    assert len(found) == 2
    m.feed("fmi2Reset", 0, found.append)
    assert m.state == "Instantiated"
    m3 = StateModel("fmi3cs_event")
    for f in ("fmi3EnterInitializationMode", "fmi3ExitInitializationMode"):
        m3.feed(f, 0, found.append)
    assert m3.state == "Event"
    m3.feed("fmi3DoStep", 3, found.append)  # refused as it must be: no finding, Terminated
    assert m3.state == "Terminated" and len(found) == 2
    m3.feed("fmi3SetFMUState", 0, found.append)
    m3.feed("fmi3DoStep", 0, found.append)  # unknown state: not judged
    assert len(found) == 2
