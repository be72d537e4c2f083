#!/usr/bin/env bash
# Builds CVODE (static, position independent) from Debian's SUNDIALS source for one target:
#   bash scripts/build_cvode.sh TARGET     TARGET in x86_64-linux, x86_64-windows, aarch64-linux
# with cmake/toolchain-TARGET.cmake, into build/cross/TARGET/cvode (include/ and lib/). Only the
# modules the FMU links are built: CVODE, the serial N_Vector, the dense matrix and linear solver
# and the Newton nonlinear solver (CVODE's default). Skipped when the installed libraries exist.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
target=$1
toolchain="$root/cmake/toolchain-$target.cmake"
[[ -f $toolchain ]] || { echo "no toolchain file $toolchain" >&2; exit 2; }
prefix="$root/build/cross/$target/cvode"
if [[ -f $prefix/lib/libsundials_cvode.a && -f $prefix/include/sundials/sundials_config.h ]]; then
    exit 0
fi
src=$(bash "$root/scripts/sundials_source.sh")
bld="$root/build/cross/$target/cvode-build"
cmake -S "$src" -B "$bld" -DCMAKE_TOOLCHAIN_FILE="$toolchain" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_INSTALL_PREFIX="$prefix" -DCMAKE_INSTALL_LIBDIR=lib \
    -DBUILD_SHARED_LIBS=OFF -DBUILD_STATIC_LIBS=ON -DCMAKE_POSITION_INDEPENDENT_CODE=ON \
    -DBUILD_ARKODE=OFF -DBUILD_CVODES=OFF -DBUILD_IDA=OFF -DBUILD_IDAS=OFF -DBUILD_KINSOL=OFF \
    -DBUILD_CVODE=ON -DEXAMPLES_ENABLE_C=OFF -DEXAMPLES_ENABLE_CXX=OFF -DEXAMPLES_INSTALL=OFF \
    -DBUILD_TESTING=OFF -DSUNDIALS_TEST_DEVTESTS=OFF -DBUILD_FORTRAN_MODULE_INTERFACE=OFF \
    -DSUNDIALS_INDEX_SIZE=64 -DSUNDIALS_PRECISION=double >>"$root/build/cross/$target/cvode-build.log" 2>&1
cmake --build "$bld" -j 2 >>"$root/build/cross/$target/cvode-build.log" 2>&1
cmake --install "$bld" >>"$root/build/cross/$target/cvode-build.log" 2>&1
