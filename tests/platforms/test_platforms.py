"""Every binary in the FMUs, tested where it runs: x86_64 Linux natively, x86_64
Windows under wine, aarch64 Linux under qemu-user, each through the same C host
(tests/host/fmu_host.c) built with that target's toolchain, FMI 2.0 and 3.0, Co-Simulation and
Model Exchange.

Per period, not along a trajectory (the platforms' math libraries differ in the last bits and a
trajectory would amplify that): the starts are the closed form's own states at t = k, k = 0..99,
and each binary's state one period later is compared with the closed form's (mapcheck.exact, the
independent truth) and with the native Linux binary's from the same start. Model Exchange under
qemu's emulation (the host's fixed-step RK4, some 20 s of CPU per 400 periods) runs a subset of
the starts: every fifth and the first periods with a wall entry of each case (EMULATED_ME_STARTS).
Also: what each binary imports and exports, and fmpy's validation and the harness's archive check
of both FMUs.
"""
from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy.validation import validate_fmu

from harness.fmu.fmi import check_archive
from mapcheck.exact import ExactOscillator
from tests.support.fmu import FMU3_PATH, FMU_PATH
from tests.support.platforms import (NATIVE, PLATFORMS, host_input, imports,
                                    require_cross_build, run_host, unpack)

pytestmark = pytest.mark.slow  # the Windows and aarch64 binaries under wine and qemu-user

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112, r=0.9, Gamma=10.0, sigma=0.5)
UNDERDAMPED = dict(nu=0.8, Omega=2.5, r=0.8, Gamma=10.0, sigma=0.5)
CASES = {
    "fig9-compliant": dict(FIG9, wall="compliant"),
    "fig9-rigid": dict(FIG9, wall="rigid"),
    "underdamped-compliant": dict(UNDERDAMPED, wall="compliant"),
    "underdamped-rigid": dict(UNDERDAMPED, wall="rigid"),
}
PERIODS = 100
TOL = 1e-8  # per period, absolute on (u, v): the bound the platforms promise
INTERFACES = [(fmi, itf) for fmi in ("fmi2", "fmi3") for itf in ("cs", "me")]
#: Model Exchange under emulation: every EVERY-th start and the first ENTRIES periods of each case
#: with a wall entry in the closed form (Figure 9's rigid case has two, at periods 54 and 85).
EMULATED = {"aarch64-linux"}
EMULATED_ME_STARTS = dict(every=5, entries=8)


@pytest.fixture(scope="module")
def unpacked(tmp_path_factory) -> dict[str, Path]:
    require_cross_build()
    base = tmp_path_factory.mktemp("platforms")
    # wine's server is not ended here: it ends itself seconds after its last program, and a kill
    # would also end the wine programs of the other test worker (tests/platforms/test_corpus.py)
    return {"fmi2": unpack(FMU_PATH, base / "fmi2"), "fmi3": unpack(FMU3_PATH, base / "fmi3")}


@pytest.fixture(scope="module")
def truth() -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per case: the start rows (k, u_k, v_k), k < 100, the closed form's state at k + 1, and the
    periods k with a wall entry."""
    out = {}
    times = np.arange(PERIODS + 1, dtype=float)
    for name, p in CASES.items():
        ex = ExactOscillator(p["nu"], p["Omega"], p["sigma"], r=p["r"], Gamma=p["Gamma"], wall=p["wall"])
        states, entries = ex.strobe(-1.0, 0.0, times)
        out[name] = (np.column_stack([times[:-1], states[:-1]]), states[1:], np.flatnonzero(np.diff(entries)))
    return out


def starts_run(truth, plat: str, itf: str) -> dict[str, np.ndarray]:
    """Per case, the periods k whose start a platform's interface runs (all but under emulated ME)."""
    if not (plat in EMULATED and itf == "me"):
        return {n: np.arange(PERIODS) for n in CASES}
    every, entries = EMULATED_ME_STARTS["every"], EMULATED_ME_STARTS["entries"]
    return {n: np.union1d(np.arange(0, PERIODS, every), truth[n][2][:entries]) for n in CASES}


def test_emulated_starts_hold_wall_entries_of_every_case(truth):
    """The subset run under emulation still meets the wall in every case, and spans the run."""
    for name, k in starts_run(truth, next(iter(EMULATED)), "me").items():
        assert np.isin(truth[name][2], k).any() and k[0] == 0 and k[-1] >= PERIODS - EMULATED_ME_STARTS["every"]


@pytest.fixture(scope="module")
def results(unpacked, truth) -> dict[tuple[str, str, str], dict[str, tuple[np.ndarray, np.ndarray]]]:
    """(platform, fmi, interface) -> case -> (the periods k run, (u, v) one period after each of
    their starts); runs lazily."""
    names = list(CASES)

    class Lazy(dict):
        def __missing__(self, key):
            plat, fmi, itf = key
            platform = next(p for p in PLATFORMS if p.name == plat)
            ks = starts_run(truth, plat, itf)
            rows = run_host(platform, unpacked[fmi], fmi, itf,
                            host_input([(CASES[n], truth[n][0][ks[n]]) for n in names]))
            assert rows.shape == (sum(len(k) for k in ks.values()), 2), rows.shape
            ends = np.cumsum([0] + [len(ks[n]) for n in names])
            self[key] = {n: (ks[n], rows[ends[i]:ends[i + 1]]) for i, n in enumerate(names)}
            return self[key]
    return Lazy()


@pytest.mark.parametrize("fmi,itf", INTERFACES, ids=lambda x: x)
@pytest.mark.parametrize("plat", [p.name for p in PLATFORMS])
def test_each_period_matches_the_closed_form(results, truth, plat, fmi, itf):
    got = results[(plat, fmi, itf)]
    for name in CASES:
        ks, rows = got[name]
        err = np.abs(rows - truth[name][1][ks]).max(axis=1)
        assert np.isfinite(err).all(), f"{name}: the FMU refused a start"
        assert err.max() <= TOL, f"{name}: period {ks[err.argmax()]} off by {err.max():.3g}"


@pytest.mark.parametrize("fmi,itf", INTERFACES, ids=lambda x: x)
@pytest.mark.parametrize("plat", [p.name for p in PLATFORMS if p is not NATIVE])
def test_each_period_matches_the_native_binary(results, plat, fmi, itf):
    got, native = results[(plat, fmi, itf)], results[(NATIVE.name, fmi, itf)]
    for name in CASES:
        (ks, rows), (k_native, rows_native) = got[name], native[name]
        assert np.isin(ks, k_native).all()
        diff = np.abs(rows - rows_native[np.searchsorted(k_native, ks)]).max()
        assert diff <= TOL, f"{name}: {diff:.3g} from the native binary"


@pytest.mark.parametrize("fmi", ["fmi2", "fmi3"])
@pytest.mark.parametrize("plat", PLATFORMS, ids=lambda p: p.name)
def test_binary_needs_only_the_system_and_exports_only_fmi(unpacked, plat, fmi):
    binary = unpacked[fmi] / plat.binary(fmi)
    needed, exported = imports(binary)
    system = {"KERNEL32.dll", "msvcrt.dll"} if plat.suffix == ".dll" else {"libc.so.6", "libm.so.6"}
    assert set(needed) <= system, needed
    assert exported and all(s.startswith(fmi) for s in exported), exported
    assert f"{fmi}Instantiate" in exported or "fmi3InstantiateCoSimulation" in exported


@pytest.mark.parametrize("fmu", [FMU_PATH, FMU3_PATH], ids=lambda p: p.name)
def test_archive_holds_every_platform_and_validates(fmu):
    require_cross_build()
    check_archive(fmu)
    assert validate_fmu(str(fmu)) == []
    names = set(zipfile.ZipFile(fmu).namelist())
    fmi = "fmi3" if "fmi3" in fmu.name else "fmi2"
    for p in PLATFORMS:
        assert p.binary(fmi) in names
