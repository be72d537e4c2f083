"""A damaged FMU archive is one line of bad input, never a traceback: a byte flipped inside the
deflate stream of the binary makes zipfile raise ``zlib.error``, which the archive check turns
into bad input like every other damage (tests/fuzz/extreme_inputs.py runs the CLI on such an archive).

Every single-byte flip at 40 places spread over the archive (the compressed binary, the
local headers, the central directory) either leaves a readable archive or raises
HarnessInputError from ``harness.fmu.fmi.check_archive``; no other exception gets through.
"""
from __future__ import annotations

import zipfile
from pathlib import Path

import pytest

from harness.errors import HarnessInputError
from harness.fmu.fmi import check_archive
from tests.support.fmu import FMU_PATH


@pytest.mark.parametrize("where", [i / 40 for i in range(40)])
def test_flipped_byte_is_bad_input_or_harmless(tmp_path: Path, where: float) -> None:
    raw = bytearray(FMU_PATH.read_bytes())
    raw[int(where * (len(raw) - 1))] ^= 0xFF
    bad = tmp_path / "flipped.fmu"
    bad.write_bytes(bytes(raw))
    try:
        check_archive(bad)
    except HarnessInputError as exc:
        assert "damaged FMU archive" in str(exc) or "FMU" in str(exc)


def test_flip_inside_the_deflate_stream_is_reported(tmp_path: Path) -> None:
    """The case that escaped: a flip in the middle of the compressed binary."""
    raw = bytearray(FMU_PATH.read_bytes())
    with zipfile.ZipFile(FMU_PATH) as z:
        so = next(i for i in z.infolist() if i.filename.endswith(".so"))
    raw[so.header_offset + 30 + len(so.filename) + so.compress_size // 2] ^= 0xFF
    bad = tmp_path / "crc.fmu"
    bad.write_bytes(bytes(raw))
    with pytest.raises(HarnessInputError, match="damaged FMU archive"):
        check_archive(bad)
