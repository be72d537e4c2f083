"""FMI 2.0 log messages through fmpy's logger proxy (harness/fmu/fmi2_logging.py).

fmpy's proxy forwards every proxied FMI 2.0 instance's messages to ONE process-global logger,
the one given last. A ctypes callback per instance would send other instances' messages to that
instance's log, and once it was collected, to freed memory (a segfault at the refused
closed-form initialisation, depending on which test files ran before it). These tests run the
real FMU through plain fmpy; the subprocess one runs that pattern (a per-instance callback gives
exit status -11 there, every run, measured).
"""
from __future__ import annotations

import gc
import os
import subprocess
import sys
from pathlib import Path

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

from tests.support.fmu import FMU3_PATH, FMU_PATH, LoggedSlave, ROOT

REFUSAL = "solver = 1 (closed form) needs the linear contact law"


def _plain_refused(name: str) -> None:
    """The refused configuration on a plain fmpy FMU2Slave (fmpy's default callbacks)."""
    md = read_model_description(str(FMU_PATH))
    f = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(FMU_PATH)),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    f.instantiate()
    try:
        f.setupExperiment(startTime=0.0)
        f.enterInitializationMode()
        f.setInteger([5, 17, 31], [1, 1, 1])  # compliant wall, Hertz, closed form
        with pytest.raises(FMICallException):
            f.exitInitializationMode()
    finally:
        f.freeInstance()


def test_each_instance_logs_to_its_own_logger(capsys: pytest.CaptureFixture) -> None:
    """Two logged instances and a plain one: every message reaches its own instance's logger
    (with one ctypes logger per instance, all went to the one created last)."""
    a, b = LoggedSlave(name="a"), LoggedSlave(name="b")
    try:
        for s, contact in ((a, 1), (b, 2)):
            with pytest.raises(FMICallException):
                s.start(0.0, wall=1, contact=contact, solver=1)
        _plain_refused("plain")
        assert len(a.errors()) == 1 and "contact = 1 (Hertz)" in a.errors()[0]
        assert len(b.errors()) == 1 and "contact = 2 (Hunt-Crossley)" in b.errors()[0]
        assert REFUSAL in capsys.readouterr().out  # the plain instance's, by fmpy's default
    finally:
        a.close()
        b.close()


def test_plain_fmpy_refusal_after_collected_loggers(capsys: pytest.CaptureFixture) -> None:
    """A logged instance closed and collected, then a plain fmpy instance reports an error: it
    must not call a collected callback (segfault)."""
    for k in range(3):
        s = LoggedSlave(name=f"short{k}")
        s.start(0.0)
        s.step_to(0.5)
        s.close()
        del s
        gc.collect()
        _plain_refused(f"plain{k}")
    assert capsys.readouterr().out.count(REFUSAL) == 3


@pytest.mark.skipif(not FMU3_PATH.exists(), reason="FMI 3.0 FMU not built")
def test_refused_init_reproducer_in_a_subprocess() -> None:
    """The reproducer (tests/support/refused_init_process.py: FMI 2.0 and 3.0, CS and ME, logging on and
    off, another instance alive) with glibc's heap checks and freed memory overwritten."""
    env = dict(os.environ, MALLOC_PERTURB_="165", MALLOC_CHECK_="3", PYTHONPATH=str(ROOT))
    res = subprocess.run([sys.executable, "-m", "tests.support.refused_init_process", "4"], cwd=ROOT,
                         env=env, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, f"rc {res.returncode}\n{res.stdout[-2000:]}\n{res.stderr[-2000:]}"
    assert res.stdout.count("needs the linear contact law") == 4 * 4  # rounds x interfaces
    assert "round 3 done" in res.stdout


def test_no_other_code_hands_fmpy_a_logger_of_its_own() -> None:
    """Only harness/fmu/fmi2_logging.py calls fmpy's addLoggerProxy (and the reproducer, for its
    "old" mode): any other ctypes logger given to the proxy would dangle again."""
    allowed = {ROOT / "harness" / "fmu" / "fmi2_logging.py", ROOT / "tests" / "support" / "refused_init_process.py"}
    offenders = [str(p.relative_to(ROOT))
                 for d in ("harness", "tests", "examples", "bench", "mapcheck", "scripts")
                 for p in sorted((ROOT / d).rglob("*.py"))
                 if p not in allowed and p != Path(__file__).resolve()
                 and ("addLoggerProxy" in p.read_text() or "logger=" in p.read_text()
                      and "simulate_fmu" in p.read_text())]
    assert not offenders, offenders
