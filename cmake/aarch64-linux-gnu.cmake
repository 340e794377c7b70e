# Cross-building for ARM64 (Linux, aarch64) with Debian's cross compiler (g++-aarch64-linux-gnu) against
# an ARM64 system root holding the dependencies' ARM64 packages (scripts/arm64-sysroot). Tests then run
# under qemu-user: ctest and catch_discover_tests call them through the emulator.
#   cmake -DCMAKE_TOOLCHAIN_FILE=cmake/aarch64-linux-gnu.cmake -DBRDFZ_SYSROOT=DIR ...
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

# The toolchain file is read again by try_compile projects: the system root travels in the environment.
if(BRDFZ_SYSROOT)
  set(ENV{BRDFZ_SYSROOT} "${BRDFZ_SYSROOT}")
endif()
set(BRDFZ_SYSROOT "$ENV{BRDFZ_SYSROOT}")
if(NOT IS_DIRECTORY "${BRDFZ_SYSROOT}/usr/lib/aarch64-linux-gnu")
  message(FATAL_ERROR "BRDFZ_SYSROOT='${BRDFZ_SYSROOT}' is no ARM64 system root (make one with scripts/arm64-sysroot)")
endif()
set(CMAKE_SYSROOT "${BRDFZ_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH "${BRDFZ_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# pkg-config (HDF5) reads the system root's .pc files and prefixes their paths with it.
set(ENV{PKG_CONFIG_LIBDIR} "${BRDFZ_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${BRDFZ_SYSROOT}/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${BRDFZ_SYSROOT}")
# The ARM64 programs run on x86-64 under qemu-user, with the system root's loader and libraries.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64 -L "${BRDFZ_SYSROOT}")
