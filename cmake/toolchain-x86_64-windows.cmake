# Toolchain for the x86_64-windows binaries (FMI 2.0 folder win64): Debian's MinGW-w64 cross
# compiler (package gcc-mingw-w64-x86-64-win32, the win32 thread model, so that no
# libwinpthread-1.dll is needed). libgcc is linked statically: the DLL imports only Windows'
# own KERNEL32.dll and msvcrt.dll. Programs built with it run under wine (CMAKE_CROSSCOMPILING_EMULATOR).
set(CMAKE_SYSTEM_NAME Windows)
set(CMAKE_SYSTEM_PROCESSOR AMD64)
set(CMAKE_C_COMPILER x86_64-w64-mingw32-gcc-win32)
set(CMAKE_RC_COMPILER x86_64-w64-mingw32-windres)
set(CMAKE_FIND_ROOT_PATH /usr/x86_64-w64-mingw32)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_SHARED_LINKER_FLAGS_INIT "-static-libgcc -s")  # -s: no symbol table in the DLL
set(CMAKE_EXE_LINKER_FLAGS_INIT "-static-libgcc")
set(CMAKE_CROSSCOMPILING_EMULATOR /usr/lib/wine/wine64)
set(IMPACT_FMI2_PLATFORM win64)
set(IMPACT_FMI3_PLATFORM x86_64-windows)
