# Cross build for the dome controller board (arm64, Raspberry Pi 4/5 class) with
# Debian's cross toolchain (crossbuild-essential-arm64) and multiarch arm64 -dev
# packages; scripts/install-deps.sh arm64 installs both. Used with
# -DLIGHTSTAGE_CONTROLLER_ONLY=ON (scripts/build.sh arm64): common/, hw/,
# firmware/ and their tests.
#
# LIGHTSTAGE_CROSS_ROOT: a folder holding arm64 -dev packages that cannot be
# installed beside their amd64 twins (yaml-cpp's is not multiarch), unpacked
# with dpkg -x.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

# Keep the variable in try_compile projects, which re-read this file.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES LIGHTSTAGE_CROSS_ROOT)
if(LIGHTSTAGE_CROSS_ROOT)
  list(APPEND CMAKE_PREFIX_PATH ${LIGHTSTAGE_CROSS_ROOT}/usr)
endif()

# No sysroot: CMAKE_LIBRARY_ARCHITECTURE makes find_library and find_package look
# in /usr/lib/aarch64-linux-gnu; programs (protoc) are the build machine's.
# pkg-config reads the arm64 .pc files (Debian ships no cross wrapper in 12).
set(ENV{PKG_CONFIG_LIBDIR} /usr/lib/aarch64-linux-gnu/pkgconfig:/usr/share/pkgconfig)
if(LIGHTSTAGE_CROSS_ROOT)
  set(ENV{PKG_CONFIG_LIBDIR} ${LIGHTSTAGE_CROSS_ROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:$ENV{PKG_CONFIG_LIBDIR})
endif()

# Tests (ctest and gtest_discover_tests) run the arm64 binaries through qemu's
# user-mode emulator; the multiarch arm64 libraries are where its loader looks.
find_program(LIGHTSTAGE_QEMU_AARCH64 NAMES qemu-aarch64-static qemu-aarch64)
if(LIGHTSTAGE_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${LIGHTSTAGE_QEMU_AARCH64})
endif()
