#!/usr/bin/env bash
# The FMUs' binaries for every target, each with CVODE built from Debian's SUNDIALS source:
#   build/cross/<target>/cvode  CVODE (scripts/build_cvode.sh, cmake/toolchain-<target>.cmake)
#   build/cross/<target>/fmu    fmu/binaries/<FMI 2 folder>, fmu3/binaries/<FMI 3 folder>
# for the cross targets x86_64-windows and aarch64-linux; the native x86_64-linux binaries and
# the archives are built by scripts/setup.sh in build/fmu, which packages these in. Also
# initialises a wine prefix once, so that no test pays wine's first start (outside the source
# tree: its z: drive links to /, and setuptools follows links when pip re-installs the project,
# walking the whole file system), and builds the platform tests' C host for each target. Every step is skipped when its output is up to date.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
for target in x86_64-linux x86_64-windows aarch64-linux; do
    bash scripts/build_cvode.sh "$target"
done
for target in x86_64-windows aarch64-linux; do
    bld=build/cross/$target/fmu
    if [[ ! -f $bld/CMakeCache.txt ]]; then
        cmake -S fmu_src -B "$bld" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/toolchain-$target.cmake" \
            -DCMAKE_BUILD_TYPE=Release -DSUNDIALS_ROOT="$root/build/cross/$target/cvode" \
            -DIMPACT_BINARIES_ONLY=ON >/dev/null
    fi
    cmake --build "$bld" -j 2 >/dev/null
done
# The platform tests' FMI importer (tests/host), one per target.
for target in x86_64-linux x86_64-windows aarch64-linux; do
    bld=build/cross/$target/host
    if [[ ! -f $bld/CMakeCache.txt ]]; then
        cmake -S tests/host -B "$bld" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/toolchain-$target.cmake" \
            -DCMAKE_BUILD_TYPE=Release >/dev/null
    fi
    cmake --build "$bld" >/dev/null
done
export WINEPREFIX="${IMPACT_WINEPREFIX:-${XDG_CACHE_HOME:-$HOME/.cache}/impact-grazing/wineprefix}" WINEDEBUG=-all
mkdir -p "$(dirname "$WINEPREFIX")"
if [[ ! -f $WINEPREFIX/system.reg ]]; then
    /usr/lib/wine/wine64 wineboot --init >/dev/null 2>&1 || true
    /usr/lib/wine/wineserver64 -w 2>/dev/null || true
fi
