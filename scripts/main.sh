#!/usr/bin/env bash
# Set everything up (idempotent), then run the main job: the Figure 9 reproduction (quick
# settings, ~30 s on 2 cores): map vs FMU window edges -> results/fig9/report.md.
# Extra arguments go to `reproduce` (e.g. `--workers 4`); for the
# publication-quality run use: .venv/bin/python -m harness reproduce fig9 --out results/fig9
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
exec .venv/bin/python -m harness reproduce fig9 --quick --out results/fig9 "$@"
