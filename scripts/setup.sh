#!/usr/bin/env bash
# One-shot, idempotent set-up on a fresh Debian machine:
#   1. Debian packages (SUNDIALS for the FMU, a C toolchain, CMake),
#   2. a virtual environment .venv with the project installed (editable),
#   3. the FMUs in build/fmu/: binaries for x86_64-linux, x86_64-windows and aarch64-linux, each
#      with CVODE built from Debian's SUNDIALS source, and the sources (docs/platforms.md).
#      IMPACT_NATIVE_ONLY=1: the Linux binary only, linked with libsundials-dev, no sources (fast).
# Each step is skipped when nothing it depends on changed, so a second run takes seconds.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

log() { printf '[setup] %s\n' "$*" >&2; }

# --- 1. Debian packages -------------------------------------------------------------------
# libtbb12: the ecos co-simulation master (ecospy, a test dependency) links against it.
# libminizip-dev libxml2-dev zlib1g-dev: fmusim, the independent importer built in step 4.
apt_pkgs=(libsundials-dev build-essential cmake zip valgrind libtbb12 libminizip-dev libxml2-dev zlib1g-dev)
native_only=${IMPACT_NATIVE_ONLY:-0}
# The cross compilers, wine and qemu-user to run what they build, dpkg-dev for `apt-get source`.
[[ $native_only == 1 ]] || apt_pkgs+=(gcc-mingw-w64-x86-64-win32 gcc-aarch64-linux-gnu
                                      libc6-dev-arm64-cross wine64 qemu-user dpkg-dev)
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
if [[ $native_only == 1 ]]; then
    fmu_args=(-DSUNDIALS_ROOT= -DSUNDIALS_SOURCE_DIR= -DIMPACT_CROSS_DIRS=)
else
    bash scripts/cross_build.sh
    fmu_args=(-DSUNDIALS_ROOT="$root/build/cross/x86_64-linux/cvode"
              -DSUNDIALS_SOURCE_DIR="$(bash scripts/sundials_source.sh)"
              "-DIMPACT_CROSS_DIRS=$root/build/cross/x86_64-windows/fmu;$root/build/cross/aarch64-linux/fmu")
fi
cmake -S fmu_src -B build/fmu -DCMAKE_BUILD_TYPE=Release "${fmu_args[@]}" >/dev/null
cmake --build build/fmu -j 2 >/dev/null
log "FMU ready: build/fmu/ImpactOscillator.fmu"

# The pythonfmu twin (same model in Python, CVODE through scikit-sundae, behind a C front that
# keeps the FMI state machine with the C FMU's state table, fmu_src/fmu_states.[ch]); rebuilt only
# when its sources are newer than the FMU.
twin_src=fmu_src/pytwin
twin_fmu=build/fmu/ImpactOscillatorPy.fmu
if [[ -f $twin_src/build.py ]]; then
    if [[ ! -f $twin_fmu ]] || [[ -n $(find "$twin_src" fmu_src/fmu_states.c fmu_src/fmu_states.h -newer "$twin_fmu" \( -name '*.py' -o -name '*.c' -o -name '*.h' \) -print -quit) ]]; then
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

# --- 4. Independent importers -------------------------------------------------------------
# fmusim (Reference FMUs v0.0.39) is not packaged: its source lives outside the repository, in
# $IMPACT_SHARED/tools (default ../shared/tools), and is built here into build/tools/fmusim,
# again only when the source is newer than the binary. Without the source the fmusim tests skip
# naming the missing path; with the source and a failed build they fail (tests/importers/test_fmusim.py).
fmusim_src="${IMPACT_SHARED:-$root/../shared}/tools/fmusim-v0.0.39"
fmusim_bin=build/tools/fmusim
if [[ -f $fmusim_src/build.sh ]]; then
    if [[ ! -x $fmusim_bin ]] || [[ -n $(find "$fmusim_src" -newer "$fmusim_bin" -type f -print -quit) ]]; then
        mkdir -p build/tools
        rm -f "$fmusim_bin"  # never test a stale binary after a failed rebuild
        if bash "$fmusim_src/build.sh" "$root/build/tools" >build/tools/fmusim-build.log 2>&1; then
            log "fmusim ready: $fmusim_bin"
        else
            log "fmusim build FAILED (build/tools/fmusim-build.log); its tests will fail"
        fi
    fi
else
    log "fmusim source not found at $fmusim_src: the fmusim tests will be skipped"
fi
