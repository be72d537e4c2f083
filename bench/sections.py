"""Marked sections of BENCHMARKS.md: ``<!-- NAME:begin -->`` ... ``<!-- NAME:end -->``.

bench/run.py rewrites the file and keeps the sections other benchmark scripts wrote
(:func:`keep_sections`); each of those scripts replaces only its own (:func:`write_section`).
"""
from __future__ import annotations

import re
from pathlib import Path

SECTION = re.compile(r"<!-- ([\w-]+):begin -->.*?<!-- \1:end -->", re.S)  # names may hold a hyphen (windows-edges)


def keep_sections(path: Path, text: str) -> str:
    """`text` with the marked sections that other benchmark scripts wrote into the existing
    `path` appended, so that a rewrite keeps them."""
    if not path.exists():
        return text
    found = [m.group(0) for m in SECTION.finditer(path.read_text())]
    kept = [sec for sec in found if sec not in text]
    return text.rstrip() + ("\n\n" + "\n\n".join(kept) + "\n" if kept else "\n")


def write_section(path: Path, section: str) -> None:
    """Put one marked `section` into the markdown file `path`: in place of the section of the
    same name if there is one, else appended (the file is created if missing)."""
    m = SECTION.fullmatch(section.strip())
    if m is None:
        raise ValueError("not one marked section: <!-- NAME:begin --> ... <!-- NAME:end -->")
    name = re.escape(m.group(1))
    pat = re.compile(f"<!-- {name}:begin -->.*?<!-- {name}:end -->", re.S)
    old = path.read_text() if path.exists() else ""
    new = pat.sub(lambda _: section.strip(), old) if pat.search(old) else old.rstrip() + "\n\n" + section.strip() + "\n"
    path.write_text(new)
