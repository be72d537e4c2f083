#!/usr/bin/env bash
# One-shot, idempotent set-up on a fresh Debian machine:
#   1. Debian packages (SUNDIALS for the FMU, a C toolchain, CMake),
#   2. a virtual environment .venv with the project installed (editable),
#   3. the FMUs in build/fmu/.
# Each step is skipped when nothing it depends on changed, so a second run takes seconds.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

log() { printf '[setup] %s\n' "$*" >&2; }

# --- 1. Debian packages -------------------------------------------------------------------
# libtbb12: the ecos co-simulation master (ecospy, a test dependency) links against it.
apt_pkgs=(libsundials-dev build-essential cmake zip valgrind libtbb12)
missing=()
for p in "${apt_pkgs[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# cmake may come from pip instead of apt; accept any cmake >= 3.16 on PATH.
if [[ " ${missing[*]} " == *" cmake "* ]] && command -v cmake >/dev/null; then
    missing=("${missing[@]/cmake}")
fi
missing=($(printf '%s\n' "${missing[@]}" | sed '/^$/d'))
if ((${#missing[@]})); then
    log "installing Debian packages: ${missing[*]}"
    sudo_cmd=()
    [[ $(id -u) -eq 0 ]] || sudo_cmd=(sudo)
    export DEBIAN_FRONTEND=noninteractive
    "${sudo_cmd[@]}" apt-get update -qq
    "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# --- 2. Python environment ----------------------------------------------------------------
py=${PYTHON:-python3}
if [[ ! -x .venv/bin/python ]]; then
    log "creating .venv"
    "$py" -m venv .venv
fi
stamp=.venv/.installed-$(sha256sum pyproject.toml | cut -c1-16)
if [[ ! -f $stamp ]]; then
    log "installing the project and its dependencies into .venv"
    .venv/bin/python -m pip install -q --upgrade pip
    .venv/bin/python -m pip install -q -e ".[dev]"
    rm -f .venv/.installed-*
    touch "$stamp"
fi

# --- 3. FMUs ------------------------------------------------------------------------------
# CMake rebuilds only what changed.
if [[ ! -f build/fmu/CMakeCache.txt ]]; then
    cmake -S fmu_src -B build/fmu -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build build/fmu -j 2 >/dev/null
log "FMU ready: build/fmu/ImpactOscillator.fmu"

# The pythonfmu twin (same model in Python, CVODE through scikit-sundae, behind a C front that
# keeps the FMI state machine); rebuilt only when its sources are newer than the FMU.
twin_src=fmu_src/pytwin
twin_fmu=build/fmu/ImpactOscillatorPy.fmu
if [[ -f $twin_src/build.py ]]; then
    if [[ ! -f $twin_fmu ]] || [[ -n $(find "$twin_src" -newer "$twin_fmu" \( -name '*.py' -o -name '*.c' \) -print -quit) ]]; then
        .venv/bin/python "$twin_src/build.py" --out "$twin_fmu" >/dev/null
        log "twin FMU ready: $twin_fmu"
    fi
fi

# The AFM example's PI controller FMU (examples/afm): plain C, build/afm/AmplitudeController.fmu.
if [[ -f examples/afm/controller/CMakeLists.txt ]]; then
    if [[ ! -f build/afm/CMakeCache.txt ]]; then
        cmake -S examples/afm/controller -B build/afm -DCMAKE_BUILD_TYPE=Release >/dev/null
    fi
    cmake --build build/afm >/dev/null
    log "controller FMU ready: build/afm/AmplitudeController.fmu"
fi
