#!/usr/bin/env bash
# API reference from the docstrings (pdoc, numpy docstring style) -> build/docs/index.html.
# Extra arguments go to pdoc (e.g. `bash scripts/docs.sh --no-search`); DOCS_OUT=DIR writes
# elsewhere (tests/test_api_docs.py builds into a temporary folder).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
out="${DOCS_OUT:-build/docs}"
rm -rf "$out"
# every module by name: pdoc follows __all__, which lists the packages' re-exports, not their
# submodules (harness.__main__ would run the CLI on import: left out)
mapfile -t modules < <(.venv/bin/python - <<'PY'
import pkgutil

import harness
import mapcheck

for pkg in (harness, mapcheck):
    print(pkg.__name__)
    for m in pkgutil.walk_packages(pkg.__path__, pkg.__name__ + "."):
        if not m.name.endswith("__main__"):
            print(m.name)
PY
)
.venv/bin/python -m pdoc --docformat numpy --output-directory "$out" "$@" "${modules[@]}"
echo "API reference: $out/index.html"
