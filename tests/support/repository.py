"""The repository's own files, as the project-wide rules (tests/project/) read them: every file
of the project's source and documentation, without the environment (.venv, .git and other hidden
folders), build outputs, results and caches."""
from __future__ import annotations

import functools
import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: Folders that hold no source of the project: build outputs, results and caches (.gitignore).
NOT_SOURCE = {"build", "results", "node_modules", "__pycache__"}
#: Suffixes of the text files: source, scripts, build files, documentation, data written by hand.
TEXT_SUFFIXES = {".py", ".md", ".sh", ".toml", ".txt", ".c", ".h", ".inc", ".cmake", ".xml", ".json", ".ssd",
                 ".cfg", ".ini", ".yml", ".yaml"}


def project_files(root: Path = ROOT, suffixes: set[str] | None = None) -> list[Path]:
    """Every file under ``root`` with one of ``suffixes`` (all files if None), sorted, outside
    hidden folders, build outputs, results and caches."""
    return list(_project_files(root, None if suffixes is None else frozenset(suffixes)))


@functools.lru_cache(maxsize=None)
def _project_files(root: Path, suffixes: frozenset[str] | None) -> tuple[Path, ...]:
    # the excluded folders are pruned, not walked (.venv, .git and build/ hold most of the files)
    found = []
    for folder, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if not (d.startswith(".") or d in NOT_SOURCE or d.endswith(".egg-info"))]
        for name in files:
            path = Path(folder) / name
            if (suffixes is None or path.suffix in suffixes) and path.is_file():
                found.append(path)
    return tuple(sorted(found))


def python_files(root: Path = ROOT) -> list[Path]:
    """Every .py file of the project."""
    return project_files(root, {".py"})


def text_files(root: Path = ROOT) -> list[Path]:
    """Every text file of the project (:data:`TEXT_SUFFIXES`)."""
    return project_files(root, TEXT_SUFFIXES)
