"""The harness's layers (docs/architecture.md): every import, module-level or inside a function,
runs downward or sideways within a layer, never upward; no import cycle between modules; every
subpackage says what it may import.  Read from the source with :mod:`ast`, so a lazy import
counts.  The size rules (files, functions) hold for the whole repository: tests/project/test_sizes.py."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2] / "harness"

#: Layer rank of each part of the package; a module may import parts of equal or lower rank,
#: except that a layer's own rank is shared only with itself (fmu does not import dynamics).
GROUND = {"config", "errors"}
RANK = {"ground": 0, "io": 1, "fmu": 2, "dynamics": 3, "runs": 4, "analysis": 5, "reproduce": 6, "cli": 7}
#: Pairs of parts that may import each other although neither is below the other: none (the
#: analyses are below the paper's figures, which use them; the CLI is above both).
SIDEWAYS: set[tuple[str, str]] = set()


def part_of(module: str) -> str | None:
    """'harness.fmu.fmi' -> 'fmu'; 'harness.config' -> 'ground'; the package itself -> None."""
    parts = module.split(".")
    if parts[0] != "harness" or len(parts) == 1:
        return None
    if parts[1] == "__main__":
        return "cli"
    return "ground" if parts[1] in GROUND else parts[1]


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imports_of(path: Path) -> list[tuple[int, str]]:
    """Absolute names of the harness modules ``path`` imports (with line numbers)."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("harness"):
                continue
            # "from . import tempdirs": the names may be modules
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                found.append((node.lineno, sub if (ROOT.parent / (sub.replace(".", "/") + ".py")).exists() else target))
        elif isinstance(node, ast.Import):
            found += [(node.lineno, a.name) for a in node.names if a.name.startswith("harness")]
    return found


MODULES = sorted(p for p in ROOT.rglob("*.py"))


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_imports_run_downward(path: Path) -> None:
    if path == ROOT / "__init__.py":
        return  # the package's lazy re-exports of the public names
    own = part_of(module_name(path)) or "ground"
    bad = []
    for line, target in imports_of(path):
        other = part_of(target)
        if other is None or other == own or (own, other) in SIDEWAYS:
            continue
        if RANK[other] >= RANK[own]:
            bad.append(f"line {line}: {target} ({other}) from the {own} layer")
    assert not bad, "upward or sideways imports:\n" + "\n".join(bad)


def test_no_import_cycle() -> None:
    graph = {module_name(p): {t for _, t in imports_of(p)} for p in MODULES}
    state: dict[str, int] = {}
    cycles: list[list[str]] = []

    def visit(node: str, stack: list[str]) -> None:
        state[node] = 1
        for nxt in sorted(graph.get(node, ())):
            if nxt == "harness" or nxt not in graph or nxt == node:
                continue
            if state.get(nxt) == 1:
                cycles.append(stack[stack.index(nxt):] + [nxt] if nxt in stack else [node, nxt])
            elif nxt not in state:
                visit(nxt, stack + [nxt])
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node, [node])
    # a subpackage's __init__ importing its own module (harness.cli -> harness.cli.main) is not a cycle
    cycles = [c for c in cycles if not any(b.startswith(a + ".") and a in {m for m in graph if m.count(".") == 1}
                                           for a, b in zip(c, c[1:]))]
    assert not cycles, "import cycles: " + "; ".join(" -> ".join(c) for c in cycles)


def test_every_subpackage_says_what_it_may_import() -> None:
    for init in ROOT.glob("*/__init__.py"):
        doc = ast.get_docstring(ast.parse(init.read_text())) or ""
        assert "Layer:" in doc, f"{init.relative_to(ROOT)} has no 'Layer:' paragraph"


def test_only_the_fmu_layer_knows_fmpy() -> None:
    """docs/architecture.md: ``fmu`` is the only part that imports fmpy; everything above talks
    to a Simulator."""
    bad = []
    for path in MODULES:
        if part_of(module_name(path)) == "fmu":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level else [])
            bad += [f"{path.relative_to(ROOT)}:{node.lineno}" for n in names if n.split(".")[0] == "fmpy"]
    assert not bad, "fmpy imported outside harness/fmu: " + ", ".join(bad)
