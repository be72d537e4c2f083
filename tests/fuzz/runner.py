"""Runs the fuzzer in a child process (sanitizer runtime preloaded) and minimises failures.

``python -m tests.fuzz.runner fuzz --build build/asan --sequences 3000`` fuzzes and prints a JSON
summary; ``... replay FILE.json`` replays a stored sequence. The parent restarts the child after a
crash (sanitizer report, signal, or the per-sequence time limit enforced by faulthandler inside
the child), so one run reports every failing sequence, each by its seed.

Findings are minimised by deleting actions while the same rule (or the same crash) still fails:
in the child for oracle violations, with one subprocess per try for crashes and hangs.
"""
from __future__ import annotations

import argparse
import faulthandler
import json
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from tests.fuzz.model import ROOT, describe

SANITIZED = ROOT / "build" / "asan"
RELEASE = ROOT / "build" / "fmu"


def seed_of(base: int, i: int) -> int:
    """The seed of sequence i of a run with base seed `base` (even: FMI 2.0, odd: FMI 3.0)."""
    return base * 1_000_003 + i


# ------------------------------------------------------------------------------------------
# building and the child's environment


def build_sanitized(build: Path = SANITIZED) -> Path:
    """Configures and builds the ASan + UBSan FMU binaries (cmake -DIMPACT_SANITIZE=ON)."""
    if not (build / "CMakeCache.txt").is_file():
        subprocess.run(["cmake", "-S", str(ROOT / "fmu_src"), "-B", str(build),
                        "-DIMPACT_SANITIZE=ON", "-DCMAKE_BUILD_TYPE=Release"],
                       check=True, capture_output=True)
    subprocess.run(["cmake", "--build", str(build), "-j", "2"], check=True, capture_output=True)
    return build


def is_sanitized(build: Path) -> bool:
    cache = build / "CMakeCache.txt"
    return cache.is_file() and "IMPACT_SANITIZE:BOOL=ON" in cache.read_text()


def child_env(build: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    if is_sanitized(build):
        libasan = subprocess.run(["gcc", "-print-file-name=libasan.so"], capture_output=True,
                                 text=True, check=True).stdout.strip()
        env["LD_PRELOAD"] = libasan
        # Python itself "leaks" at exit by design; leaks of the FMU are valgrind's (test_valgrind)
        env["ASAN_OPTIONS"] = "detect_leaks=0:halt_on_error=1:abort_on_error=0:exitcode=86"
        env["UBSAN_OPTIONS"] = "halt_on_error=1:print_stacktrace=1:exitcode=87"
    return env


# ------------------------------------------------------------------------------------------
# the child: runs sequences in-process


class Child:
    """Both bindings of one build, and the generators of both FMI versions."""

    def __init__(self, build: Path) -> None:
        from tests.fuzz.bindings import Fmi2, Fmi3
        from tests.fuzz.sequences import Generator

        self.libs = {2: Fmi2(describe(build, 2)), 3: Fmi3(describe(build, 3))}
        self.gens = {v: Generator(lib.desc) for v, lib in self.libs.items()}

    def execute(self, seq: dict[str, Any], detail: dict | None = None) -> tuple[int, str | None, str]:
        """Runs `seq`; returns (calls, violated rule or None, message).

        `detail`, if given, receives the FMU's refusals ("errors") and the variables after the
        last action ("final")."""
        from tests.fuzz.executor import Executor, Violation
        from tests.fuzz.sequences import version_of

        lib = self.libs[version_of(seq["interface"])]
        lib.messages.clear()
        ex = Executor(lib, seq["interface"])
        try:
            ex.run(seq["actions"], expect_error=bool(seq.get("expect_error")))
        except Violation as v:
            return ex.calls, v.kind, f"{v} (FMU said: {ex.last_message()})"
        finally:
            if detail is not None:
                detail["errors"] = ex.errors
                detail["final"] = getattr(ex, "final", None)
        return ex.calls, None, ""


def minimise(seq: dict[str, Any], fails: Callable[[dict[str, Any]], bool],
             budget: int = 400) -> dict[str, Any]:
    """Deletes chunks of actions, then single ones, while `fails` still holds (ddmin-like).

    Parameters
    ----------
    seq : dict
        A sequence ({"interface", "actions", ...}).
    fails : callable
        True where a candidate still shows the failure (same rule or same crash).
    budget : int
        Most candidates tried.

    Returns
    -------
    dict
        `seq` with the fewest actions found that still fail.
    """
    acts = list(seq["actions"])
    chunk = max(1, len(acts) // 2)
    tries = 0
    while chunk >= 1 and tries < budget:
        i, shrunk = 0, False
        while i < len(acts) and tries < budget:
            cand = acts[:i] + acts[i + chunk:]
            tries += 1
            if fails({**seq, "actions": cand}):
                acts, shrunk = cand, True
            else:
                i += chunk
        if not shrunk:
            chunk //= 2
    return {**seq, "actions": acts}


def child_fuzz(args: argparse.Namespace) -> None:
    child = Child(Path(args.build))
    calls = done = 0
    found: list[dict[str, Any]] = []
    kinds_minimised: set[str] = set()
    slowest = (0.0, -1)
    t_start = time.perf_counter()
    for i in range(args.start, args.start + args.count):
        seed = seed_of(args.seed, i)
        seq = child.gens[2 if seed % 2 == 0 else 3].sequence(seed)
        print(f"BEGIN {i}", flush=True)
        faulthandler.dump_traceback_later(args.timeout, exit=True)
        t0 = time.perf_counter()
        n, kind, msg = child.execute(seq)
        dt = time.perf_counter() - t0
        slowest = max(slowest, (dt, seed))
        calls += n
        done += 1
        print(f"END {i} {n}", flush=True)
        if kind:
            entry: dict[str, Any] = {"seed": seed, "kind": kind, "message": msg}
            if args.minimise and kind not in kinds_minimised:
                kinds_minimised.add(kind)
                small = minimise(seq, lambda s: child.execute(s)[1] == kind)
                entry["minimal"] = small
                entry["minimal_message"] = child.execute(small)[2]
            found.append(entry)
            print("VIOLATION " + json.dumps(entry), flush=True)
        faulthandler.cancel_dump_traceback_later()
    print("DONE " + json.dumps({"sequences": done, "calls": calls, "violations": len(found),
                                "seconds": time.perf_counter() - t_start,
                                "slowest_sequence": {"seconds": slowest[0], "seed": slowest[1]}}),
          flush=True)


def child_replay(args: argparse.Namespace) -> None:
    """Replays stored sequences; prints one RESULT line each (a crash ends the process)."""
    child = Child(Path(args.build))
    for path in args.files:
        data = json.loads(Path(path).read_text())
        seq = data.get("sequence", data)
        print(f"BEGIN {path}", flush=True)
        faulthandler.dump_traceback_later(float(data.get("timeout", args.timeout)), exit=True)
        detail: dict = {}
        t0 = time.perf_counter()
        n, kind, msg = child.execute(seq, detail)
        faulthandler.cancel_dump_traceback_later()
        print("RESULT " + json.dumps({"file": str(path), "calls": n, "kind": kind,
                                      "message": msg, "seconds": time.perf_counter() - t0,
                                      **detail}), flush=True)


# ------------------------------------------------------------------------------------------
# the parent


@dataclass
class Report:
    """What a fuzz run found: counts, oracle violations, crashes (sanitizer, signal, hang)."""

    sequences: int = 0
    calls: int = 0
    seconds: float = 0.0
    violations: list[dict[str, Any]] = field(default_factory=list)
    crashes: list[dict[str, Any]] = field(default_factory=list)
    slowest: dict[str, Any] = field(default_factory=dict)

    @property
    def failures(self) -> list[dict[str, Any]]:
        return self.violations + self.crashes

    def summary(self) -> str:
        lines = [f"{self.sequences} sequences, {self.calls} calls, {self.seconds:.1f} s, "
                 f"{len(self.violations)} oracle violations, {len(self.crashes)} crashes/hangs"]
        for f in self.failures[:20]:
            lines.append(f"  seed {f['seed']}: {f['kind']}: {f.get('message', '')[:600]}")
        return "\n".join(lines)


def crash_kind(rc: int, stderr: str) -> str:
    if "AddressSanitizer" in stderr or "LeakSanitizer" in stderr:
        return "asan"
    if "runtime error:" in stderr:
        return "ubsan"
    if "Timeout (" in stderr:
        return "timeout"
    if "Traceback (most recent call last)" in stderr:
        return "python-error"  # a bug of the fuzzer itself
    return f"crash(rc={rc})"


def _child(build: Path, argv: list[str], timeout: float) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "tests.fuzz.runner", *argv, "--build", str(build)]
    try:
        return subprocess.run(cmd, cwd=ROOT, env=child_env(build), capture_output=True,
                              text=True, timeout=timeout)
    except subprocess.TimeoutExpired as e:  # faulthandler did not fire (should not happen)
        return subprocess.CompletedProcess(cmd, -9, e.stdout or "", "Timeout (parent)")


def fuzz(build: Path, sequences: int, seed: int = 13, timeout: float = 20.0,
         minimise_crashes: bool = True) -> Report:
    """Runs `sequences` sequences, restarting the child after every crash.

    Parameters
    ----------
    build : Path
        CMake build directory of the FMU (build/asan: sanitizers preloaded in the child).
    sequences : int
        Number of sequences; sequence i has seed ``seed_of(seed, i)``.
    seed : int
        Base seed of the run.
    timeout : float
        Seconds one sequence may take before it counts as a hang.
    minimise_crashes : bool
        Minimise the first crash of each kind and place (one subprocess per try).

    Returns
    -------
    Report
        Counts of sequences and FMI calls, oracle violations and crashes, each with its seed.
    """
    rep = Report()
    start, t0 = 0, time.perf_counter()
    while start < sequences:
        argv = ["fuzz", "--seed", str(seed), "--start", str(start),
                "--count", str(sequences - start), "--timeout", str(timeout), "--minimise"]
        res = _child(build, argv, timeout * (sequences - start) + 120)
        last = start
        for line in res.stdout.splitlines():
            if line.startswith("BEGIN "):
                last = int(line.split()[1])
            elif line.startswith("END "):
                rep.calls += int(line.split()[2])
                rep.sequences += 1
            elif line.startswith("VIOLATION "):
                rep.violations.append(json.loads(line[10:]))
            elif line.startswith("DONE "):
                d = json.loads(line[5:])
                if d["slowest_sequence"]["seconds"] > rep.slowest.get("seconds", 0.0):
                    rep.slowest = d["slowest_sequence"]
        if "DONE " in res.stdout:
            break
        s = seed_of(seed, last)
        kind = crash_kind(res.returncode, res.stderr)
        crash: dict[str, Any] = {"seed": s, "index": last, "kind": kind,
                                 "message": _excerpt(res.stderr)}
        where = next((ln.split(" runtime error")[0] for ln in res.stderr.splitlines()
                      if "runtime error" in ln or "ERROR: AddressSanitizer" in ln), "")
        crash["where"] = where
        if minimise_crashes and (kind, where) not in {(c["kind"], c["where"]) for c in rep.crashes}:
            crash["minimal"] = minimise_crash(build, s, kind, timeout)
        rep.crashes.append(crash)
        rep.sequences += 1
        start = last + 1
    rep.seconds = time.perf_counter() - t0
    return rep


def _excerpt(stderr: str) -> str:
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    keep = [ln for ln in lines if "ERROR" in ln or "runtime error" in ln or "Timeout" in ln
            or ln.lstrip().startswith("#") or "File " in ln][:12]
    return "\n".join(keep or lines[-12:])


def sequence_of(build: Path, seed: int) -> dict[str, Any]:
    from tests.fuzz.sequences import Generator

    return Generator(describe(build, 2 if seed % 2 == 0 else 3)).sequence(seed)


def replay(build: Path, seq: dict[str, Any], timeout: float = 20.0) -> dict[str, Any]:
    """Runs one sequence in a fresh child process.

    Parameters
    ----------
    build : Path
        CMake build directory of the FMU.
    seq : dict
        The sequence ({"interface", "actions", optional "expect_error"}).
    timeout : float
        Seconds before the sequence counts as a hang.

    Returns
    -------
    dict
        "kind" (None, the violated rule, or the crash kind: asan, ubsan, timeout ...),
        "message", "calls", and for a completed run "errors" (the FMU's refusals) and "final"
        (all variables after the last action).
    """
    with tempfile.TemporaryDirectory() as tmp:
        f = Path(tmp) / "seq.json"
        f.write_text(json.dumps(seq))
        res = _child(build, ["replay", str(f), "--timeout", str(timeout)], timeout + 60)
    for line in res.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    return {"kind": crash_kind(res.returncode, res.stderr), "message": _excerpt(res.stderr),
            "calls": None}


def minimise_crash(build: Path, seed: int, kind: str, timeout: float,
                   budget: int = 60) -> dict[str, Any]:
    seq = sequence_of(build, seed)
    return minimise(seq, lambda s: replay(build, s, timeout)["kind"] == kind, budget=budget)


# ------------------------------------------------------------------------------------------


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m tests.fuzz.runner", description=__doc__)
    sub = p.add_subparsers(dest="cmd", required=True)
    f = sub.add_parser("fuzz", help="fuzz (parent: restarts the child after crashes)")
    f.add_argument("--sequences", type=int, default=int(os.environ.get("IMPACT_FUZZ_SEQUENCES", 3000)))
    f.add_argument("--json", help="write the report here")
    for sp in (f, sub.add_parser("replay", help="replay stored sequences")):
        sp.add_argument("--build", default=str(SANITIZED))
        sp.add_argument("--timeout", type=float, default=20.0)
    f.add_argument("--seed", type=int, default=13)
    # the child's own options
    f.add_argument("--start", type=int, default=None, help=argparse.SUPPRESS)
    f.add_argument("--count", type=int, default=None, help=argparse.SUPPRESS)
    f.add_argument("--minimise", action="store_true", help=argparse.SUPPRESS)
    sub.choices["replay"].add_argument("files", nargs="+")
    args = p.parse_args(argv)
    if args.cmd == "replay":
        build = Path(args.build)
        if is_sanitized(build) and "libasan" not in os.environ.get("LD_PRELOAD", ""):
            # run by hand: restart with the sanitizer runtime preloaded
            os.execve(sys.executable, [sys.executable, "-m", "tests.fuzz.runner", *sys.argv[1:]],
                      child_env(build))
        child_replay(args)
        return 0
    if args.start is not None:
        child_fuzz(args)
        return 0
    build = Path(args.build)
    if build == SANITIZED:
        build_sanitized(build)
    rep = fuzz(build, args.sequences, seed=args.seed, timeout=args.timeout)
    print(rep.summary())
    if args.json:
        Path(args.json).write_text(json.dumps(rep.__dict__, indent=1))
    return 1 if rep.failures else 0


if __name__ == "__main__":
    sys.exit(main())
