"""The size rules, everywhere in the repository: no Python file over MAX_LINES lines, no function
or method over MAX_FUNCTION_LINES lines -- harness/, mapcheck/, bench/, scripts/, examples/,
fmu_src/ (the pythonfmu twin included), tests/ and docs/ alike.  A longer file or function does
more than one thing and is split by concern.  Read from the source with :mod:`ast`."""
from __future__ import annotations

import ast
from pathlib import Path

from tests.support.repository import ROOT, python_files

MAX_LINES = 420
#: Longest function (or method) allowed, in lines from its def to the end of its body, docstring
#: included (:func:`function_lengths`).
MAX_FUNCTION_LINES = 80


def function_lengths(path: Path) -> list[tuple[str, int, int]]:
    """(qualified name, first line, length) of every function and method in ``path``.

    The length runs from the ``def`` line (decorators not counted) to the last line of the body,
    docstring included: the span a reader scrolls through, with nothing to argue about."""
    found = []

    def visit(node: ast.AST, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                found.append((prefix + child.name, child.lineno, child.end_lineno - child.lineno + 1))
                visit(child, prefix + child.name + ".")
            elif isinstance(child, ast.ClassDef):
                visit(child, prefix + child.name + ".")
            else:
                visit(child, prefix)

    visit(ast.parse(path.read_text()), "")
    return found


def test_the_search_sees_every_part_of_the_repository() -> None:
    """The checks below look where the code is: each top-level source folder has files in the
    list, and nothing from the environment or the build is in it."""
    rels = {p.relative_to(ROOT).as_posix() for p in python_files()}
    for folder in ("harness", "mapcheck", "bench", "scripts", "examples", "fmu_src", "fmu_src/pytwin", "tests"):
        assert any(r.startswith(folder + "/") for r in rels), folder
    assert not any(r.startswith((".venv/", "build/")) for r in rels)


def test_files_are_small() -> None:
    big = {p.relative_to(ROOT).as_posix(): n for p in python_files()
           if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert not big, f"Python files over {MAX_LINES} lines: {big}"


def test_functions_are_short() -> None:
    """No function or method is longer than MAX_FUNCTION_LINES lines (from its ``def`` to the end
    of its body, docstring included): a longer one does more than one thing, and is split by
    concern (a closure that rebinds variables becomes a small class)."""
    long = [f"{p.relative_to(ROOT).as_posix()}: {name} (line {line}): {n} lines"
            for p in python_files() for name, line, n in function_lengths(p) if n > MAX_FUNCTION_LINES]
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines:\n" + "\n".join(long)


def test_the_checks_can_fail(tmp_path: Path) -> None:
    """A file one line over the limit and a function one line over it are found; hidden and
    build folders are not searched."""
    body = "\n".join(f"    x{i} = {i}" for i in range(MAX_FUNCTION_LINES - 1))
    (tmp_path / "pkg").mkdir()
    long_fn = tmp_path / "pkg" / "long.py"
    long_fn.write_text(f"def f():\n{body}\n    return x0\n")
    assert function_lengths(long_fn) == [("f", 1, MAX_FUNCTION_LINES + 1)]
    for hidden in (".venv", "build"):
        (tmp_path / hidden).mkdir()
        (tmp_path / hidden / "x.py").write_text("\n" * (MAX_LINES + 1))
    assert python_files(tmp_path) == [long_fn]
