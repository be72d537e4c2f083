"""The pythonfmu twin's column of the state-machine conformance suite.

The twin (build/fmu/ImpactOscillatorPy.fmu, FMI 2.0 Co-Simulation) is judged against the same
standard table as the C FMU (tests/support/fmi_standard.py, "fmi2-cs"): every (state, function) pair,
each on a fresh instance. The twin runs only inside a Python process (pythonfmu's binary needs
the host's libpython), and a wrong call can crash its host, so each state's cases run in a
child process; a crash there is a failure of that state, with the cases done before it.

Criteria (the twin's messages are its own, so the state is judged from outside):

* allowed: not Error, except where the twin does not provide the function (TWIN_NOT_PROVIDED);
* not allowed: Error (never Fatal), and then the Error state: fmi2GetReal answers, fmi2Terminate
  is refused.

Functions the twin's binary does not export (Model Exchange: it is a Co-Simulation-only FMU)
are not called: 31 functions x 5 states.
"""
from __future__ import annotations

import json
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from tests.support import fmi_standard as std

ROOT = Path(__file__).resolve().parents[2]
TWIN = ROOT / "build" / "fmu" / "ImpactOscillatorPy.fmu"
VR_SIGMA = 2  # the twin has no inputs: sigma (tunable) is the Real every setter state accepts
TWIN_NOT_PROVIDED = {
    "fmi2GetRealOutputDerivatives", "fmi2CancelStep",
    "fmi2GetStatus", "fmi2GetIntegerStatus", "fmi2GetBooleanStatus", "fmi2GetStringStatus",
    "fmi2SetRealInputDerivatives",
}


def _binding(unzipped: Path):  # noqa: ANN202 (tests.fuzz.bindings.Fmi2)
    """A fuzz binding of the twin's binary, instantiated with its own resources."""
    import ctypes as C

    from tests.fuzz.bindings import Fmi2
    from tests.fuzz.model import _parse

    lib = next((unzipped / "binaries").glob("*/*.so"))
    desc = _parse(unzipped / "modelDescription.xml", 2, lib)

    class Twin(Fmi2):
        def _fn(self, name: str, restype: object, *argtypes: object) -> None:
            if hasattr(self.lib, name):  # a Co-Simulation-only binary: no ME functions
                super()._fn(name, restype, *argtypes)

        def instantiate(self, me: bool, token_ok: bool = True, **_: object) -> bool:
            p = self.lib.fmi2Instantiate(b"twin", 1, desc.token.encode(),
                                         (unzipped / "resources").as_uri().encode(),
                                         C.byref(self._cb), 0, 0)
            self.inst = p or None
            return self.inst is not None
    return Twin(desc)


def run_state(state: str, unzipped: Path) -> list[dict]:
    """All cases of one state, in this process: one dict per function."""
    from tests.support.fmi_probes import Instance, calls, drive
    from tests.fuzz.bindings import ERROR, FATAL

    out = []
    for fn in sorted(std.FMI2):
        if not hasattr(_binding(unzipped).lib, fn):
            continue  # not exported (Model Exchange functions of a Co-Simulation-only FMU)
        x = Instance("fmi2-cs", binding=_binding(unzipped), set_real_vr=VR_SIGMA)
        try:
            drive(x, state)
            allowed = state in std.allowed("fmi2-cs", fn)
            st = calls(x)[fn]()
            if fn == "fmi2FreeInstance":
                x.p = None
                out.append({"fn": fn, "ok": True, "why": "freed"})
                continue
            if st == FATAL:
                ok, why = False, "Fatal"
            elif allowed:
                ok = st != ERROR or fn in TWIN_NOT_PROVIDED
                why = f"allowed, returned {st}"
            else:
                c = calls(x)
                get, term = c["fmi2GetReal"](), c["fmi2Terminate"]()
                ok = st == ERROR and get == 0 and term == ERROR
                why = f"not allowed, returned {st}; then GetReal {get}, Terminate {term}"
            out.append({"fn": fn, "ok": ok, "why": why})
        finally:
            x.free()
    return out


@pytest.fixture(scope="module")
def unzipped(tmp_path_factory: pytest.TempPathFactory) -> Path:
    if not TWIN.is_file():
        pytest.fail(f"{TWIN} missing: run scripts/setup.sh (it builds the twin)")
    d = tmp_path_factory.mktemp("twin")
    zipfile.ZipFile(TWIN).extractall(d)
    return d


@pytest.mark.parametrize("state", std.STATES_FMI2_CS)
def test_twin_state_machine(state: str, unzipped: Path) -> None:
    code = ("import json, sys; from pathlib import Path; "
            "from tests.twin.test_fmi_conformance import run_state; "
            f"print(json.dumps(run_state({state!r}, Path({str(unzipped)!r}))))")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, f"the twin's host process died in {state}: {r.stderr[-2000:]}"
    cases = json.loads(r.stdout.strip().splitlines()[-1])
    assert len(cases) >= len([f for f in std.FMI2 if std.allowed("fmi2-cs", f)])
    bad = [c for c in cases if not c["ok"]]
    assert not bad, f"{len(bad)} of {len(cases)} cases in {state}: {bad}"
