"""The fuzzer's corpus (tests/fuzz_corpus/) replayed on every platform.

tests/fmu/test_fuzz_fmi.py replays each sequence natively, in Python through ctypes, under the
sanitizers. Here the same sequences, written as text, go through tests/host/corpus_replay.c (a C
port of tests/fuzz/executor.py's actions and oracle) built for each target, with the binaries
from the FMUs: natively, under wine and under qemu-user. Every sequence must pass the oracle on
every platform, and each platform must refuse exactly the calls the native binary refuses
(the count of refused calls after every action is the same).
"""
from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from tests.support.fmu import FMU3_PATH, FMU_PATH
from tests.fuzz.model import _parse
from tests.support.platforms import (CROSS, NATIVE, PLATFORMS, TOKEN, env,
                                    require_cross_build, to_hex, unpack)

pytestmark = pytest.mark.slow  # replays the fuzz corpus on every platform

ROOT = Path(__file__).resolve().parents[2]
CORPUS = sorted((ROOT / "tests" / "fuzz_corpus").glob("*.json"))
PORTED_CORRUPTIONS = {"none", "bitflip", "nan", "inf", "zero_word"}
# One sequence takes 7 s natively (a doStep of 1e8 periods with no wall, ended by the FMU's step
# budget) and some 100 s under qemu's emulation: it runs natively and under wine, not under qemu.
NOT_EMULATED = {"aarch64-linux": {"F7-bounded-wall0-dostep-1e8"}}


def expected(platform: str) -> list[str]:
    """The corpus sequences replayed on `platform`."""
    return [p.stem for p in CORPUS if p.stem not in NOT_EMULATED.get(platform, set())]


def _vars_line(tag: str, xml: Path, version: int) -> str:
    desc = _parse(xml, version, xml)
    parts = [tag]
    for kind in ("real", "int", "bool"):
        vrs = [v.vr for v in desc.of_kind(kind)]
        parts += [str(len(vrs)), *map(str, vrs)]
    time_vr = next((v.vr for v in desc.variables if v.causality == "independent"), -1)
    parts += [str(time_vr), str(desc.n_states), str(desc.n_indicators)]
    return " ".join(parts)


def _hex_or_dash(x) -> str:
    return "-" if x is None else to_hex(x)


def _action(a: dict) -> str:
    op = a["op"]
    head = f"A {int(a.get('repeat', 1))} {int(bool(a.get('must_pass')))} {op}"
    if op in ("setup", "enter_init"):
        return f"{head} {to_hex(a['start'])} {_hex_or_dash(a['tol'])}"
    if op == "set":
        assert len(a["vrs"]) == 1 and a["kind"] in ("real", "int"), a
        value = to_hex(a["values"][0]) if a["kind"] == "real" else str(int(a["values"][0]))
        return f"{head} {a['kind'][0]} {a['vrs'][0]} {value}"
    if op == "step":
        mode = "now" if a["t"] == "now" else "abs"
        assert a["t"] in ("now",) or isinstance(a["t"], (int, float)), a
        return f"{head} {mode} {to_hex(0.0 if mode == 'now' else a['t'])} {to_hex(a['h'])}"
    if op in ("get_state", "set_state", "roundtrip"):
        return f"{head} {a['slot']}"
    if op == "deser":
        assert a["corrupt"] in PORTED_CORRUPTIONS, a
        offset = -1 if a.get("offset") is None else a["offset"]
        return (f"{head} {a['slot']} {a['src']} {a['corrupt']} {to_hex(a.get('pos', 0.0))} "
                f"{a.get('bit', 0)} {offset} {int(bool(a['set']))}")
    if op == "set_x":
        return f"{head} {len(a['x'])} " + " ".join(map(to_hex, a["x"]))
    if op == "me_get":
        assert not a.get("n_delta"), a
        return f"{head} {a['what']}"
    if op == "integrate":
        return f"{head} {to_hex(a['h'])} {a['n']}"
    if op == "foreign":
        return f"{head} {to_hex(a['h'])}"
    assert op in ("exit_init", "reset", "get_all", "update", "enter_cont"), f"action {op} not ported"
    return head


def corpus_text(md2: Path, md3: Path, names: list[str]) -> str:
    """The corpus sequences `names` in corpus_replay.c's input format."""
    lines = [_vars_line("V2", md2, 2), _vars_line("V3", md3, 3)]
    for path in (p for p in CORPUS if p.stem in names):
        seq = json.loads(path.read_text())["sequence"]
        lines.append(f"SEQ {path.stem} {seq['interface']} {int(bool(seq.get('expect_error')))}")
        lines += [_action(a) for a in seq["actions"]]
        lines.append("END")
    return "\n".join(lines) + "\n"


def replay(platform, fmi2: Path, fmi3: Path, text: str) -> dict[str, list[str]]:
    exe = CROSS / platform.name / "host" / ("corpus_replay.exe" if platform.suffix == ".dll" else "corpus_replay")
    cmd = [*platform.runner, str(exe), platform.binary("fmi2"), str(Path("..") / "fmi3" / platform.binary("fmi3")),
           TOKEN]
    proc = subprocess.run(cmd, input=text, capture_output=True, text=True, cwd=fmi2, env=env(), timeout=300)
    assert proc.returncode == 0, f"{cmd}: {proc.returncode} {proc.stderr[-2000:]}"
    out: dict[str, list[str]] = {}
    for line in proc.stdout.splitlines():
        if line.startswith("SEQ "):
            current = out.setdefault(line.split()[1], [])
        else:
            current.append(line)
    return out


@pytest.fixture(scope="module")
def traces(tmp_path_factory) -> dict[str, dict[str, list[str]]]:
    require_cross_build()
    base = tmp_path_factory.mktemp("corpus")
    fmi2, fmi3 = unpack(FMU_PATH, base / "fmi2"), unpack(FMU3_PATH, base / "fmi3")
    mds = fmi2 / "modelDescription.xml", fmi3 / "modelDescription.xml"
    # wine's server ends itself after its last program (no kill: see tests/platforms/test_platforms.py)
    return {p.name: replay(p, fmi2, fmi3, corpus_text(*mds, expected(p.name))) for p in PLATFORMS}


@pytest.mark.parametrize("plat", [p.name for p in PLATFORMS])
def test_every_sequence_passes_the_oracle(traces, plat):
    got = traces[plat]
    assert sorted(got) == sorted(expected(plat))
    failed = {name: lines[-1] for name, lines in got.items() if not lines or lines[-1] != "PASS"}
    assert not failed, failed


@pytest.mark.parametrize("plat", [p.name for p in PLATFORMS if p is not NATIVE])
def test_each_platform_refuses_what_the_native_binary_refuses(traces, plat):
    native = traces[NATIVE.name]
    differ = [name for name, lines in traces[plat].items() if lines != native[name]]
    assert not differ, {n: (traces[plat][n][-3:], native[n][-3:]) for n in differ[:3]}
