"""Failures a user can cause end in one line on stderr and exit status 2, never a traceback
broken FMU binaries, unreadable experiment files, unwritable outputs."""
from __future__ import annotations

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from tests.support.cli import run_main as _run_main

ROOT = Path(__file__).resolve().parents[2]
FMU = ROOT / "build" / "fmu" / "ImpactOscillator.fmu"
SHORT = ["--transient", "3", "--samples", "3", "--no-progress"]


def _binary_member(archive: zipfile.ZipFile) -> str:
    """The binary this machine loads (the FMU also carries other platforms')."""
    return next(n for n in archive.namelist() if n.startswith("binaries/linux64/") and n.endswith(".so"))


@pytest.fixture(scope="module")
def garbage_fmu(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The real FMU with its shared library replaced by random bytes of the same length."""
    out = tmp_path_factory.mktemp("broken") / "garbage.fmu"
    with zipfile.ZipFile(FMU) as src, zipfile.ZipFile(out, "w") as dst:
        so = _binary_member(src)
        for item in src.infolist():
            data = src.read(item.filename)
            dst.writestr(item, os.urandom(len(data)) if item.filename == so else data)
    return out


@pytest.fixture(scope="module")
def crc_fmu(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The real FMU, stored uncompressed, with one byte of its shared library flipped: the zip
    directory is intact, the member's CRC-32 no longer matches."""
    out = tmp_path_factory.mktemp("broken") / "crc.fmu"
    with zipfile.ZipFile(FMU) as src, zipfile.ZipFile(out, "w", compression=zipfile.ZIP_STORED) as dst:
        for item in src.infolist():
            dst.writestr(item.filename, src.read(item.filename))
    raw = bytearray(out.read_bytes())
    at = raw.find(b"\x7fELF")
    assert at > 0
    raw[at + 4096] ^= 0xFF
    out.write_bytes(bytes(raw))
    with zipfile.ZipFile(out) as check:  # the damage is in the data, not the directory
        assert check.testzip() is not None
    return out


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.mark.parametrize("command", [["strobe"], ["sweep", "--values", "0.5,0.6", "--mode", "fresh", "--workers", "2"]],
                         ids=["strobe (in process)", "sweep (pool workers)"])
def test_fmu_with_a_garbage_binary(garbage_fmu: Path, tmp_path: Path, capsys, command: list[str]) -> None:
    cwd = os.getcwd()
    code, _, err = _run_main([*command, "--fmu", str(garbage_fmu), *SHORT, "--out", str(tmp_path / "x.nc")], capsys)
    line = _one_line(err)
    assert code == 2 and "argument --fmu" in line and "invalid ELF header" in line, line
    assert not list(tmp_path.iterdir())  # no result, no checkpoint left behind
    assert os.getcwd() == cwd  # not left in the extraction folder of the binary that failed to load


def test_fmu_with_a_crc_corrupt_binary(crc_fmu: Path, tmp_path: Path, capsys) -> None:
    code, _, err = _run_main(["strobe", "--fmu", str(crc_fmu), *SHORT, "--out", str(tmp_path / "x.nc")], capsys)
    line = _one_line(err)
    assert code == 2 and "argument --fmu" in line and "damaged FMU archive" in line and "CRC" in line, line


def test_config_not_utf8_and_config_a_directory(tmp_path: Path, capsys) -> None:
    bad = tmp_path / "latin1.toml"
    bad.write_bytes('[model]\n# r\xe9glage\nsigma = 0.5\n'.encode("latin-1"))
    code, _, err = _run_main(["strobe", "--config", str(bad), *SHORT], capsys)
    assert code == 2 and "not UTF-8" in _one_line(err) and "argument --config" in err
    code, _, err = _run_main(["strobe", "--config", str(tmp_path), *SHORT], capsys)
    assert code == 2 and "is a directory" in _one_line(err) and "argument --config" in err


def test_out_is_a_directory_leaves_nothing_beside_it(tmp_path: Path, capsys) -> None:
    """`--out DIR` is refused without writing DIR.tmp (or anything) next to DIR."""
    target = tmp_path / "dir"
    target.mkdir()
    code, _, err = _run_main(["strobe", *SHORT, "--out", str(target)], capsys)
    assert code == 2 and "argument --out" in _one_line(err) and "is a directory" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dir"] and not list(target.iterdir())


@pytest.mark.parametrize("flag", ["--out", "--plot"])
def test_unwritable_out_or_plot(tmp_path: Path, capsys, flag: str) -> None:
    # a directory that cannot be created (its parent is a file): refused before the run,
    # even for root, who may write anywhere else
    blocker = tmp_path / "file"
    blocker.write_text("")
    argv = ["strobe", *SHORT, "--out", str(tmp_path / "ok.nc")]
    argv += [flag, str(blocker / "sub" / ("x.nc" if flag == "--out" else "x.png"))]
    code, out, err = _run_main(argv, capsys)
    assert code == 2 and f"argument {flag}" in _one_line(err), err
    assert out == ""  # nothing ran: the check comes before the work
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_unknown_plot_format_is_refused_before_the_run(tmp_path: Path, capsys) -> None:
    code, out, err = _run_main(["strobe", *SHORT, "--out", str(tmp_path / "a.nc"), "--plot", str(tmp_path / "a.xyz")],
                               capsys)
    assert code == 2 and "unknown image format 'xyz'" in _one_line(err) and out == ""


def test_atomic_write_cleans_up_on_failure(tmp_path: Path) -> None:
    from harness.errors import HarnessInputError
    from harness.io.outputs import atomic_write

    with pytest.raises(RuntimeError):
        with atomic_write(tmp_path / "r.nc") as tmp:
            tmp.write_text("half")
            raise RuntimeError("interrupted mid-write")
    assert not list(tmp_path.iterdir())
    with atomic_write(tmp_path / "r.nc") as tmp:
        tmp.write_text("whole")
    assert [p.name for p in tmp_path.iterdir()] == ["r.nc"] and (tmp_path / "r.nc").read_text() == "whole"
    with pytest.raises(HarnessInputError, match="is a directory"):
        with atomic_write(tmp_path):
            pass


@pytest.mark.slow  # a real CLI process
def test_broken_fmu_in_a_real_process(garbage_fmu: Path, tmp_path: Path) -> None:
    res = subprocess.run([sys.executable, "-m", "harness", "simulate", "--fmu", str(garbage_fmu), "--t-end", "1",
                          "--out", str(tmp_path / "x.nc"), "--no-progress"],
                         capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert res.returncode == 2 and "invalid ELF header" in _one_line(res.stderr)


def test_rejected_sweep_leaves_no_checkpoint_and_no_note_next_time(tmp_path: Path, capsys) -> None:
    """A run refused for a bad parameter left OUT.partial, and the corrected rerun
    printed a note about discarding it."""
    out = tmp_path / "s.nc"
    base = ["sweep", "--param", "contact", "--mode", "fresh", "--solver", "closed-form", "--transient", "2",
            "--samples", "2", "--workers", "1", "--out", str(out), "--no-plot", "--no-progress"]
    # the FMU refuses the closed-form solver with the Hertz law (contact = 1) after contact = 0 finished
    # (a start inside a rigid wall is not a refusal of the run but an invalid point, tests/harness/test_basins.py)
    code, _, err = _run_main([*base, "--values", "0,1"], capsys)
    assert code == 2 and "closed" in _one_line(err).lower() and "Hertz" in _one_line(err), err
    assert not (tmp_path / "s.nc.partial").exists() and not out.exists()
    code, _, err = _run_main([*base, "--values", "0", "--set", "contact=0"], capsys)
    assert code == 0 and err == "" and out.exists(), err


def test_atomic_write_gives_the_file_the_umask_mode(tmp_path: Path) -> None:
    """mkstemp's 0600 was kept: results and figures were unreadable to the user's group."""
    from harness.io.outputs import atomic_write

    old = os.umask(0o027)
    try:
        with atomic_write(tmp_path / "r.txt") as tmp:
            tmp.write_text("x")
    finally:
        os.umask(old)
    assert (tmp_path / "r.txt").stat().st_mode & 0o777 == 0o640
