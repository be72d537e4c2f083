"""Rules for the whole repository, read from its files:

* comments and documentation say what is and why, never which issue asked for it: no text file
  outside CHANGELOG.md (which keeps the history) names an issue number;
* nothing outside tests/ imports from tests/ (the test suite may use the tools, not the reverse);
* every repository path the documentation and the code name exists (a renamed or moved file
  leaves no stale reference behind).
"""
from __future__ import annotations

import ast
import re
from pathlib import Path

from tests.support.repository import ROOT, python_files, text_files

#: The word issue (or issues), any case, then a number, with or without a number sign or a hyphen
#: between; or a bare number sign before a number.  An upstream project's issue written
#: owner/repo, number sign, number is a citation and stays.
ISSUE = re.compile(r"\bissues?[\s-]*#?\d+|(?<![\w/&.-])#\d{1,4}(?![\w-])", re.I)
#: Texts that are not the project's own words: the history, and the FMI standards' headers,
#: vendored verbatim (their revision notes cite the standard's tickets).
NOT_OURS = ("CHANGELOG.md", "fmu_src/include/")

#: The repository's top-level folders, as a path in a text starts.
TOP = r"harness|mapcheck|bench|scripts|examples|fmu_src|tests|docs|cmake|\.ci"
PATH = re.compile(rf"(?<![\w./-])((?:{TOP})/[\w./+-]*[\w/])")


def _rel(path: Path) -> str:
    return path.relative_to(ROOT).as_posix()


def issue_mentions(text: str) -> list[tuple[int, str]]:
    """(line number, the mention) of every issue number in ``text``."""
    return [(n, m.group(0)) for n, line in enumerate(text.splitlines(), 1) for m in ISSUE.finditer(line)]


def test_no_text_names_an_issue() -> None:
    found = [f"{_rel(p)}:{n}: {m}" for p in text_files() if not _rel(p).startswith(NOT_OURS)
             for n, m in issue_mentions(p.read_text(errors="replace"))]
    assert not found, "issue numbers outside CHANGELOG.md (say what is and why instead):\n" + "\n".join(found)


def test_issue_mentions_are_found() -> None:
    # written in pieces, so that this file does not name an issue itself
    i = "iss" + "ue"
    h = "#"
    text = f"a ({i} 13) b\nI{i[1:]} {h}26: c\nsee {i}s 11 and 14\nthe {i}-17 case\nLLNL/sundials{h}57 d\nx{h}1f77b4\n"
    assert [n for n, _ in issue_mentions(text)] == [1, 2, 3, 4]
    assert issue_mentions("docs/theory.md#1-the-model, ## 2. Free flight") == []


def imports_of_tests(path: Path) -> list[int]:
    """Line numbers of the imports of the ``tests`` package in ``path``."""
    lines = []
    for node in ast.walk(ast.parse(path.read_text())):
        names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                 else [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level else [])
        if any(n == "tests" or n.startswith("tests.") for n in names):
            lines.append(node.lineno)
    return lines


#: Files outside tests/ that import from it, each with its reason (a tool that measures the test
#: suite's own cases belongs beside them, under tests/; this one writes a benchmark section).
IMPORTS_TESTS = {
    "bench/sens_bench.py": "its accuracy section runs the sensitivity tests' cases against their reference "
                           "(tests/support/sensitivities.py)",
}


def test_nothing_outside_tests_imports_tests() -> None:
    bad = [f"{_rel(p)}:{n}" for p in python_files() if not _rel(p).startswith("tests/")
           and _rel(p) not in IMPORTS_TESTS for n in imports_of_tests(p)]
    assert not bad, "imports from tests/ outside tests/:\n" + "\n".join(bad)
    stale = [f for f in IMPORTS_TESTS if not imports_of_tests(ROOT / f)]
    assert not stale, f"no longer import from tests/ (remove them from IMPORTS_TESTS): {stale}"


def named_paths(text: str) -> list[tuple[int, str]]:
    """(line number, path) of every repository path named in ``text`` that names a file (an
    extension), a folder (a trailing /) or a test module (test_*, as TESTING.md's table writes
    them relative to tests/, without .py).  A path cut off by a placeholder (``<target>``,
    ``{a,b}``, ``[ch]``, an upper-case word such as ``TARGET``) is no claim and is skipped."""
    found = []
    for n, line in enumerate(text.splitlines(), 1):
        for m in PATH.finditer(line):
            path = m.group(1).split("::")[0].rstrip(".")
            after = line[m.end():m.end() + 1]
            if after in ("<", "{", "[", "*") or re.search(r"[A-Z]{3,}", path):
                continue
            name = path.rstrip("/").rsplit("/", 1)[-1]
            if path.endswith("/") or re.search(r"\.\w+$", name) or name.startswith("test_"):
                found.append((n, path))
    return found


def exists(path: str) -> bool:
    return any((ROOT / c).exists() for c in (path, path + ".py", "tests/" + path, "tests/" + path + ".py"))


def test_named_paths_exist() -> None:
    missing = [f"{_rel(p)}:{n}: {path}" for p in text_files() if not _rel(p).startswith(NOT_OURS)
               for n, path in named_paths(p.read_text(errors="replace")) if not exists(path)]
    assert not missing, "paths named but not in the repository:\n" + "\n".join(missing)


def test_named_paths_are_read() -> None:
    nowhere = "docs/" + "nowhere.md"  # in pieces, so that this file names no missing path itself
    text = ("see `harness/fmu/fmi.py`, tests/fmu/test_ports.py::test_x and `fmu/test_bounds`\n"
            f"cmake/toolchain-<target>.cmake, fmu_src/fmu_states.[ch], cmake/gcc, {nowhere}.\n")
    assert named_paths(text) == [(1, "harness/fmu/fmi.py"), (1, "tests/fmu/test_ports.py"), (2, nowhere)]
    assert exists("harness/fmu/fmi.py") and exists("fmu/test_bounds") and not exists(nowhere)
