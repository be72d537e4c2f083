"""harness/README.md lists every module of the package, one line each, and nothing that is not
there: a module added, moved or removed must be described where a reader looks for it."""
from __future__ import annotations

import re
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2] / "harness"
#: A list item naming a module (``cli/main.py``) or a package (``cli/``), relative to harness/.
ITEM = re.compile(r"^\s*- `((?:[A-Za-z0-9_]+/)*(?:[A-Za-z0-9_]+\.py|[A-Za-z0-9_]+/))`: \S")


def modules_on_disk() -> set[str]:
    """Every module and subpackage of harness/, as the README names them (the package's own
    ``__init__.py`` is the package itself, not a module of it)."""
    found = set()
    for path in ROOT.rglob("*.py"):
        rel = path.relative_to(ROOT)
        if rel.name == "__init__.py":
            if rel.parent != Path("."):
                found.add(f"{rel.parent.as_posix()}/")
        else:
            found.add(rel.as_posix())
    return found


def listed_in_readme() -> list[str]:
    text = (ROOT / "README.md").read_text()
    section = text.split("\n## Modules\n", 1)[1].split("\n## ", 1)[0]
    return [m.group(1) for line in section.splitlines() if (m := ITEM.match(line))]


def test_every_module_is_listed_once() -> None:
    listed = listed_in_readme()
    twice = sorted(name for name, n in Counter(listed).items() if n > 1)
    missing = sorted(modules_on_disk() - set(listed))
    assert not twice, f"listed more than once in harness/README.md: {twice}"
    assert not missing, f"modules missing from harness/README.md's 'Modules' list: {missing}"


def test_every_listed_module_exists() -> None:
    gone = sorted(set(listed_in_readme()) - modules_on_disk())
    assert not gone, f"harness/README.md lists modules that do not exist: {gone}"
