"""Extreme inputs -- out-of-range parameters, huge and tiny steps, corrupted and foreign FMU
states, runs over the limits, damaged archives, signals -- and the answer the FMU and the CLI give
each: refused with a message, run, or (never) crashed, hung or sanitizer-reported.

    .venv/bin/python -m tests.fuzz.extreme_inputs [--out results/extreme_inputs.md] [--skip-cli]

FMU rows run as call sequences of the fuzzer (this package) in a child process, once on the
release binaries (build/fmu: the answer and its time) and once on the ASan + UBSan build
(build/asan: whether the sanitizers stay silent), each under a time limit. "oracle" is the
fuzzer's verdict (tests/fuzz/executor.py): ok, or the rule broken (nonfinite: a non-finite value
with status OK; bricked: reset does not work after the sequence; refused-valid: a valid call failed;
accepted-extreme: no call refused the input; timeout; ubsan/asan: a sanitizer report).
CLI rows run `python -m harness ...` with a 4 GiB address-space limit and a time limit, and report
the exit status, the first line of stderr, whether a traceback was printed and the peak RSS.
Prints a Markdown table (and writes it to --out).
"""
from __future__ import annotations

import argparse
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path
from typing import Any

from tests.fuzz import runner
from tests.fuzz.model import ROOT, describe

#: Value references by variable name, read from the release build's modelDescription.xml.
VR = {v.name: v.vr for v in describe(runner.RELEASE, 2).variables}
INIT = [{"op": "setup", "start": 0.0, "tol": None}, {"op": "enter_init", "start": 0.0, "tol": None}]
EXIT = {"op": "exit_init"}


def real(name: str, x: float) -> dict[str, Any]:
    return {"op": "set", "kind": "real", "vrs": [VR[name]], "values": [x]}


def wall(kind: int) -> dict[str, Any]:
    return {"op": "set", "kind": "int", "vrs": [VR["wall"]], "values": [kind]}


def step(h: float, repeat: int = 1, must_pass: bool = False, t: Any = "now") -> dict[str, Any]:
    return {"op": "step", "t": t, "h": h, "repeat": repeat, "must_pass": must_pass}


def fmu_rows() -> list[tuple[str, dict[str, Any], float]]:
    """(the input in words, sequence, time limit in seconds)."""
    rows: list[tuple[str, dict[str, Any], float]] = []
    for sigma, gamma in ((0.2, None), (0.5, None), (1.0, None), (0.2, 1e12)):
        acts = INIT + [real("r", 0.0), real("sigma", sigma)] + ([real("Gamma", gamma)] if gamma else [])
        rows.append((f"compliant wall r = 0, sigma {sigma}" + (f", Gamma {gamma:g}" if gamma else "")
                     + ": 100 periods", {"interface": "fmi2cs", "actions": acts + [EXIT, step(1.0, 100, True)]}, 120))
    for r in (0.44, 0.46, 0.48, 0.50, 0.68, 0.6):
        acts = INIT + [wall(2), real("nu", 0.196), real("Omega", 7.368), real("sigma", 10.0),
                       real("u0", -0.03), real("v0", 0.0), real("r", r), EXIT, step(1.0, 100, True)]
        rows.append((f"rigid chatter (nu .196, Omega 7.368, sigma 10, u0 -.03, v0 0), r = {r}: 100 periods",
                     {"interface": "fmi2cs", "actions": acts}, 120))
    for itf in ("fmi2cs", "fmi3cs"):
        rows.append((f"{itf}: state with NaN written into its body (39 positions), set",
                     {"interface": itf, "actions": INIT + [EXIT, step(0.7), {"op": "get_state", "slot": 0}] + [
                         {"op": "deser", "slot": 1, "src": "slot0", "corrupt": "nan", "pos": k / 40, "bit": 0, "set": True}
                         for k in range(8, 40)]}, 30))
        off = 8 if itf == "fmi2cs" else 4
        rows.append((f"{itf}: state whose stored FMI state word is 0, set, then Reset",
                     {"interface": itf, "actions": INIT + [EXIT, step(0.7), {"op": "get_state", "slot": 0},
                      {"op": "deser", "slot": 1, "src": "slot0", "corrupt": "zero_word", "offset": off, "set": True},
                      {"op": "reset"}]}, 30))
    rows.append(("fmi2 CS snapshot set into an ME instance, then fmi2DoStep",
                 {"interface": "fmi2me", "actions": INIT + [EXIT, {"op": "foreign", "h": 0.3},
                  {"op": "deser", "slot": 0, "src": "foreign", "corrupt": "none", "set": True},
                  step(0.1, t=0.3)]}, 30))
    for name, x in (("Omega", 1.7976931348623157e308), ("sigma", 1e308), ("sigma", 1e295), ("u0", -1e296)):
        rows.append((f"{name} = {x:.4g}, then doStep(0, 2)",
                     {"interface": "fmi2cs", "expect_error": True,
                      "actions": INIT + [real(name, x), EXIT, step(2.0), {"op": "get_all"}]}, 30))
    rows.append(("ME SetContinuousStates([0.001, 1e308]), GetDerivatives",
                 {"interface": "fmi2me", "actions": INIT + [EXIT, {"op": "update"}, {"op": "enter_cont"},
                  {"op": "set_x", "x": [0.001, 1e308]}, {"op": "me_get", "what": "der"}]}, 30))
    for h in (1e14, 1e300):
        rows.append((f"doStep(0, {h:g})", {"interface": "fmi2cs", "actions": INIT + [EXIT, step(h)]}, 30))
    rows.append(("wall = 0, doStep(0, 1e300)", {"interface": "fmi2cs",
                 "actions": INIT + [wall(0), EXIT, step(1e300)]}, 30))
    rows.append(("Omega = 1e10, doStep(0, 0.01)", {"interface": "fmi2cs",
                 "actions": INIT + [real("Omega", 1e10), EXIT, step(0.01)]}, 30))
    # the same work inside the valid ranges: must end with the work limit, not run for hours
    rows.append(("(in range) wall = 0, doStep(0, 1e8)", {"interface": "fmi2cs",
                 "actions": INIT + [wall(0), EXIT, step(1e8)]}, 120))
    rows.append(("(in range) Omega = 1e4, doStep(0, 10)", {"interface": "fmi2cs",
                 "actions": INIT + [real("Omega", 1e4), EXIT, step(10.0)]}, 120))
    for h in (1e-300, 5e-324):
        rows.append((f"doStep(0, {h:g}), then doStep(t, 0.5)", {"interface": "fmi2cs",
                     "actions": INIT + [EXIT, step(h, must_pass=True), step(0.5, must_pass=True)]}, 30))
    rows.append(("startTime = 1e300, doStep(1e300, 1)", {"interface": "fmi2cs", "expect_error": True,
                 "actions": [{"op": "setup", "start": 1e300, "tol": None},
                             {"op": "enter_init", "start": 1e300, "tol": None}, EXIT, step(1.0)]}, 30))
    return rows


def answer(res: dict[str, Any]) -> str:
    errs = res.get("errors") or []
    if res["kind"] in ("timeout", "asan", "ubsan") or str(res["kind"]).startswith("crash"):
        return f"{res['kind']}: {(res.get('message') or '').splitlines()[0][:160] if res.get('message') else ''}"
    if errs:
        text = errs[0].split("logStatusError: ", 1)[-1]
        return f"refused: {text[:200]}" + (f" (+{len(errs) - 1} more)" if len(errs) > 1 else "")
    return "OK" if res["kind"] is None else f"OK ({res['message'][:160]})"


# ------------------------------------------------------------------------------------------
# CLI


def _limit() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))
    os.setsid()


def run_cli(args: list[str], timeout: float, cwd: Path, tmpdir: Path) -> dict[str, Any]:
    """Runs the CLI in its own session with TMPDIR=`tmpdir`; the peak RSS is the main process's
    (os.wait4), the exit status "timeout" after `timeout` seconds (the session is killed)."""
    t0 = time.perf_counter()
    with tempfile.TemporaryFile("w+") as errf:
        p = subprocess.Popen([sys.executable, "-m", "harness", *args], cwd=cwd,
                             stdout=subprocess.DEVNULL, stderr=errf, preexec_fn=_limit,
                             env={**os.environ, "PYTHONPATH": str(ROOT), "TMPDIR": str(tmpdir)})
        timed_out, status, ru = False, 0, None
        while True:
            pid, status, ru = os.wait4(p.pid, os.WNOHANG)
            if pid:
                break
            if time.perf_counter() - t0 > timeout:
                os.killpg(p.pid, signal.SIGKILL)  # the session we started (setsid above)
                pid, status, ru = os.wait4(p.pid, 0)
                timed_out = True
                break
            time.sleep(0.05)
        p.returncode = os.waitstatus_to_exitcode(status)
        errf.seek(0)
        err = errf.read()
    lines = [ln for ln in err.splitlines() if ln.strip() and "%|" not in ln]
    return {"rc": "timeout" if timed_out else p.returncode, "seconds": time.perf_counter() - t0,
            "first": lines[0][:160] if lines else "", "lines": len(lines),
            "traceback": "Traceback" in err, "maxrss_mb": ru.ru_maxrss / 1024 if ru else 0.0}


def _session(sid: int) -> list[str]:
    """Command lines of the live processes of session `sid` (zombies excluded)."""
    out = []
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            stat = (proc / "stat").read_text()
            fields = stat[stat.rindex(")") + 2:].split()
            if int(fields[3]) == sid and fields[0] != "Z":
                out.append((proc / "cmdline").read_bytes().replace(b"\0", b" ").decode()[:60])
        except (OSError, ValueError, IndexError):
            continue
    return out


def interrupt_run(sig: signal.Signals, tmp: Path, tmpdir: Path) -> str:
    """A 2-worker sweep, signalled once its workers run: what is left 3 s later."""
    o = tmp / f"kill_{sig.name}.nc"
    p = subprocess.Popen([sys.executable, "-m", "harness", "sweep", "--num", "60", "--workers", "2",
                          "--transient", "100", "--samples", "50", "--out", str(o), "--no-plot",
                          "--no-progress"], cwd=tmp, stdout=subprocess.DEVNULL,
                         stderr=subprocess.PIPE, text=True, preexec_fn=os.setsid,
                         env={**os.environ, "PYTHONPATH": str(ROOT), "TMPDIR": str(tmpdir)})
    t0 = time.perf_counter()
    while len(_session(p.pid)) < 3 and time.perf_counter() - t0 < 30 and p.poll() is None:
        time.sleep(0.1)
    time.sleep(1.0)
    n_before = len(_session(p.pid))
    if p.poll() is not None:
        return f"finished before the signal (exit {p.returncode}): {p.stderr.read()[-200:]}"
    if sig == signal.SIGKILL:
        os.kill(p.pid, sig)  # the main process only, as a crash or the OOM killer would
    else:
        os.killpg(p.pid, sig)  # Ctrl-C reaches the whole foreground group
    try:
        _, err = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        err = "(no exit within 60 s)"
    time.sleep(3.0)
    left = _session(p.pid)
    if left:
        os.killpg(p.pid, signal.SIGKILL)  # clean up what we started
    first = next((ln for ln in err.splitlines() if ln.strip()), "")[:120]
    return (f"{n_before} processes before, exit {p.returncode}, {len(left)} left 3 s later"
            f"{' (' + '; '.join(left) + ')' if left else ''}; stderr: {first}")


def cli_rows(tmp: Path) -> list[tuple[str, list[str]]]:
    fmu = ROOT / "build" / "fmu" / "ImpactOscillator.fmu"
    garbage = tmp / "garbage.fmu"
    with zipfile.ZipFile(fmu) as zin, zipfile.ZipFile(garbage, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item)
            zout.writestr(item, os.urandom(len(data)) if item.filename.endswith(".so") else data)
    crc = tmp / "crc.fmu"
    raw = bytearray(fmu.read_bytes())
    with zipfile.ZipFile(fmu) as z:
        so = next(i for i in z.infolist() if i.filename.endswith(".so"))
    mid = so.header_offset + 30 + len(so.filename) + so.compress_size // 2
    raw[mid] ^= 0xFF
    crc.write_bytes(bytes(raw))
    bad_toml = tmp / "bad.toml"
    bad_toml.write_bytes(b"[fmu]\nname = \"\xff\xfe\"\n")
    blocker = tmp / "a_file"
    blocker.write_text("x")
    o = str(tmp / "o.nc")
    q = ["--no-progress", "--no-plot"]
    return [
        ("sweep --num 1e9", ["sweep", "--num", "1e9", "--out", o, *q]),
        ("sweep --scan Gamma=1:10:1000000", ["sweep", "--scan", "Gamma=1:10:1000000", "--out", o, *q]),
        ("sweep --samples 1e9", ["sweep", "--samples", "1e9", "--num", "3", "--out", o, *q]),
        ("sweep --transient 1e12", ["sweep", "--transient", "1e12", "--num", "3", "--out", o, *q]),
        ("simulate --dt 1e-9", ["simulate", "--dt", "1e-9", "--out", o, *q]),
        ("simulate --fmu (garbage .so)", ["simulate", "--fmu", str(garbage), "--out", o, *q]),
        ("simulate --fmu (CRC-corrupt .so)", ["simulate", "--fmu", str(crc), "--out", o, *q]),
        ("simulate --config non-UTF-8.toml", ["simulate", "--config", str(bad_toml), "--out", o, *q]),
        ("simulate --config DIRECTORY", ["simulate", "--config", str(tmp), "--out", o, *q]),
        ("simulate --out UNWRITABLE", ["simulate", "--out", str(blocker / "o.nc"), *q]),
        ("simulate --plot UNWRITABLE", ["simulate", "--out", o, "--plot", str(blocker / "p.png"), "--no-progress"]),
    ]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--skip-cli", action="store_true")
    ap.add_argument("--skip-asan", action="store_true")
    ap.add_argument("--benchmarks", action="store_true",
                    help="also write the table as the 'fuzz' section of BENCHMARKS.md")
    args = ap.parse_args()
    release = runner.RELEASE
    asan = None if args.skip_asan else runner.build_sanitized()
    lines = ["| input | answer (release FMU) | s | oracle | ASan+UBSan |",
             "|---|---|---|---|---|"]
    for text, seq, limit in fmu_rows():
        res = runner.replay(release, seq, timeout=limit)
        san = runner.replay(asan, seq, timeout=limit)["kind"] if asan else "-"
        san_txt = "clean" if san in (None, "nonfinite", "bricked", "refused-valid", "accepted-extreme",
                                     "me-dostep", "not-atomic", "roundtrip") else san
        secs = f"{res['seconds']:.2f}" if res.get("seconds") is not None else f">{limit:g}"
        lines.append(f"| {text} | {answer(res)} | {secs} | {res['kind'] or 'ok'} | {san_txt} |")
        print(lines[-1], flush=True)
    if not args.skip_cli:
        lines += ["", "| CLI input | exit | s | stderr lines | traceback | peak RSS MB | first line |",
                  "|---|---|---|---|---|---|---|"]
        with tempfile.TemporaryDirectory() as d:
            tmp = Path(d)
            private = tmp / "tmpdir"  # the CLI's TMPDIR: what it leaves there is its own
            private.mkdir()
            for text, argv in cli_rows(tmp):
                r = run_cli(argv, 60.0, tmp, private)
                lines.append(f"| {text} | {r['rc']} | {r['seconds']:.1f} | {r['lines']} | "
                             f"{'yes' if r['traceback'] else 'no'} | {r['maxrss_mb']:.0f} | {r['first']} |")
                print(lines[-1], flush=True)
            r = run_cli(["simulate", "--t-end", "1", "--out", "/tmp", "--no-plot", "--no-progress"], 60.0,
                        tmp, private)
            left = Path("/tmp.tmp").exists()
            lines.append(f"| simulate --out /tmp | {r['rc']} | {r['seconds']:.1f} | {r['lines']} | "
                         f"{'yes' if r['traceback'] else 'no'} | {r['maxrss_mb']:.0f} | {r['first']}; "
                         f"/tmp.tmp left: {'yes' if left else 'no'} |")
            for sig in (signal.SIGKILL, signal.SIGINT):
                lines.append(f"| sweep --workers 2, {sig.name} once running | "
                             f"{interrupt_run(sig, tmp, private)} | | | | | |")
                print(lines[-1], flush=True)
            left_tmp = sorted(p.name for p in private.iterdir())
            lines.append(f"\nleft in the CLI's TMPDIR by these runs: {left_tmp or 'nothing'}")
    text = "\n".join(lines)
    print(text)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n")
    if args.benchmarks:
        from bench.sections import write_section

        write_section(ROOT / "BENCHMARKS.md", "<!-- fuzz:begin -->\n## Extreme inputs and the answer "
                      "each gets\n\n`.venv/bin/python -m tests.fuzz.extreme_inputs "
                      "--benchmarks` (one run; FMU rows: release build for the answer and its seconds, "
                      "ASan + UBSan build for the sanitizer column; \"oracle\" is the fuzzer's verdict, "
                      "tests/fuzz/executor.py).\n\n" + text + "\n<!-- fuzz:end -->")
    return 0


if __name__ == "__main__":
    sys.exit(main())
