# Toolchain for the aarch64-linux binaries: Debian's gcc-aarch64-linux-gnu with its sysroot
# /usr/aarch64-linux-gnu (libc6-dev-arm64-cross). Programs built with it run under qemu-user.
# FMI 2.0.4 names only x86 platforms (win64, linux64, ...) and asks for FMI 3.0's platform tuple
# for any other, so this target uses the folder aarch64-linux in both FMUs.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64;-L;/usr/aarch64-linux-gnu)
set(IMPACT_FMI2_PLATFORM aarch64-linux)
set(IMPACT_FMI3_PLATFORM aarch64-linux)
