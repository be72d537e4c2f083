"""The repository's own files, as the project-wide rules (tests/project/) read them: every file
of the project's source and documentation, without the environment (.venv, .git and other hidden
folders), build outputs, results and caches."""
from __future__ import annotations

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
    found = []
    for path in root.rglob("*"):
        rel = path.relative_to(root).parts
        if any(p.startswith(".") or p in NOT_SOURCE or p.endswith(".egg-info") for p in rel[:-1]):
            continue
        if not path.is_file() or (suffixes is not None and path.suffix not in suffixes):
            continue
        found.append(path)
    return sorted(found)


def python_files(root: Path = ROOT) -> list[Path]:
    """Every .py file of the project."""
    return project_files(root, {".py"})


def text_files(root: Path = ROOT) -> list[Path]:
    """Every text file of the project (:data:`TEXT_SUFFIXES`)."""
    return project_files(root, TEXT_SUFFIXES)
