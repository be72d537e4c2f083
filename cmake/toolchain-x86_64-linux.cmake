# Toolchain for the x86_64-linux binaries (FMI 2.0 folder linux64): the build machine's own gcc.
# Named like the cross files so that every target is built the same way (scripts/cross_build.sh).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR x86_64)
set(CMAKE_C_COMPILER gcc)
set(IMPACT_FMI2_PLATFORM linux64)
set(IMPACT_FMI3_PLATFORM x86_64-linux)
