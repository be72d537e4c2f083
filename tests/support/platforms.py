"""Running the FMUs' binaries for every platform through the C host (tests/host/fmu_host.c).

scripts/cross_build.sh builds the host for each target in build/cross/<target>/host; this module
unpacks an FMU, feeds the host start states and parameters as 64-bit patterns, and runs it
natively, under wine (Windows) or under qemu-user with the aarch64 sysroot (aarch64 Linux).
"""
from __future__ import annotations

import os
import shutil
import struct
import subprocess
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
CROSS = ROOT / "build" / "cross"
#: wine's prefix, outside the source tree (scripts/cross_build.sh says why); the same default there
WINEPREFIX = Path(os.environ.get("IMPACT_WINEPREFIX")
                  or Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "impact-grazing" / "wineprefix")
WINE = "/usr/lib/wine/wine64"
AARCH64_SYSROOT = "/usr/aarch64-linux-gnu"
TOKEN = "{6c1f8a52-3d0e-4b8e-9a57-1e0f0b7c2a11}"


@dataclass(frozen=True)
class Platform:
    """One target: its FMI 2.0 and 3.0 binary folders and how its programs are run here."""

    name: str
    fmi2_dir: str
    fmi3_dir: str
    suffix: str
    runner: tuple[str, ...]

    def binary(self, fmi: str) -> str:
        folder = self.fmi2_dir if fmi == "fmi2" else self.fmi3_dir
        return f"binaries/{folder}/ImpactOscillator{self.suffix}"

    @property
    def host(self) -> Path:
        return CROSS / self.name / "host" / ("fmu_host.exe" if self.suffix == ".dll" else "fmu_host")


PLATFORMS = [
    Platform("x86_64-linux", "linux64", "x86_64-linux", ".so", ()),
    Platform("x86_64-windows", "win64", "x86_64-windows", ".dll", (WINE,)),
    Platform("aarch64-linux", "aarch64-linux", "aarch64-linux", ".so",
             ("qemu-aarch64", "-L", AARCH64_SYSROOT)),
]
NATIVE = PLATFORMS[0]


def require_cross_build() -> None:
    """Skip only where the user asked for the native build alone; otherwise a missing piece fails."""
    if os.environ.get("IMPACT_NATIVE_ONLY") == "1":
        pytest.skip("IMPACT_NATIVE_ONLY=1: only the native binary was built")
    missing = [str(p.host) for p in PLATFORMS if not p.host.exists()]
    missing += [t for t in ("qemu-aarch64", WINE) if shutil.which(t) is None]
    assert not missing, f"cross build or its runners missing (run scripts/setup.sh): {missing}"


def env() -> dict[str, str]:
    """The environment for wine: the prefix scripts/cross_build.sh initialised, no debug output."""
    return dict(os.environ, WINEPREFIX=str(WINEPREFIX), WINEDEBUG="-all")


def unpack(fmu: Path, dest: Path) -> Path:
    with zipfile.ZipFile(fmu) as z:
        z.extractall(dest)
    return dest


def to_hex(x: float) -> str:
    return "%016x" % struct.unpack("<Q", struct.pack("<d", float(x)))[0]


def from_hex(s: str) -> float:
    return struct.unpack("<d", struct.pack("<Q", int(s, 16)))[0]


# FMI variables by value reference (the same in both model descriptions).
REALS = {"nu": 0, "Omega": 1, "sigma": 2, "r": 3, "Gamma": 4}
INTS = {"wall": 5}
WALLS = {"compliant": 1, "rigid": 2}


def host_input(cases: list[tuple[dict, np.ndarray]]) -> str:
    """The host's stdin: per case its parameters and start rows (t0, u0, v0)."""
    out = []
    for params, starts in cases:
        lines = [f"r {REALS[k]} {to_hex(v)}" for k, v in params.items() if k in REALS]
        lines += [f"i {INTS[k]} {WALLS[v]}" for k, v in params.items() if k in INTS]
        out.append(f"P {len(lines)}")
        out += lines
        out.append(f"S {len(starts)}")
        out += [" ".join(to_hex(x) for x in row) for row in starts]
    return "\n".join(out) + "\n"


def run_host(platform: Platform, unpacked: Path, fmi: str, interface: str, text: str) -> np.ndarray:
    """(u, v) after one period per start row, NaN where the FMU refused; in the host's order."""
    cmd = [*platform.runner, str(platform.host), platform.binary(fmi), fmi, interface, TOKEN]
    proc = subprocess.run(cmd, input=text, capture_output=True, text=True, cwd=unpacked, env=env(),
                          timeout=120)
    assert proc.returncode == 0, f"{cmd}: {proc.returncode} {proc.stderr[-2000:]}"
    rows = []
    for line in proc.stdout.splitlines():
        parts = line.split()
        rows.append([from_hex(parts[1]), from_hex(parts[2])] if parts[0] == "ok" else [np.nan, np.nan])
    return np.array(rows)


def imports(binary: Path) -> tuple[list[str], list[str]]:
    """The binary's needed libraries and its exported symbols (objdump -p for PE, readelf for ELF)."""
    if binary.suffix == ".dll":
        text = subprocess.run(["x86_64-w64-mingw32-objdump", "-p", str(binary)], capture_output=True,
                              text=True, check=True).stdout
        needed = [ln.split("DLL Name:")[1].strip() for ln in text.splitlines() if "DLL Name:" in ln]
        table = text.split("[Ordinal/Name Pointer] Table", 1)[1].split("\n\n", 1)[0]
        exported = [ln.split("]", 1)[1].strip() for ln in table.splitlines() if "]" in ln]
        return needed, exported
    dyn = subprocess.run(["readelf", "-d", "-W", str(binary)], capture_output=True, text=True,
                         check=True).stdout
    needed = [ln.split("[", 1)[1].rstrip("]") for ln in dyn.splitlines() if "(NEEDED)" in ln]
    syms = subprocess.run(["readelf", "--dyn-syms", "-W", str(binary)], capture_output=True,
                          text=True, check=True).stdout
    exported = []
    for ln in syms.splitlines():
        f = ln.split()
        if len(f) >= 8 and f[4] in ("GLOBAL", "WEAK") and f[6] != "UND":
            exported.append(f[7].split("@")[0])
    return needed, exported
