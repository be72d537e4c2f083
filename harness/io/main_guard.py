"""The ``if __name__ == "__main__":`` mistake, found before any worker process starts.

Worker processes are started with "spawn": each re-imports the script that started the run.
A script that calls :func:`harness.run_sweep` (or any parallel entry point) at its top level,
outside the guard, would start the run again in every worker, which fails in the worker's
bootstrapping and ends, after hundreds of lines of interleaved tracebacks, in
``BrokenProcessPool``.  :func:`require_main_guard` finds the top-level line of ``__main__``
that is running now and, when that line is not under the guard, raises one error that says
the fix.
"""
from __future__ import annotations

import ast
import sys
from pathlib import Path
from types import FrameType

from ..errors import HarnessInputError


def _is_main_test(node: ast.expr) -> bool:
    """``__name__ == "__main__"`` (either order)."""
    if not (isinstance(node, ast.Compare) and len(node.ops) == 1 and isinstance(node.ops[0], ast.Eq)):
        return False
    sides = [node.left, node.comparators[0]]
    names = [s for s in sides if isinstance(s, ast.Name) and s.id == "__name__"]
    consts = [s for s in sides if isinstance(s, ast.Constant) and s.value == "__main__"]
    return bool(names and consts)


def guarded_lines(source: str) -> list[tuple[int, int]]:
    """Line ranges (first, last) of the top-level ``if __name__ == "__main__":`` bodies, and of
    the top-level function and class definitions (their bodies do not run at import)."""
    tree = ast.parse(source)
    out = []
    for node in tree.body:
        if isinstance(node, ast.If) and _is_main_test(node.test):
            out.append((node.body[0].lineno, node.end_lineno or node.lineno))
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out.append((node.lineno, node.end_lineno or node.lineno))
    return out


def _top_level_main_frame() -> FrameType | None:
    """The frame running the module level of ``__main__`` (the script), if any."""
    frame = sys._getframe(1)
    found = None
    while frame is not None:
        if frame.f_code.co_name == "<module>" and frame.f_globals.get("__name__") == "__main__":
            found = frame
        frame = frame.f_back
    return found


def unguarded_call() -> tuple[str, int] | None:
    """(script, line) when the running top-level statement of ``__main__`` is outside the
    guard, so that a spawned worker would run it again; None otherwise (or when the script's
    source cannot be read: an interactive session, ``python -c``)."""
    frame = _top_level_main_frame()
    if frame is None:
        return None
    path = frame.f_globals.get("__file__")
    if not path or not Path(path).is_file():
        return None
    try:
        ranges = guarded_lines(Path(path).read_text(encoding="utf-8"))
    except (OSError, SyntaxError, UnicodeDecodeError, ValueError):
        return None
    line = frame.f_lineno
    if any(first <= line <= last for first, last in ranges):
        return None
    return str(path), int(line)


def require_main_guard(what: str) -> None:
    """Raise :class:`HarnessInputError` (one line, the fix included) when ``what`` is about to
    start worker processes from an unguarded top-level line of the running script."""
    found = unguarded_call()
    if found is None:
        return
    path, line = found
    raise HarnessInputError(
        what, f"called at the top level of {Path(path).name} (line {line}), outside "
        "'if __name__ == \"__main__\":'; its worker processes re-import the script and would start the run "
        "again: put the call under that guard (or use backend=\"serial\")")
