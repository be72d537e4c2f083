#!/usr/bin/env bash
# API reference from the docstrings (pdoc, numpy docstring style) -> build/docs/index.html.
# Extra arguments go to pdoc (e.g. `bash scripts/docs.sh --no-search`); DOCS_OUT=DIR writes
# elsewhere (tests/project/test_api_docs.py builds into a temporary folder).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
# IMPACT_DOCS_NO_SETUP=1: the set-up is done (the tests: a set-up running beside other tests
# could rebuild the FMU archives they are reading)
[[ ${IMPACT_DOCS_NO_SETUP:-0} == 1 ]] || bash scripts/setup.sh
out="${DOCS_OUT:-build/docs}"
rm -rf "$out"
# the FMU's state table, rendered from the table in fmu_src/fmu_states.c
.venv/bin/python scripts/state_table_doc.py
# every module by name: pdoc follows __all__ at the top of a package, which lists the re-exports,
# not the submodules (but a submodule named like a re-export is added by pdoc); a subpackage without __all__ brings its own submodules, so those are not
# named again (a module named twice is a pdoc warning). harness.__main__ would run the CLI on
# import: left out.
mapfile -t modules < <(.venv/bin/python - <<'PY'
import importlib
import pkgutil

import harness
import mapcheck

for pkg in (harness, mapcheck):
    print(pkg.__name__)
    expanded = []  # packages without __all__: pdoc documents their submodules itself
    for m in pkgutil.walk_packages(pkg.__path__, pkg.__name__ + "."):
        parent, leaf = m.name.rsplit(".", 1)
        if leaf == "__main__" or any(m.name.startswith(s + ".") for s in expanded):
            continue
        if leaf in getattr(importlib.import_module(parent), "__all__", ()):
            continue  # pdoc adds it itself (mapcheck.windows: a module and a re-exported function)
        if m.ispkg and not hasattr(importlib.import_module(m.name), "__all__"):
            expanded.append(m.name)
        print(m.name)
PY
)
.venv/bin/python -m pdoc --docformat numpy --output-directory "$out" "$@" "${modules[@]}"
echo "API reference: $out/index.html"
