"""Running the harness CLI in-process for the CLI tests (one copy, shared)."""
from __future__ import annotations

import pytest

from harness.cli.main import main


def run_main(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """``impact-harness argv`` in this process: (exit code, stdout, stderr).

    argparse reports its own errors by ``SystemExit``; its code is returned like main's.
    """
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    cap = capsys.readouterr()
    return code, cap.out, cap.err
